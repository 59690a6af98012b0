"""A baseline file opens in xarray (engine h5netcdf) group by group: the first run at the root, each further run
in ``runs/<run_id>``, with the coordinates ``frequency_hz`` (Hz), ``channel`` (the channel pairs as the reader
returns them, ``output<-input``), ``output``/``input`` (the first pair's ports), ``units`` on every numeric
variable and the values the rotorcheck reader returns; no phony dimensions. Baselines written before the labels
(tests/data/legacy, schema_version 1) still load. Skipped when xarray or h5netcdf is not installed."""

from __future__ import annotations

import copy
import warnings
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

from rotorcheck.baseline import Baseline, read_baselines, write_baseline
from rotorcheck.cli import EXIT_OK, main
from rotorcheck.resources import samples_dir
from rotorcheck.sweep import read_sweep, write_sweep
from rotorcheck.sweep.format import Sweep
from tests.netcdf_helpers import LEGACY, small_baseline, two_run_baseline
from tests.shared_runs import CliRun

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

#: the unit of each dataset (gamma's: additive m/N; the others by what they hold)
UNITS = {"gamma": "m/N", "gamma_lower": "m/N", "noise_bound_per_point_m": "m", "model_frf": "m/N",
         "input_phasor": "N", "output_phasor": "m", "healthy_frf": "m/N", "healthy_frf_var": "m^2/N^2",
         "healthy_frf_dof": "1", "benign_directions": "m/N", "benign_direction_bound": "1",
         "benign_correction": "m/N per unit of the parameter"}
#: every dataset of a baseline group, as the reader names it (Baseline's flat properties)
DATASETS = ("gamma", "gamma_lower", "gamma_status", "noise_bound_per_point_m", "model_frf", "input_phasor",
            "output_phasor", "healthy_frf", "healthy_frf_var", "healthy_frf_dof", "benign_directions",
            "benign_direction_bound", "benign_correction")


def _open(path: Path, group: str | None = None):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. a warning about phony (unlabelled) dimensions
        return xr.open_dataset(path, engine="h5netcdf", group=group)


def _check_group(path: Path, group: str | None, b: Baseline, gamma_units: str = "m/N") -> None:
    """Group ``group`` of ``path`` through xarray against the set ``b`` the rotorcheck reader returned."""
    ds = _open(path, group)
    assert ds["frequency_hz"].values.tobytes() == b.frequency_hz.tobytes()
    assert ds["frequency_hz"].attrs["units"] == "Hz"
    pairs = b.healthy.channel_pairs
    assert pairs is not None
    assert list(ds["channel"].values) == [f"{o}<-{i}" for o, i in pairs]
    assert list(ds["output"].values) == [pairs[0][0]] and list(ds["input"].values) == [pairs[0][1]]
    assert sorted(ds.coords) == ["channel", "frequency_hz", "input", "output"]
    present = {n for n in DATASETS if getattr(b, n) is not None}
    assert set(ds.data_vars) == present
    for name in present:
        var, ref = ds[name], np.asarray(getattr(b, name))
        if name == "gamma_status":  # text: no unit; decoded as str (the attribute _Encoding)
            assert list(var.values) == ref.tolist() and "units" not in var.attrs
            continue
        expected = gamma_units if name in ("gamma", "gamma_lower") else UNITS[name]
        assert var.attrs["units"] == expected, name
        assert var.dtype == ref.dtype and var.values.tobytes() == ref.tobytes(), name  # complex128 as complex
    assert ds["healthy_frf"].dims == ("frequency_hz", "channel")
    assert ds["model_frf"].dims == ("frequency_hz", "output", "input")
    # a label lookup: the last channel pair's healthy FRF at the 3rd point is the reader's column
    label = f"{pairs[-1][0]}<-{pairs[-1][1]}"
    f2 = b.frequency_hz[2]
    assert ds["healthy_frf"].sel(channel=label, frequency_hz=f2).item() == b.healthy_frf[2, len(pairs) - 1]
    assert ds.attrs["run_id"] == b.run_id and ds.attrs["speed_rpm"] == b.speed_rpm
    ds.close()


def test_two_run_baseline_opens_group_by_group(tmp_path: Path) -> None:
    """Root (first run) and runs/1000rpm on another grid, every optional dataset present (benign arrays on the
    stacked axis ``point``, one row per ``direction`` / ``parameter``)."""
    first, others = two_run_baseline()
    others = copy.deepcopy(others)
    assert others[0].bound is not None
    others[0].bound.frequency_hz = others[0].bound.frequency_hz + 2.5  # another grid than the root's
    path = tmp_path / "baseline.h5"
    write_baseline(first, path, others)
    read = read_baselines(path)
    assert [b.run_id for b in read] == ["0rpm", "1000rpm"]
    _check_group(path, None, read[0])
    _check_group(path, "runs/1000rpm", read[1])
    ds = _open(path)
    assert ds["benign_directions"].dims == ("direction", "point") and ds.sizes["point"] == 9 * 2
    assert ds["benign_correction"].dims == ("parameter", "point") and ds.sizes["parameter"] == 3
    groups = xr.open_groups(path, engine="h5netcdf")  # every group at once (their grids differ)
    assert sorted(groups) == ["/", "/runs", "/runs/1000rpm"]
    assert groups["/runs/1000rpm"]["frequency_hz"].values[0] == 32.5


@pytest.mark.parametrize("uncertainty, parameter, units", [
    ("multiplicative", "", "1"), ("parametric", "masses.m2.mass", "kg"),
    ("parametric", "lumped_springs.k1.stiffness", "N/m"), ("parametric", "bearings.left.kxx", "N/m")])
def test_gamma_carries_the_unit_of_its_uncertainty(tmp_path: Path, uncertainty: str, parameter: str,
                                                   units: str) -> None:
    path = tmp_path / "baseline.h5"
    write_baseline(small_baseline("0rpm", 0.0, 5, uncertainty, parameter), path)
    _check_group(path, None, read_baselines(path)[0], gamma_units=units)


def test_one_run_baseline_from_the_cli_opens_at_the_root(validated_0rpm: CliRun) -> None:
    """`validate` on one sweep of one run: the set is the root (there is no runs/ group to name)."""
    path = validated_0rpm.out / "baseline.h5"
    (b,) = read_baselines(path)
    _check_group(path, None, b)
    with h5py.File(path, "r") as h5:
        assert "runs" not in h5
    assert b.healthy_frf is not None and b.healthy_frf.shape[1] == 1


def test_two_speed_multi_pair_baseline_from_the_cli_opens(tmp_path: Path) -> None:
    """`validate` on one file holding the bundled x/y sweeps at 0 and 1000 rpm (8 channel pairs, 261 and 262
    points in the band): the 0 rpm set at the root, the 1000 rpm set in runs/1000rpm."""
    xy = samples_dir() / "crack_rig_xy"
    a, b = read_sweep(xy / "healthy_0rpm.h5"), read_sweep(xy / "healthy_1000rpm.h5")
    sweep = tmp_path / "two_speeds.h5"
    write_sweep(Sweep(a.rig_id, a.source, a.generator, a.created_utc, a.channels, {**a.runs, **b.runs}), sweep)
    out = tmp_path / "out"
    assert main(["validate", str(sweep), "--out", str(out), "--no-plots"]) == EXIT_OK
    path = out / "baseline.h5"
    read = read_baselines(path)
    assert [(s.run_id, s.frequency_hz.size) for s in read] == [("0rpm", 261), ("1000rpm", 262)]
    _check_group(path, None, read[0])
    _check_group(path, "runs/1000rpm", read[1])
    ds = _open(path, "runs/1000rpm")
    assert ds.sizes["channel"] == 8 and ds["channel"].values[0] == "s6.x<-s8.x"  # the rig's own pair first


def _fields(b: Baseline) -> dict[str, Any]:
    """Everything the reader returns, arrays as (dtype, shape, bytes) or text lists."""
    out: dict[str, Any] = {}
    for part in ("provenance", "noise", "bound", "healthy", "drift"):
        obj = getattr(b, part)
        for key, value in vars(obj).items():
            if isinstance(value, np.ndarray):
                value = value.tolist() if value.dtype.kind in "US" else (value.dtype.str, value.shape,
                                                                          value.tobytes())
            out[f"{part}.{key}"] = value
    return out


def test_baselines_written_before_the_labels_still_load(tmp_path: Path) -> None:
    """tests/data/legacy (written at e03973e, schema_version 1, no dimension scales): the reader verifies their
    digests and returns the sets they were made from; a baseline written now reads the same."""
    first, others = two_run_baseline()
    want = [_fields(b) for b in (first, *others)]
    old = read_baselines(LEGACY / "baseline_two_runs.h5")
    assert [_fields(b) for b in old] == want
    (one,) = read_baselines(LEGACY / "baseline_one_run.h5")
    assert _fields(one) == _fields(small_baseline("0rpm", 0.0, 3))
    new = tmp_path / "baseline.h5"
    write_baseline(first, new, others)
    assert [_fields(b) for b in read_baselines(new)] == want
    with h5py.File(LEGACY / "baseline_two_runs.h5", "r") as h5:
        assert "channel" not in h5 and "DIMENSION_LIST" not in h5["gamma"].attrs  # really without labels


def test_the_readme_xarray_example_runs(validated_0rpm: CliRun, tmp_path: Path,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """The README's xarray block, run as it stands (in a folder holding rotorcheck-out/baseline.h5): the FRF it
    selects by channel names is the reader's column, the baseline's by pair label the reader's healthy FRF."""
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    blocks = [b.split("```", 1)[0] for b in readme.split("```python\n")[1:]]
    (code,) = [b for b in blocks if 'engine="h5netcdf"' in b]
    validated_0rpm.copy_to(tmp_path / "rotorcheck-out")
    monkeypatch.chdir(tmp_path)
    space: dict[str, Any] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        exec(compile(code, "README.md", "exec"), space)  # the README's own example
    sw = read_sweep(samples_dir() / "crack_rig_xy" / "healthy_1000rpm.h5")
    o = [c.name for c in sw.outputs].index("disp_s6_x")
    i = [c.name for c in sw.inputs].index("force_s8_x")
    assert space["h"].values.tobytes() == np.ascontiguousarray(sw.runs["1000rpm"].frf[:, o, i]).tobytes()
    assert space["h"].attrs["units"] == "m/N" and space["h"]["frequency"].attrs["units"] == "Hz"
    (b,) = read_baselines(tmp_path / "rotorcheck-out" / "baseline.h5")
    assert space["g"].values.tobytes() == np.ascontiguousarray(b.healthy_frf[:, 0]).tobytes()
    assert sorted(space["tree"]["runs"].children) == ["1000rpm"]
