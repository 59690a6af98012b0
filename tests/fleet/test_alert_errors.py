"""Issue 32: an unreadable (error) sweep neither confirms nor clears an alarm; it gets a watch note."""

from __future__ import annotations

from typing import Any

from rotorcheck.fleet.summary import alerts


def _rows(*verdicts: str) -> list[dict[str, Any]]:
    return [{"time": f"2026-01-0{i + 1}T00:00:00Z", "verdict": v} for i, v in enumerate(verdicts)]


def _rules(rows: list[dict[str, Any]]) -> dict[str, tuple[str, str]]:
    return {e["rule"]: (e["level"], e["since"]) for e in alerts({"m1": rows}, {}, confirm=2)}


def test_a_truncated_newer_sweep_keeps_the_alarm() -> None:
    got = _rules(_rows("healthy", "damage", "damage", "error"))
    assert got == {"damage-confirmed": ("alarm", "2026-01-03T00:00:00Z"),
                   "sweep-error": ("watch", "2026-01-04T00:00:00Z")}


def test_errors_between_damages_do_not_break_the_streak() -> None:
    got = _rules(_rows("healthy", "damage", "error", "damage"))
    assert got == {"damage-confirmed": ("alarm", "2026-01-04T00:00:00Z")}


def test_errors_do_not_confirm_an_alarm() -> None:
    got = _rules(_rows("healthy", "damage", "error", "error"))
    assert got == {"damage-unconfirmed": ("watch", "2026-01-02T00:00:00Z"),
                   "sweep-error": ("watch", "2026-01-03T00:00:00Z")}


def test_a_healthy_sweep_still_clears_and_only_errors_watch() -> None:
    assert _rules(_rows("damage", "damage", "healthy")) == {}
    assert _rules(_rows("error")) == {"sweep-error": ("watch", "2026-01-01T00:00:00Z")}
    entry = alerts({"m1": _rows("damage", "damage", "error")}, {}, confirm=2)[0]
    assert entry["level"] == "alarm" and entry["damage_streak"] == 2 and entry["latest_verdict"] == "error"
    assert entry["first_damage_time"] == "2026-01-01T00:00:00Z"


def test_an_unreachable_scheduler_is_refused_naming_it(monkeypatch: Any) -> None:
    from rotorcheck.fleet.runner import SCHEDULER_TIMEOUT_S

    assert SCHEDULER_TIMEOUT_S <= 10  # the default bound, far below the 30 s of retries before
    import socket
    import time

    import pytest

    from rotorcheck.errors import InputError
    from rotorcheck.fleet import runner

    pytest.importorskip("distributed")
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(runner, "SCHEDULER_TIMEOUT_S", 1.0)
    t0 = time.monotonic()
    with pytest.raises(InputError, match=rf"^--scheduler: cannot reach a Dask scheduler at 'tcp://127.0.0.1:{port}' "
                                         r"within 1 s"):
        runner._dask([], 1, f"tcp://127.0.0.1:{port}", lambda text: None)
    assert time.monotonic() - t0 < 8
