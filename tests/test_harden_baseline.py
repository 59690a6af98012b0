"""Issue 32: a baseline whose attributes or datasets have the wrong type is refused naming the file and the
attribute (before the digest check, which would compute on them), never a TypeError/ValueError."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

from rotorcheck.baseline import read_baseline
from rotorcheck.cli import main
from rotorcheck.errors import InputError
from rotorcheck.resources import samples_dir

HEALTHY = samples_dir() / "crack_rig" / "healthy_0rpm.h5"


@pytest.fixture(scope="module")
def baseline(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("base")
    assert main(["validate", str(HEALTHY), "--out", str(out), "--no-plots"]) == 0
    return out / "baseline.h5"


def _set_attr(h5: h5py.File, name: str, value: Any) -> None:
    h5.attrs[name] = value


def _replace(h5: h5py.File, name: str, value: Any) -> None:
    del h5[name]
    if isinstance(value, str) and value == "group":
        h5.create_group(name)
    else:
        h5.create_dataset(name, data=value)


def _vlen_attr(h5: h5py.File, name: str) -> None:
    del h5.attrs[name]
    data = np.empty(1, dtype=object)
    data[0] = np.arange(3, dtype=np.int32)
    h5.attrs.create(name, data=data, dtype=h5py.vlen_dtype(np.int32))


EDITS = [  # (edit, the field named)
    (lambda h: _set_attr(h, "noise_bound_m", "1e-7"), "/@noise_bound_m", "must be a real number, got str"),
    (lambda h: _set_attr(h, "noise_bound_m", np.array([1e-7, 2e-7])), "/@noise_bound_m", "must be a real number"),
    (lambda h: _set_attr(h, "speed_rpm", True), "/@speed_rpm", "must be a real number, got bool"),
    (lambda h: _set_attr(h, "speed_rpm", np.nan), "/@speed_rpm", "must be finite"),
    (lambda h: _set_attr(h, "noise_confidence", b"0.99"), "/@noise_confidence", "must be a real number"),
    (lambda h: _set_attr(h, "rig_id", 5), "/@rig_id", "must be text, got int64"),
    (lambda h: _set_attr(h, "stage", "done"), "/@stage", "must be 'noise' or 'validated'"),
    (lambda h: _set_attr(h, "n_healthy", 1.5), "/@n_healthy", "must be an integer"),
    (lambda h: _set_attr(h, "n_healthy", 0), "/@n_healthy", "must be >= 1"),
    (lambda h: _set_attr(h, "benign_kappa", "x"), "/@benign_kappa", "must be a real number"),
    (lambda h: _set_attr(h, "x_rig_path", np.arange(3)), "/@x_rig_path", "must be text"),
    (lambda h: _set_attr(h, "sweep_sha256", 7), "/@sweep_sha256", "must be text"),
    (lambda h: _replace(h, "gamma", "group"), "/gamma", "must be a dataset, got Group"),
    (lambda h: _replace(h, "gamma", np.array([b"a", b"b"])), "/gamma", "is not numeric"),
    (lambda h: _replace(h, "frequency_hz", np.ones((2, 2))), "/frequency_hz", "must be 1-D"),
    (lambda h: _replace(h, "healthy_frf", 1.0), "/healthy_frf", "must be an array over the frequencies"),
    (lambda h: _replace(h, "gamma_status", np.arange(3)), "/gamma_status", "is not text"),
    (lambda h: _set_attr(h, "schema", np.arange(2)), "/@schema", "not a rotorcheck baseline"),
    # the fuzzer's SIGSEGV: a variable-length sequence (its corrupt base type crashed libhdf5): refused unread
    (lambda h: _vlen_attr(h, "noise_method"), "/@noise_method", "a Vlen attribute"),
    (lambda h: h.attrs.create("x_note", data=np.zeros(1, dtype=[("a", "<i4"), ("b", "<f8")])), "/@x_note",
     "a Compound attribute"),
]


@pytest.mark.parametrize(("edit", "field", "message"), EDITS, ids=[f"{f}-{m[:12]}" for _, f, m in EDITS])
def test_wrongly_typed_items_are_refused_naming_them(baseline: Path, tmp_path: Path, edit: Any, field: str,
                                                     message: str) -> None:
    p = tmp_path / "baseline.h5"
    shutil.copy(baseline, p)
    with h5py.File(p, "r+") as h5:
        edit(h5)
    with pytest.raises(InputError) as info:
        read_baseline(p)
    assert info.value.file == str(p) and info.value.field == field and message in info.value.message


def test_detect_with_a_string_noise_bound_exits_2_naming_it(baseline: Path, tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    p = tmp_path / "baseline.h5"
    shutil.copy(baseline, p)
    with h5py.File(p, "r+") as h5:
        h5.attrs["noise_bound_m"] = "1e-7"
    out = tmp_path / "out"
    assert main(["detect", str(HEALTHY), "--baseline", str(p), "--out", str(out), "--no-plots"]) == 2
    msg = capsys.readouterr().err
    assert f"error: {p}: /@noise_bound_m: must be a real number, got str '1e-7'" in msg
    assert not out.exists() or not any(out.iterdir())


def test_the_untouched_baseline_reads(baseline: Path) -> None:
    b = read_baseline(baseline)
    assert b.validated and b.noise_bound_m > 0 and b.gamma is not None and b.gamma.shape == b.frequency_hz.shape
