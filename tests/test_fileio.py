"""The one atomic writer (rotorcheck.fileio): modes as open() gives, no umask flips, no clobbering."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from rotorcheck import fileio
from tests.umask_helpers import proc_umask, refuse_umask


def test_output_mode_is_open_mode_and_umask_unchanged(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(os, "umask", refuse_umask)  # os.umask can only read by setting
    before = proc_umask()
    out = tmp_path / "out.txt"
    fileio.atomic_write_text(out, "x\n")
    assert proc_umask() == before
    assert out.stat().st_mode & 0o777 == 0o666 & ~before
    plain = tmp_path / "plain"
    plain.write_text("x")  # a default ACL on the folder would show here as well
    assert out.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777


def test_refuses_before_work_and_leaves_target(tmp_path: Path) -> None:
    p = tmp_path / "a.txt"
    p.write_text("old")
    ran = False
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        with fileio.atomic_path(p, overwrite=False):
            ran = True
    assert not ran and p.read_text() == "old"
    fileio.atomic_write_text(p, "new")  # overwrite=True is the default (callers check first)
    assert p.read_text() == "new" and [x.name for x in tmp_path.iterdir()] == ["a.txt"]


def test_file_appearing_meanwhile_is_not_clobbered(tmp_path: Path) -> None:
    p = tmp_path / "a.txt"
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        with fileio.atomic_path(p, overwrite=False) as tmp:
            tmp.write_text("ours")
            p.write_text("theirs")
    assert p.read_text() == "theirs" and [x.name for x in tmp_path.iterdir()] == ["a.txt"]


def test_failure_leaves_no_trace(tmp_path: Path) -> None:
    p = tmp_path / "sub" / "a.txt"
    with pytest.raises(RuntimeError):
        with fileio.atomic_path(p) as tmp:
            assert tmp.parent == p.parent and tmp.exists()
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert list(p.parent.iterdir()) == []


def test_publish_dir_is_all_or_nothing_and_first_writer_wins(tmp_path: Path) -> None:
    """A folder built beside its final name appears complete by one rename; a second copy finds the first in
    place (False, its own folder removed); replace=True swaps the old folder for the new one."""
    from rotorcheck.fileio import publish_dir, temp_dir_beside

    final = tmp_path / "results" / "abc"
    first = temp_dir_beside(final)
    assert first.parent == final.parent and first.name.startswith(".abc.") and first.name.endswith(".tmp")
    (first / "row.json").write_text("1")
    assert not final.exists()
    assert publish_dir(first, final) is True
    assert (final / "row.json").read_text() == "1" and not first.exists()
    second = temp_dir_beside(final)
    (second / "row.json").write_text("2")
    assert publish_dir(second, final) is False
    assert (final / "row.json").read_text() == "1" and not second.exists()
    third = temp_dir_beside(final)
    (third / "row.json").write_text("3")
    assert publish_dir(third, final, replace=True) is True
    assert (final / "row.json").read_text() == "3"
    assert sorted(p.name for p in final.parent.iterdir()) == ["abc"]  # nothing left beside it
