"""Sweep writers go through rotorcheck.fileio: outputs get open()'s mode, the umask is never touched."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

from rotorcheck.sweep import Sweep, write_sweep
from rotorcheck.sweep.tidy_csv import export_tidy_csv
from rotorcheck.sweep.uff import export_uff58
from tests.umask_helpers import proc_umask, refuse_umask

WRITERS: dict[str, Callable[[Sweep, Path], None]] = {
    "h5": lambda s, p: write_sweep(s, p),
    "uff": lambda s, p: export_uff58(s, p),
    "csv": lambda s, p: export_tidy_csv(s, p),
}


@pytest.mark.parametrize("kind", sorted(WRITERS))
def test_output_mode_is_open_mode_and_umask_unchanged(
    tmp_path: Path, sweep: Sweep, kind: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(os, "umask", refuse_umask)  # os.umask can only read by setting
    before = proc_umask()
    out = tmp_path / f"out.{kind}"
    WRITERS[kind](sweep, out)
    assert proc_umask() == before
    assert out.stat().st_mode & 0o777 == 0o666 & ~before
    plain = tmp_path / "plain"
    plain.write_text("x")  # a default ACL on the folder would show here as well
    assert out.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777
    assert sorted(x.name for x in tmp_path.iterdir()) == sorted([out.name, "plain"])  # no temp left


@pytest.mark.parametrize("kind", sorted(WRITERS))
def test_refusal_leaves_file_and_folder_untouched(tmp_path: Path, sweep: Sweep, kind: str) -> None:
    out = tmp_path / f"out.{kind}"
    out.write_bytes(b"old")
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        WRITERS[kind](sweep, out)
    assert out.read_bytes() == b"old" and [x.name for x in tmp_path.iterdir()] == [out.name]
