"""Issue 32: outputs that cannot be written (no permission, a full disk, a folder or a file in the way) end
as exit 2 naming the path, never "internal error", and leave no temporary file behind."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from rotorcheck import fileio
from rotorcheck.cli import main
from rotorcheck.errors import InputError
from rotorcheck.resources import samples_dir

HEALTHY = samples_dir() / "crack_rig" / "healthy_0rpm.h5"
ROSS = Path(__file__).resolve().parent / "data" / "ross" / "rotor_example.toml"
SIM = ["--speed", "0", "--points", "5", "--periods", "4", "--f-min", "40", "--f-max", "60"]

COMMANDS = {  # name: argv writing into the folder OUT
    "schema": ["schema", "--out", "OUT/schema.json"],
    "convert": ["convert", str(HEALTHY), "OUT/c.h5"],
    "import-ross": ["import-ross", str(ROSS), "OUT/rig.yaml"],
    "simulate": ["simulate", "OUT/s.h5", *SIM],
    "validate": ["validate", str(HEALTHY), "--out", "OUT", "--no-plots"],
}


def _argv(name: str, out: Path) -> list[str]:
    return [a.replace("OUT", str(out)) for a in COMMANDS[name]]


@pytest.fixture
def read_only_temp(monkeypatch: pytest.MonkeyPatch) -> None:
    """The temp file of every output refused as in a read-only folder (tests run as root, so no chmod)."""
    real_open = os.open

    def refuse(path: str | os.PathLike[str], flags: int, *args: int) -> int:
        if os.fspath(path).endswith(".tmp") and flags & os.O_CREAT:
            raise PermissionError(errno.EACCES, "Permission denied", os.fspath(path))
        return real_open(path, flags, *args)

    monkeypatch.setattr(os, "open", refuse)


@pytest.mark.parametrize("name", list(COMMANDS))
def test_read_only_output_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str], read_only_temp: None,
                                 name: str) -> None:
    out = tmp_path / "ro"
    out.mkdir()
    assert main(_argv(name, out)) == 2
    msg = capsys.readouterr().err
    assert "internal error" not in msg
    assert f"error: {out}/" in msg and "output: cannot write: no permission to write here" in msg
    assert list(out.iterdir()) == []


def test_full_disk_in_simulate_leaves_no_temp_file(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    import rotorcheck.sweep.hdf5io as hdf5io

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(hdf5io, "_put", full)  # the first dataset written into the temp file
    out = tmp_path / "o"
    out.mkdir()
    assert main(["simulate", str(out / "s.h5"), *SIM]) == 2
    msg = capsys.readouterr().err
    assert f"error: {out / 's.h5'}: output: cannot write: no space left on the device" in msg
    assert list(out.iterdir()) == []  # no temp file, no output


def test_full_disk_reported_inside_an_hdf5_message(tmp_path: Path) -> None:
    exc = OSError("Can't write data (file write failed: time = x, errno = 28, error message = 'No space')")
    assert "no space left on the device" in str(fileio.output_error(tmp_path / "b.h5", exc))


def test_full_disk_in_a_text_write_leaves_no_temp_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def full(self: Path, *a: object, **k: object) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(InputError, match="no space left on the device") as info:
        fileio.atomic_write_text(tmp_path / "a.json", "{}")
    assert info.value.file == str(tmp_path / "a.json")
    assert list(tmp_path.iterdir()) == []


def test_an_output_that_is_a_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "c.h5").mkdir()
    assert main(["convert", str(HEALTHY), str(tmp_path / "c.h5"), "--force"]) == 2
    assert f"error: {tmp_path / 'c.h5'}: output: is a folder, not a file" in capsys.readouterr().err
    (tmp_path / "s.json").mkdir()
    assert main(["schema", "--out", str(tmp_path / "s.json"), "--force"]) == 2
    assert f"error: {tmp_path / 's.json'}: output: is a folder, not a file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.h5", "s.json"]
    assert not any((tmp_path / "c.h5").iterdir())


@pytest.mark.parametrize("name", ["validate", "simulate", "schema"])
def test_a_file_where_the_output_folder_should_be(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                  name: str) -> None:
    blocker = tmp_path / "out"
    blocker.write_text("a file")
    assert main(_argv(name, blocker)) == 2
    assert f"error: {blocker}: output folder: is a file, not a folder" in capsys.readouterr().err
    assert blocker.read_text() == "a file" and [p.name for p in tmp_path.iterdir()] == ["out"]


def test_atomic_path_mkdir_through_a_file(tmp_path: Path) -> None:
    (tmp_path / "f").write_text("x")
    with pytest.raises(InputError, match="is a file, not a folder"):
        fileio.atomic_write_text(tmp_path / "f" / "sub" / "a.txt", "y")
