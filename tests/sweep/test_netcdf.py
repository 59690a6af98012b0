"""The sweep files rotorcheck writes open in xarray (engine h5netcdf) as netCDF-4: per run group the coordinates
``frequency`` (Hz) and the channel names (``input``, ``output``, with per-period phasors ``channel``), every
data variable with its units, complex128 as complex, strings as str, no phony dimensions; the whole file as
one DataTree. The labels change no byte of the contract's datasets, and the reader still reads files written
before them (tests/data/legacy). Skipped when xarray or h5netcdf is not installed."""

from __future__ import annotations

import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
from sweep_helpers import make_sweep, v2_sweep

from rotorcheck.sweep import Sweep, compare_sweeps, read_sweep, write_sweep
from rotorcheck.sweep.format import CHANNEL_FIELDS, PATTERN_ATTRS
from tests.netcdf_helpers import LEGACY

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "data_samples"
#: the units each variable must carry (spec: N, m, Hz; variances their squares; period_phasor by channel)
UNITS = {"frequency": "Hz", "input_phasor": "N", "output_phasor": "m", "output_var": "m^2", "input_var": "N^2",
         "n_periods": "1", "frf": "m/N", "frf_var": "m^2/N^2",
         "period_phasor": "N (input channels), m (output channels)"}


def _open(path: Path, group: str | None):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. xarray's warning about phony (unlabelled) dimensions
        return xr.open_dataset(path, engine="h5netcdf", group=group)


def _reader_array(sw: Sweep, run_id: str, name: str, version: int) -> np.ndarray:
    """The array the rotorcheck reader returns for dataset ``name`` of a run (v1: the single pattern)."""
    run = sw.runs[run_id]
    if name in ("frequency", "frf", "frf_var"):
        return np.asarray(getattr(run, name))
    a = np.asarray(getattr(run, PATTERN_ATTRS[name]))
    return a[:, 0] if version == 1 else a


def _check_run_group(path: Path, run_id: str, dims: dict[str, tuple[str, ...]]) -> None:
    """Run ``run_id`` of ``path`` through xarray against the rotorcheck reader and the raw file."""
    sw = read_sweep(path)
    ds = _open(path, f"runs/{run_id}")
    with h5py.File(path, "r") as h5:
        g, version = h5[f"runs/{run_id}"], int(h5.attrs["schema_version"])
        # coordinates: the frequency grid (bit for bit, Hz) and the channel names the reader returns
        assert ds["frequency"].values.tobytes() == sw.runs[run_id].frequency.tobytes()
        assert ds["frequency"].attrs["units"] == "Hz" and ds.indexes["frequency"].name == "frequency"
        assert list(ds["input"].values) == [c.name for c in sw.channels if c.role == "input"]
        assert list(ds["output"].values) == [c.name for c in sw.channels if c.role == "output"]
        has_periods = "period_phasor" in dims
        assert sorted(ds.coords) == sorted(["frequency", "input", "output"] + ["channel"] * has_periods)
        if has_periods:
            assert list(ds["channel"].values) == [c.name for c in sw.channels]
        assert sorted(ds.data_vars) == sorted(dims)
        for name, var in ds.data_vars.items():
            assert var.dims == dims[name], name
            assert var.attrs["units"] == UNITS[name], name
            ref = _reader_array(sw, run_id, name, version)
            assert var.dtype == ref.dtype and var.values.tobytes() == ref.tobytes(), name  # complex128 as complex
        for key, value in g.attrs.items():
            assert ds.attrs[key] == value and not isinstance(ds.attrs[key], bytes), key
        # a label lookup: the FRF of the second output and the first input at the grid's 4th point
        out, inp, f3 = ds["output"].values[-1], ds["input"].values[0], ds["frequency"].values[3]
        o, i = ds.sizes["output"] - 1, 0
        assert ds["frf"].sel(output=out, input=inp, frequency=f3).item() == sw.runs[run_id].frf[3, o, i]
    ds.close()


def _check_channels_and_tree(path: Path) -> None:
    """``/channels`` and the root as the reader sees them; the whole file as one DataTree."""
    sw = read_sweep(path)
    ch = _open(path, "channels")
    for fld in CHANNEL_FIELDS:
        assert list(ch[fld].values) == [getattr(c, fld) for c in sw.channels], fld
        assert ch[fld].dims == ("channel",)
    assert ch["node"].attrs["units"] == "1" and isinstance(ch["role"].values[0], str)
    root = _open(path, None)
    assert list(root["channel"].values) == [c.name for c in sw.channels]
    assert root.attrs["schema"] == "rotorcheck.sweep" and isinstance(root.attrs["rig_id"], str)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tree = xr.open_datatree(path, engine="h5netcdf")
    assert sorted(tree["runs"].children) == sorted(sw.runs)
    assert list(tree["channels"]["channel"].values) == [c.name for c in sw.channels]  # inherited from the root


V1_DIMS = {"input_phasor": ("frequency", "input"), "output_phasor": ("frequency", "output"),
           "output_var": ("frequency", "output"), "n_periods": ("frequency",),
           "frf": ("frequency", "output", "input")}


def test_bundled_samples_open_in_xarray() -> None:
    """A one-run v1 sample with per-period phasors and a one-run v2 sample (x/y: 2 inputs in 2 patterns)."""
    v1 = SAMPLES / "crack_rig" / "healthy_1000rpm.h5"
    sw = read_sweep(v1)
    (rid,) = sw.runs
    p = sw.runs[rid].period_phasor.shape[1]
    _check_run_group(v1, rid, {**V1_DIMS, "period_phasor": ("frequency", f"period_{p}", "channel")})
    _check_channels_and_tree(v1)
    ds = _open(v1, "runs/" + rid)
    assert ds.sizes["frequency"] == 262 and ds["frequency"].values[0] == 30.0 and ds.attrs["speed_rpm"] == 1000.0
    v2 = SAMPLES / "crack_rig_xy" / "healthy_0rpm.h5"
    sw2 = read_sweep(v2)
    (rid2,) = sw2.runs
    pat = ("frequency", "pattern_2")
    _check_run_group(v2, rid2, {
        "input_phasor": (*pat, "input"), "output_phasor": (*pat, "output"), "output_var": (*pat, "output"),
        "input_var": (*pat, "input"), "n_periods": pat, "frf": ("frequency", "output", "input"),
        "frf_var": ("frequency", "output", "input")})
    _check_channels_and_tree(v2)
    ds2 = _open(v2, "runs/" + rid2)
    assert list(ds2["output"].values) == [c.name for c in sw2.outputs] and ds2.sizes["output"] == 4


def test_v1_and_v2_files_open_in_xarray(tmp_path: Path) -> None:
    v1 = tmp_path / "v1.h5"
    write_sweep(make_sweep(periods=True), v1)
    for rid in ("healthy_1000rpm", "healthy_0rpm"):
        _check_run_group(v1, rid, {**V1_DIMS, "period_phasor": ("frequency", "period_64", "channel")})
    _check_channels_and_tree(v1)
    v2 = tmp_path / "v2.h5"
    write_sweep(v2_sweep(), v2)
    _check_run_group(v2, "two_shakers", {
        "input_phasor": ("frequency", "pattern_2", "input"), "output_phasor": ("frequency", "pattern_2", "output"),
        "output_var": ("frequency", "pattern_2", "output"), "n_periods": ("frequency", "pattern_2"),
        "frf": ("frequency", "output", "input"), "frf_var": ("frequency", "output", "input"),
        "period_phasor": ("frequency", "pattern_2", "period_4", "channel")})
    _check_run_group(v2, "analyser", {"frf": ("frequency", "output", "input"),
                                      "frf_var": ("frequency", "output", "input")})
    _check_channels_and_tree(v2)
    ds = _open(v2, "runs/analyser")
    assert ds.sizes == {"frequency": 7, "output": 2, "input": 2} and ds.attrs["noise_source"] == "measured"
    # writing stays deterministic
    again = tmp_path / "again.h5"
    write_sweep(v2_sweep(), again)
    assert again.read_bytes() == v2.read_bytes()
    with h5py.File(v2, "r") as h5:
        assert sorted(h5) == ["channel", "channels", "pattern_2", "period_4", "runs"]
        # beside the contract's datasets only the channel-name coordinates
        assert sorted(h5["runs/analyser"]) == ["frequency", "frf", "frf_var", "input", "output"]


def _raw(ds: h5py.Dataset) -> object:
    """A dataset's content as bytes (numbers) or a list of bytes (variable-length strings)."""
    v = ds[()]
    return v.tolist() if v.dtype.kind == "O" else v.tobytes()


@pytest.mark.parametrize("name, make", [("sweep_v1.h5", lambda: make_sweep(n_f=4, periods=True)),
                                        ("sweep_v2.h5", v2_sweep)])
def test_files_written_before_the_labels_still_read(tmp_path: Path, name: str, make) -> None:
    """tests/data/legacy: written at e03973e (no channel coordinates). The reader gives the sweep they were
    made from; a file written now holds every contract dataset and attribute with the same bytes."""
    old = LEGACY / name
    assert compare_sweeps(read_sweep(old), make()) == []
    new = tmp_path / name
    write_sweep(make(), new)
    assert compare_sweeps(read_sweep(new), read_sweep(old)) == []
    with h5py.File(old, "r") as a, h5py.File(new, "r") as b:
        assert dict(a.attrs) == dict(b.attrs)
        contract = [f"channels/{f}" for f in CHANNEL_FIELDS]
        for rid in a["runs"]:
            assert dict(a[f"runs/{rid}"].attrs) == dict(b[f"runs/{rid}"].attrs)
            contract += [f"runs/{rid}/{n}" for n in a[f"runs/{rid}"]]
        for path in contract:
            assert a[path].dtype == b[path].dtype and _raw(a[path]) == _raw(b[path]), path
        assert "input" not in a["runs/" + next(iter(a["runs"]))]  # the old file really has no labels
