"""The HDF5 files rotorcheck writes open in xarray (engine h5netcdf) as netCDF-4: per run group a
``frequency`` coordinate (a dimension scale) in Hz, data variables with units, complex128 as complex,
strings as str; no phony dimensions. Skipped when xarray or h5netcdf is not installed."""

from __future__ import annotations

import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
from sweep_helpers import make_sweep, v2_sweep

from rotorcheck.sweep import read_sweep, write_sweep

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

REPO = Path(__file__).resolve().parents[2]
SAMPLE = REPO / "data_samples" / "crack_rig" / "healthy_1000rpm.h5"
UNITS = {"frequency": "Hz", "input_phasor": "N", "output_phasor": "m", "output_var": "m^2", "input_var": "N^2",
         "n_periods": "1", "frf": "m/N", "frf_var": "m^2/N^2"}


def _open(path: Path, group: str | None):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. xarray's warning about phony (unlabelled) dimensions
        return xr.open_dataset(path, engine="h5netcdf", group=group)


def _check_run_group(path: Path, run_id: str, dims: dict[str, tuple[str, ...]]) -> None:
    ds = _open(path, f"runs/{run_id}")
    with h5py.File(path, "r") as h5:
        g = h5[f"runs/{run_id}"]
        # the coordinate is the file's frequency dataset, bit for bit, with its unit
        assert list(ds.coords) == ["frequency"] and ds.indexes["frequency"].name == "frequency"
        assert ds["frequency"].values.tobytes() == g["frequency"][()].tobytes()
        assert ds["frequency"].attrs["units"] == "Hz" == g["frequency"].attrs["units"]
        assert sorted(ds.data_vars) == sorted(set(g) - {"frequency"})
        for name, var in ds.data_vars.items():
            assert var.dims == dims[name], name
            raw = g[name][()]
            assert var.dtype == raw.dtype and var.values.tobytes() == raw.tobytes(), name  # complex128 as complex
            if name in UNITS:
                assert var.attrs["units"] == UNITS[name] == g[name].attrs["units"], name
            else:
                assert name == "period_phasor" and "units" not in var.attrs  # N or m by channel
        for key, value in g.attrs.items():
            assert ds.attrs[key] == value and not isinstance(ds.attrs[key], bytes), key
    ds.close()


def test_bundled_sample_opens_in_xarray() -> None:
    sw = read_sweep(SAMPLE)
    (rid,) = sw.runs
    p = sw.runs[rid].period_phasor.shape[1]
    _check_run_group(SAMPLE, rid, {
        "input_phasor": ("frequency", "input"), "output_phasor": ("frequency", "output"),
        "output_var": ("frequency", "output"), "n_periods": ("frequency",), "frf": ("frequency", "output", "input"),
        "period_phasor": ("frequency", f"period_{p}", "channel"),
    })
    ds = _open(SAMPLE, "runs/" + rid)
    assert ds.sizes["frequency"] == 262 and ds["frequency"].values[0] == 30.0 and ds.attrs["speed_rpm"] == 1000.0
    # the FRF through xarray's label lookup equals the reader's
    np.testing.assert_array_equal(ds["frf"].sel(frequency=300.0, method="nearest").values,
                                  sw.runs[rid].frf[np.argmin(np.abs(sw.runs[rid].frequency - 300.0))])
    ch = _open(SAMPLE, "channels")
    assert [str(x) for x in ch["name"].values] == [c.name for c in sw.channels]
    assert ch["name"].dims == ("channel",) and isinstance(ch["role"].values[0], str)
    assert list(ch["node"].values) == [c.node for c in sw.channels]
    root = _open(SAMPLE, None)
    assert root.attrs["schema"] == "rotorcheck.sweep" and isinstance(root.attrs["rig_id"], str)


def test_v1_and_v2_files_open_in_xarray(tmp_path: Path) -> None:
    v1 = tmp_path / "v1.h5"
    write_sweep(make_sweep(periods=True), v1)
    for rid in ("healthy_1000rpm", "healthy_0rpm"):
        _check_run_group(v1, rid, {
            "input_phasor": ("frequency", "input"), "output_phasor": ("frequency", "output"),
            "output_var": ("frequency", "output"), "n_periods": ("frequency",),
            "frf": ("frequency", "output", "input"), "period_phasor": ("frequency", "period_64", "channel")})
    v2 = tmp_path / "v2.h5"
    sw = v2_sweep()
    write_sweep(sw, v2)
    _check_run_group(v2, "two_shakers", {
        "input_phasor": ("frequency", "pattern_2", "input"), "output_phasor": ("frequency", "pattern_2", "output"),
        "output_var": ("frequency", "pattern_2", "output"), "n_periods": ("frequency", "pattern_2"),
        "frf": ("frequency", "output", "input"), "frf_var": ("frequency", "output", "input"),
        "period_phasor": ("frequency", "pattern_2", "period_4", "channel")})
    _check_run_group(v2, "analyser", {"frf": ("frequency", "output", "input"),
                                      "frf_var": ("frequency", "output", "input")})
    ds = _open(v2, "runs/analyser")
    assert ds.sizes == {"frequency": 7, "output": 2, "input": 2} and ds.attrs["noise_source"] == "measured"
    # the labels change no byte the reader reads, and writing stays deterministic
    again = tmp_path / "again.h5"
    write_sweep(v2_sweep(), again)
    assert again.read_bytes() == v2.read_bytes()
    with h5py.File(v2, "r") as h5:
        assert sorted(h5) == ["channel", "channels", "input", "output", "pattern_2", "period_4", "runs"]
        assert sorted(h5["runs/analyser"]) == ["frequency", "frf", "frf_var"]  # nothing added inside a run
