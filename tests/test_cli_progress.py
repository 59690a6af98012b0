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
