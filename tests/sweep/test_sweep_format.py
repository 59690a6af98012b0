"""HDF5 sweep format: bit-exact round trip, deterministic bytes, atomic writes, refusals."""

from __future__ import annotations

import hashlib
import re
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from sweep_helpers import make_sweep

from rotorcheck.sweep import (
    Sweep,
    SweepFormatError,
    compare_sweeps,
    read_sweep,
    sweep_sha256,
    write_sweep,
)
from rotorcheck.sweep.format import PHASOR_CONVENTION

# --------------------------------------------------------------------------------------------
# round trip
# --------------------------------------------------------------------------------------------


def test_write_read_bit_for_bit(tmp_path: Path) -> None:
    s = make_sweep(periods=True)
    p = tmp_path / "a.h5"
    write_sweep(s, p)
    back = read_sweep(p)
    assert compare_sweeps(s, back) == []
    # independent check with raw h5py: the datasets hold exactly the arrays written
    with h5py.File(p, "r") as h5:
        assert h5.attrs["schema"] == "rotorcheck.sweep"
        assert int(h5.attrs["schema_version"]) == 1
        assert h5.attrs["phasor_convention"] == PHASOR_CONVENTION
        g = h5["runs/healthy_1000rpm"]
        assert g["frf"].dtype == np.complex128
        assert g["n_periods"].dtype == np.int32
        for name in ("frequency", "input_phasor", "output_phasor", "output_var", "frf"):
            a = np.asarray(getattr(s.runs["healthy_1000rpm"], name))
            assert a.tobytes() == g[name][()].tobytes(), name
        assert [x.decode() for x in h5["channels/name"][()]] == ["F8x", "d6x", "d6y"]
        assert list(h5["runs"]) == ["healthy_1000rpm", "healthy_0rpm"]  # creation order kept


def test_compare_detects_one_ulp(sweep: Sweep) -> None:
    other = make_sweep()
    assert compare_sweeps(sweep, other) == []
    r = other.runs["healthy_0rpm"]
    r.output_phasor = r.output_phasor.copy()
    r.output_phasor[7, 1] = np.nextafter(r.output_phasor[7, 1].real, np.inf) + 1j * r.output_phasor[7, 1].imag
    d = compare_sweeps(sweep, other)
    assert len(d) == 1 and "/runs/healthy_0rpm/output_phasor: 1 of" in d[0] and "(7, 1)" in d[0]
    other.created_utc = "2030-01-01T00:00:00Z"
    assert any("created_utc" in x for x in compare_sweeps(sweep, other))
    assert not any("created_utc" in x for x in compare_sweeps(sweep, other, ignore=["created_utc"]))


def test_two_writes_byte_identical_and_sha256(tmp_path: Path, sweep: Sweep) -> None:
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    write_sweep(sweep, a)
    time.sleep(1.1)  # HDF5 object timestamps have 1 s resolution: make them differ if stored
    write_sweep(make_sweep(), b)
    assert a.read_bytes() == b.read_bytes()
    assert sweep_sha256(a) == hashlib.sha256(a.read_bytes()).hexdigest()


def test_refuses_overwrite_unless_force(tmp_path: Path, sweep: Sweep) -> None:
    p = tmp_path / "s.h5"
    write_sweep(sweep, p)
    before = p.read_bytes()
    changed = make_sweep(seed=2)
    with pytest.raises(FileExistsError, match=re.escape(str(p))):
        write_sweep(changed, p)
    assert p.read_bytes() == before
    write_sweep(changed, p, force=True)
    assert compare_sweeps(read_sweep(p), changed) == []
    assert [x.name for x in tmp_path.iterdir()] == ["s.h5"]  # no temp files left


def test_writer_refuses_invalid_sweep(tmp_path: Path, sweep: Sweep) -> None:
    sweep.runs["healthy_0rpm"].frequency = sweep.runs["healthy_0rpm"].frequency[::-1].copy()
    p = tmp_path / "bad.h5"
    with pytest.raises(SweepFormatError, match="/runs/healthy_0rpm/frequency"):
        write_sweep(sweep, p)
    assert not p.exists() and list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------------------------
# malformed files: one test each; the message names the file, the path inside, the reason
# --------------------------------------------------------------------------------------------

RUN = "/runs/healthy_1000rpm"


def _refused(path: Path, inside: str, reason: str) -> SweepFormatError:
    with pytest.raises(SweepFormatError) as ei:
        read_sweep(path)
    msg = str(ei.value)
    assert msg.startswith(f"{path}: {inside}: "), msg
    assert re.search(reason, msg), msg
    assert ei.value.file == str(path) and ei.value.path_inside == inside
    return ei.value


def test_missing_dataset(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        del h5[f"{RUN}/output_var"]
    _refused(sweep_file, f"{RUN}/output_var", "missing dataset")


def test_missing_attribute(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        del h5[RUN].attrs["speed_rpm"]
    _refused(sweep_file, f"{RUN}@speed_rpm", "missing attribute")


def test_wrong_shape(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        a = h5[f"{RUN}/output_phasor"][()]
        del h5[f"{RUN}/output_phasor"]
        h5[f"{RUN}/output_phasor"] = a[:, :1]
    _refused(sweep_file, f"{RUN}/output_phasor", r"wrong shape \(262, 1\), expected \(262, 2\)")


def test_wrong_dtype(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        a = h5[f"{RUN}/frequency"][()]
        del h5[f"{RUN}/frequency"]
        h5[f"{RUN}/frequency"] = a.astype(np.float32)
    _refused(sweep_file, f"{RUN}/frequency", "wrong dtype float32, expected float64")


def test_nan_value(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5[f"{RUN}/output_phasor"][17, 1] = np.nan + 0j
    _refused(sweep_file, f"{RUN}/output_phasor", r"non-finite value at index \(17, 1\)")


def test_non_increasing_frequency(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        f = h5[f"{RUN}/frequency"][()]
        f[40], f[41] = f[41], f[40]
        h5[f"{RUN}/frequency"][...] = f
    _refused(sweep_file, f"{RUN}/frequency", "not strictly increasing at index 41")


def test_zero_input_phasor(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5[f"{RUN}/input_phasor"][3, 0] = 0j
    _refused(sweep_file, f"{RUN}/input_phasor", r"zero input phasor at index \(3, 0\)")


def test_negative_variance(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5[f"{RUN}/output_var"][5, 0] = -1e-20
    _refused(sweep_file, f"{RUN}/output_var", "negative variance")


def test_frf_inconsistent(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5[f"{RUN}/frf"][9, 1, 0] *= 1 + 1e-6
    _refused(sweep_file, f"{RUN}/frf", r"inconsistent with output_phasor/input_phasor at index \(9, 1, 0\)")


def test_unknown_schema_version(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5.attrs["schema_version"] = np.int32(4)
    _refused(sweep_file, "/@schema_version", r"unknown schema_version 4 \(this reader knows 1, 2, 3\)")


def test_version_1_layout_under_schema_version_2(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5.attrs["schema_version"] = np.int32(2)
    _refused(sweep_file, f"{RUN}/input_phasor", r"wrong shape \(262, 1\), expected \(f=262, n_exc >= 1, n_in=1\)")


def test_wrong_schema(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5.attrs["schema"] = "something.else"
    _refused(sweep_file, "/@schema", "expected 'rotorcheck.sweep'")


def test_channel_table_inconsistent(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5["channels/unit"][1] = "N"  # a displacement channel in newtons
    _refused(sweep_file, "/channels/unit", "does not match quantity 'displacement'")


def test_channel_count_inconsistent_with_data(sweep_file: Path) -> None:
    with h5py.File(sweep_file, "r+") as h5:
        h5["channels/role"][2] = "input"
        h5["channels/quantity"][2] = "force"
        h5["channels/unit"][2] = "N"
    _refused(sweep_file, f"{RUN}/input_phasor", r"expected \(262, 2\).*n_in=2, n_out=1")


def test_truncated_file(sweep_file: Path) -> None:
    data = sweep_file.read_bytes()
    sweep_file.write_bytes(data[: len(data) // 2])
    _refused(sweep_file, "/", "truncated")


def test_not_hdf5(tmp_path: Path) -> None:
    p = tmp_path / "notes.h5"
    p.write_text("frequency,frf\n1,2\n")
    _refused(p, "/", "not an HDF5 file")


def test_period_phasor_padding_and_mean_checked(tmp_path: Path) -> None:
    s = make_sweep(periods=True)
    p = tmp_path / "p.h5"
    write_sweep(s, p)
    assert read_sweep(p).runs[RUN.split("/")[-1]].period_phasor.shape == (262, 64, 3)
    with h5py.File(p, "r+") as h5:
        h5[f"{RUN}/period_phasor"][4, 10, 2] += 1e-7
    _refused(p, f"{RUN}/period_phasor", r"differs from output_phasor")


def test_reads_compound_channel_table_and_fixed_length_strings(tmp_path: Path, sweep: Sweep) -> None:
    """The other layout the contract allows (as MATLAB-style writers produce it)."""
    p = tmp_path / "c.h5"
    write_sweep(sweep, p)
    with h5py.File(p, "r+") as h5:
        del h5["channels"]
        dt = np.dtype(
            [
                ("name", "S8"),
                ("role", "S8"),
                ("node", "<i4"),
                ("direction", "S1"),
                ("quantity", "S16"),
                ("unit", "S2"),
            ]
        )
        rows = [(c.name, c.role, c.node, c.direction, c.quantity, c.unit) for c in sweep.channels]
        h5["channels"] = np.array(rows, dtype=dt)
        h5.attrs["rig_id"] = np.bytes_(b"crack_rig")
    back = read_sweep(p)
    assert compare_sweeps(sweep, back) == []
