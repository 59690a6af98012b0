"""Progress on stderr (rich) for the steps that take a second or more: shown on a terminal, quiet otherwise."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from rotorcheck.cli import EXIT_OK, common, main


@pytest.mark.parametrize("terminal", [True, False])
def test_simulate_shows_progress_only_on_a_terminal(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                    terminal: bool) -> None:
    buf = io.StringIO()
    # the one stderr console every command module prints to (rotorcheck.cli.common.err), redirected
    monkeypatch.setattr(common.err, "_file", buf)  # restored to None: sys.stderr as each later test has it
    monkeypatch.setattr(common.err, "_force_terminal", terminal)
    monkeypatch.setattr(common.err, "is_interactive", terminal)
    assert main(["simulate", str(tmp_path / "s.h5"), "--points", "20", "--periods", "4"]) == EXIT_OK
    text = buf.getvalue()
    assert "wrote" in text
    assert ("simulating 20 points" in text) is terminal


def test_the_time_left_counts_from_the_steps_start(monkeypatch: pytest.MonkeyPatch) -> None:
    """Plain progress lines time a step's items from its ``done`` 0 call: a ranking of 4 elements that starts 10 s
    into the command and finishes its first element 2 s later has 3 x 2 s = 6 s left (from the command's start it
    would read 36 s); a step that never says it started is timed from the start (12 s x 3 = 36 s)."""
    import time

    from rotorcheck.progress import ConsoleSteps

    now = [100.0]
    monkeypatch.setattr(time, "monotonic", lambda: now[0])
    lines: list[str] = []

    class Console:
        is_terminal = False

        def print(self, text: str, **_: object) -> None:
            lines.append(text)

    with ConsoleSteps(Console(), "locating", every_s=0.0) as tick:
        now[0] = 110.0
        tick(0, 4, "ranking")
        now[0] = 112.0
        tick(1, 4, "ranking: element 1")
    assert lines == ["[1/4] locating ranking: element 1: elapsed 0:00:12, about 0:00:06 left"]
    lines.clear()
    now[0] = 100.0
    with ConsoleSteps(Console(), "locating", every_s=0.0) as tick:
        now[0] = 112.0
        tick(1, 4, "ranking: element 1")
    assert lines == ["[1/4] locating ranking: element 1: elapsed 0:00:12, about 0:00:36 left"]
