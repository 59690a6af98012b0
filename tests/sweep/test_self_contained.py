"""Sweep files that reach outside themselves (issue 16): external links, soft links (a loop), virtual
datasets and external raw storage each map other data into a sweep; a huge file loads whole. Each is
refused before anything is read: SweepFormatError naming the path, exit 2 from the CLI, no traceback."""

from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from rotorcheck.cli import EXIT_INPUT, main
from rotorcheck.resources import samples_dir
from rotorcheck.sweep import read_sweep
from rotorcheck.sweep.hdf5io import MAX_SWEEP_BYTES, SweepFormatError

SAMPLE = samples_dir() / "crack_rig" / "healthy_0rpm.h5"


def _copy(tmp_path: Path) -> Path:
    p = tmp_path / "s.h5"
    shutil.copy(SAMPLE, p)
    return p


def _secret(tmp_path: Path) -> Path:
    s = tmp_path / "secret.bin"
    s.write_bytes(np.arange(64, dtype=np.float64).tobytes())
    return s


def _external_link(p: Path, tmp: Path) -> str:
    other = tmp / "other.h5"
    with h5py.File(other, "w") as h:
        h["x"] = np.ones(3)
    with h5py.File(p, "a") as h:
        h["leak"] = h5py.ExternalLink(str(other), "/x")
    return "/leak"


def _soft_loop(p: Path, tmp: Path) -> str:
    with h5py.File(p, "a") as h:
        h["a"] = h5py.SoftLink("/b")
        h["b"] = h5py.SoftLink("/a")
    return "/a"


def _virtual(p: Path, tmp: Path) -> str:
    other = tmp / "v.h5"
    with h5py.File(other, "w") as h:
        h["x"] = np.ones(4)
    layout = h5py.VirtualLayout(shape=(4,), dtype="f8")
    layout[:] = h5py.VirtualSource(str(other), "x", shape=(4,))
    with h5py.File(p, "a") as h:
        h.create_virtual_dataset("vds", layout)
    return "/vds"


def _external_storage(p: Path, tmp: Path) -> str:
    secret = _secret(tmp)
    with h5py.File(p, "a") as h:
        h.create_dataset("raw", shape=(64,), dtype="f8", external=[(str(secret), 0, 64 * 8)])
    return "/raw"


def _huge(p: Path, tmp: Path) -> str:
    with h5py.File(p, "a") as h:  # chunked and never written: no disk, but its size counts
        h.create_dataset("big", shape=(MAX_SWEEP_BYTES // 8 + 1,), dtype="f8", chunks=(1024,))
    return "/big"


@pytest.mark.parametrize("make", [_external_link, _soft_loop, _virtual, _external_storage, _huge])
def test_reaching_outside_is_refused_naming_the_path(tmp_path: Path, make, capsys: pytest.CaptureFixture) -> None:  # type: ignore[no-untyped-def]
    p = _copy(tmp_path)
    read_sweep(p)  # the unaltered copy reads
    where = make(p, tmp_path)
    with pytest.raises(SweepFormatError) as exc:
        read_sweep(p)
    assert where in str(exc.value) and str(p) in str(exc.value)
    assert main(["info", str(p)]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert where in err and "Traceback" not in err
