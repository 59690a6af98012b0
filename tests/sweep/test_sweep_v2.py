"""Sweep format version 2: several inputs (excitation patterns), least-squares FRF and its variance,
FRF-only runs, the v1 -> v2 reader, and the several-input simulator.

References are independent of the code under test: a known FRF matrix H that generates the phasors,
``np.linalg.lstsq`` per draw for the Monte Carlo, raw h5py reads, dense solves of the FE model
(tests/oracles/frf.py) and the noise level restated from the rig file.
"""

from __future__ import annotations

import copy
import csv
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
import pyuff
import yaml
from scipy import stats
from sweep_helpers import make_sweep

from rotorcheck.config import Port, parse_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.sim.rig_sim import rig_channels, simulate_rig_patterns, step_settings
from rotorcheck.sweep import Channel, Run, Sweep, SweepFormatError, compare_sweeps, read_sweep, write_sweep
from rotorcheck.sweep.summary import summarize
from rotorcheck.sweep.tidy_csv import V2_COLUMNS, export_tidy_csv, import_tidy_csv, read_tidy_csv
from rotorcheck.sweep.uff import export_uff58, import_uff58, read_uff58_frf
from tests.oracles.frf import dense_receptance

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "data_samples"

CH_2IN_4OUT = [
    Channel("F8x", "input", 8, "x", "force", "N"),
    Channel("F8y", "input", 8, "y", "force", "N"),
    Channel("d6x", "output", 6, "x", "displacement", "m"),
    Channel("d6y", "output", 6, "y", "displacement", "m"),
    Channel("d3x", "output", 3, "x", "displacement", "m"),
    Channel("d3y", "output", 3, "y", "displacement", "m"),
]
CREATED = "2024-05-01T12:00:00Z"


def _known_h(rng: np.random.Generator, nf: int, n_out: int = 4, n_in: int = 2) -> np.ndarray:
    """A known FRF matrix (f, n_out, n_in), m/N, magnitudes spread over two decades."""
    mag = 10.0 ** rng.uniform(-7, -5, (nf, n_out, n_in))
    return mag * np.exp(2j * np.pi * rng.random((nf, n_out, n_in)))


def _one_at_a_time(rng: np.random.Generator, nf: int, n_in: int = 2) -> np.ndarray:
    """X (f, n_exc = n_in, n_in): pattern e drives input e alone (the others exactly 0)."""
    x = np.zeros((nf, n_in, n_in), complex)
    for e in range(n_in):
        x[:, e, e] = (0.5 + rng.random(nf)) * np.exp(2j * np.pi * rng.random(nf))
    return x


def _multi_reference(rng: np.random.Generator, nf: int) -> np.ndarray:
    """X (f, 3 patterns, 2 inputs): both shakers at once with different phases (multi-reference)."""
    amp = np.array([[1.0, 0.8], [0.6, 1.2], [1.0, 1.0]])
    phase = np.array([[0.0, 0.0], [0.0, 2.1], [0.3, -1.9]])
    x = amp * np.exp(1j * phase)
    return np.broadcast_to(x, (nf, 3, 2)) * np.exp(2j * np.pi * rng.random((nf, 1, 1)))


def _pattern_run(seed: int = 3, nf: int = 40, multi: bool = False, periods: bool = False) -> Run:
    """A noisy several-pattern run whose mean/variance come from per-period phasors."""
    rng = np.random.default_rng(seed)
    f = np.sort(30.0 + 570.0 * rng.random(nf))
    h = _known_h(rng, nf)
    x = _multi_reference(rng, nf) if multi else _one_at_a_time(rng, nf)
    ne = x.shape[1]
    p = 16
    y = np.einsum("foi,fei->feo", h, x)
    def cgauss(shape: tuple[int, ...]) -> np.ndarray:
        return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)

    per_in = np.repeat(x[:, :, None, :], p, axis=2)
    per_in = per_in + (per_in != 0) * 1e-3 * cgauss(per_in.shape)  # undriven inputs stay exactly 0
    per_out = y[:, :, None, :] + 1e-8 * cgauss((nf, ne, p, 4))
    mi, mo = per_in.mean(axis=2), per_out.mean(axis=2)
    vi = (np.abs(per_in - mi[:, :, None]) ** 2).sum(axis=2) / (p * (p - 1))
    vo = (np.abs(per_out - mo[:, :, None]) ** 2).sum(axis=2) / (p * (p - 1))
    pp = np.concatenate([per_in, per_out], axis=3) if periods else None
    return Run.from_patterns("two_shakers_1000rpm", 1000.0, f, mi, mo, vo, p, input_var=vi, period_phasor=pp,
                             notes="two inputs one at a time")


def _v2_sweep(periods: bool = True) -> Sweep:
    multi = _pattern_run(periods=periods)
    rng = np.random.default_rng(9)
    nf = 25
    f = np.linspace(40.0, 400.0, nf)
    frf_only = Run.frf_only("analyser_0rpm", 0.0, f, _known_h(rng, nf), 1e-16 * (1 + rng.random((nf, 4, 2))),
                            noise_source="assumed: 1 % of |H| floor")
    return Sweep("crack_rig", "measured", "tests/sweep v2", CREATED, list(CH_2IN_4OUT),
                 {multi.run_id: multi, frf_only.run_id: frf_only})


# --------------------------------------------------------------------------------------------
# a v1 file through the v2 reader
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("source", ["written", "bundled"])
def test_v1_file_read_by_v2_reader_unchanged(tmp_path: Path, source: str) -> None:
    if source == "written":
        p = tmp_path / "v1.h5"
        write_sweep(make_sweep(periods=True), p)
    else:
        p = SAMPLES / "crack_rig" / "healthy_1000rpm.h5"
    sw = read_sweep(p)
    with h5py.File(p, "r") as h5:
        assert int(h5.attrs["schema_version"]) == 1
        for rid, run in sw.runs.items():
            g = h5[f"runs/{rid}"]
            assert run.n_exc == 1 and not run.is_frf_only and run.frf_var is None and run.noise_source is None
            for name in ("input_phasor", "output_phasor", "output_var", "n_periods", "frf", "period_phasor"):
                if name not in g:
                    assert name == "period_phasor" and run.period_phasor is None
                    continue
                raw = g[name][()]
                view = getattr(run, name)
                assert view.shape == raw.shape and view.dtype == raw.dtype, name
                assert view.tobytes() == raw.tobytes(), name  # the v1 shapes and bits
            assert run.input_phasor_exc.shape == (g["frequency"].shape[0], 1, g["input_phasor"].shape[1])
            assert run.n_periods_exc.shape == (g["frequency"].shape[0], 1)
            # the propagated variance of a v1 run is output_var / |W|^2
            w, v = g["input_phasor"][()], g["output_var"][()]
            np.testing.assert_allclose(run.frf_variance(), v[:, :, None] / np.abs(w[:, None, :]) ** 2, rtol=1e-13)
    # writing it again gives the same version-1 bytes
    if source == "written":
        q = tmp_path / "again.h5"
        write_sweep(sw, q)
        assert q.read_bytes() == p.read_bytes()


# --------------------------------------------------------------------------------------------
# least squares FRF and its variance
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("multi", [False, True], ids=["one_at_a_time", "multi_reference"])
def test_ls_frf_equals_known_matrix_noise_free(multi: bool) -> None:
    rng = np.random.default_rng(11)
    nf = 50
    h = _known_h(rng, nf)
    x = _multi_reference(rng, nf) if multi else _one_at_a_time(rng, nf)
    y = np.einsum("foi,fei->feo", h, x)  # Y = H X, pattern by pattern
    run = Run.from_patterns("r", 0.0, np.arange(1.0, nf + 1), x, y, np.full(y.shape, 1e-18), 8)
    rel = np.abs(run.frf - h).max() / np.abs(h).max()
    assert rel < 1e-12, rel  # measured 5e-16
    assert run.n_exc == (3 if multi else 2) and run.frf.shape == (nf, 4, 2)


def test_frf_var_one_input_per_pattern_is_output_var_over_force_squared() -> None:
    rng = np.random.default_rng(5)
    nf = 30
    x = _one_at_a_time(rng, nf)
    var = 10.0 ** rng.uniform(-18, -16, (nf, 2, 4))
    run = Run.from_patterns("r", 0.0, np.arange(1.0, nf + 1), x, np.ones((nf, 2, 4)), var, 8)
    for e in range(2):  # pattern e drives input e
        expected = var[:, e, :] / np.abs(x[:, e, e])[:, None] ** 2
        np.testing.assert_allclose(run.frf_var[:, :, e], expected, rtol=1e-13)


@pytest.mark.parametrize("multi", [False, True], ids=["one_at_a_time", "multi_reference"])
def test_frf_var_against_monte_carlo(multi: bool) -> None:
    rng = np.random.default_rng(21)
    nf, draws = 4, 2000
    h = _known_h(rng, nf)
    x = _multi_reference(rng, nf) if multi else _one_at_a_time(rng, nf)
    ne = x.shape[1]
    var = 10.0 ** rng.uniform(-17, -15, (nf, ne, 4))  # unequal per frequency, pattern, output
    y0 = np.einsum("foi,fei->feo", h, x)
    run = Run.from_patterns("r", 0.0, np.arange(1.0, nf + 1), x, y0, var, 8)
    sq = np.zeros((nf, 4, 2))
    for _ in range(draws):
        noise = np.sqrt(var / 2) * (rng.standard_normal(var.shape) + 1j * rng.standard_normal(var.shape))
        y = y0 + noise
        for k in range(nf):  # independent route: least squares X^T H^T = Y^T
            ht = np.linalg.lstsq(x[k], y[k], rcond=None)[0]  # (n_in, n_out)
            sq[k] += np.abs(ht.T - h[k]) ** 2
    mc = sq / draws
    ratio = run.frf_var / mc
    assert np.all(np.abs(ratio - 1) < 0.10), (ratio.min(), ratio.max())  # measured 0.95-1.07


# --------------------------------------------------------------------------------------------
# validation of the input matrix
# --------------------------------------------------------------------------------------------


def test_zero_inputs_accepted_where_x_keeps_full_rank(tmp_path: Path) -> None:
    run = _pattern_run()
    assert np.count_nonzero(run.input_phasor_exc == 0) == run.frequency.size * 2  # undriven inputs
    sw = Sweep("crack_rig", "simulated", "t", CREATED, list(CH_2IN_4OUT), {run.run_id: run})
    write_sweep(sw, tmp_path / "ok.h5")


def test_rank_deficient_x_rejected_naming_frequency_and_inputs(tmp_path: Path) -> None:
    run = _pattern_run(multi=True)
    k = 7
    fk = float(run.frequency[k])
    x = run.input_phasor_exc.copy()
    x[k, 1] = (0.3 - 2j) * x[k, 0]  # pattern 1 the same as pattern 0 up to scale
    x[k, 2] = 2.5j * x[k, 0]
    run.input_phasor_exc = x
    sw = Sweep("crack_rig", "simulated", "t", CREATED, list(CH_2IN_4OUT), {run.run_id: run})
    with pytest.raises(SweepFormatError) as ei:
        write_sweep(sw, tmp_path / "bad.h5")
    msg = str(ei.value)
    assert ei.value.path_inside == f"/runs/{run.run_id}/input_phasor", msg
    assert f"rank-deficient at frequency {fk:.9g} Hz (index {k})" in msg, msg
    assert "['F8x', 'F8y']" in msg, msg
    assert not (tmp_path / "bad.h5").exists()


def test_undriven_input_rejected_in_file(tmp_path: Path) -> None:
    run = _pattern_run()
    sw = Sweep("crack_rig", "simulated", "t", CREATED, list(CH_2IN_4OUT), {run.run_id: run})
    p = tmp_path / "s.h5"
    write_sweep(sw, p)
    where = f"/runs/{run.run_id}/input_phasor"
    with h5py.File(p, "r+") as h5:
        h5[where][3, 1, 1] = 0j  # pattern 1 no longer drives F8y: no pattern does at 3
    with pytest.raises(SweepFormatError) as ei:
        read_sweep(p)
    msg = str(ei.value)
    assert msg.startswith(f"{p}: {where}: "), msg
    assert f"frequency {float(run.frequency[3]):.9g} Hz (index 3)" in msg
    assert "input(s) ['F8y'] zero in every pattern" in msg
    assert "(1, 'F8y')" in msg  # the zero phasor that caused it


def test_fewer_patterns_than_inputs_rejected(tmp_path: Path) -> None:
    run = _pattern_run()
    run.input_phasor_exc = run.input_phasor_exc[:, :1]
    run.output_phasor_exc = run.output_phasor_exc[:, :1]
    run.output_var_exc = run.output_var_exc[:, :1]
    run.n_periods_exc = run.n_periods_exc[:, :1]
    run.input_var_exc = None
    sw = Sweep("crack_rig", "simulated", "t", CREATED, list(CH_2IN_4OUT), {run.run_id: run})
    with pytest.raises(SweepFormatError, match=r"1 excitation pattern\(s\) for 2 inputs"):
        write_sweep(sw, tmp_path / "x.h5")
    with pytest.raises(ValueError, match="need n_exc >= n_in"):
        Run.from_patterns("r", 0.0, [1.0], np.ones((1, 1, 2)), np.ones((1, 1, 4)), np.ones((1, 1, 4)), 4)


def test_frf_inconsistent_with_ls_rejected(tmp_path: Path) -> None:
    run = _pattern_run(multi=True)
    sw = Sweep("crack_rig", "simulated", "t", CREATED, list(CH_2IN_4OUT), {run.run_id: run})
    p = tmp_path / "s.h5"
    write_sweep(sw, p)
    with h5py.File(p, "r+") as h5:
        h5[f"/runs/{run.run_id}/frf"][5, 2, 1] *= 1 + 1e-6
    with pytest.raises(SweepFormatError, match=r"frf inconsistent with Y X\^\+ .* at index \(5, 2, 1\)"):
        read_sweep(p)


# --------------------------------------------------------------------------------------------
# round trip, FRF-only runs, single-pattern views
# --------------------------------------------------------------------------------------------


def test_v2_roundtrip_bit_exact(tmp_path: Path) -> None:
    sw = _v2_sweep()
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    write_sweep(sw, a)
    write_sweep(_v2_sweep(), b)
    assert a.read_bytes() == b.read_bytes()  # deterministic bytes
    back = read_sweep(a)
    assert compare_sweeps(sw, back) == []
    multi, fo = sw.runs["two_shakers_1000rpm"], sw.runs["analyser_0rpm"]
    with h5py.File(a, "r") as h5:  # raw h5py: the datasets are exactly the arrays, v2 names and shapes
        assert int(h5.attrs["schema_version"]) == 2
        g = h5["runs/two_shakers_1000rpm"]
        # v2's names, and the channel-name coordinates of the netCDF view (hdf5io's docstring)
        assert sorted(g) == sorted(["frequency", "input_phasor", "output_phasor", "output_var", "input_var",
                                    "n_periods", "frf", "frf_var", "period_phasor", "input", "output", "channel"])
        for name, arr in (("input_phasor", multi.input_phasor_exc), ("output_phasor", multi.output_phasor_exc),
                          ("output_var", multi.output_var_exc), ("input_var", multi.input_var_exc),
                          ("n_periods", multi.n_periods_exc), ("frf", multi.frf), ("frf_var", multi.frf_var),
                          ("period_phasor", multi.period_phasor_exc)):
            assert g[name][()].tobytes() == np.ascontiguousarray(arr).tobytes(), name
        assert g["input_phasor"].shape == (40, 2, 2) and g["period_phasor"].shape == (40, 2, 16, 6)
        assert g["n_periods"].dtype == np.int32
        f = h5["runs/analyser_0rpm"]
        assert sorted(f) == ["frequency", "frf", "frf_var", "input", "output"]
        assert f.attrs["noise_source"] == "assumed: 1 % of |H| floor"
        assert f["frf"][()].tobytes() == fo.frf.tobytes()
    # a one-ulp change is found
    back.runs["analyser_0rpm"].frf_var[2, 1, 0] = np.nextafter(back.runs["analyser_0rpm"].frf_var[2, 1, 0], 1.0)
    (d,) = compare_sweeps(sw, back)
    assert d.startswith("/runs/analyser_0rpm/frf_var: 1 of 200 elements differ") and d.endswith("index (2, 1, 0)")


def test_period_phasor_per_pattern_checked(tmp_path: Path) -> None:
    sw = _v2_sweep()
    p = tmp_path / "s.h5"
    write_sweep(sw, p)
    where = "/runs/two_shakers_1000rpm/period_phasor"
    with h5py.File(p, "r+") as h5:
        h5[where][4, 1, 10, 3] += 1e-7
    with pytest.raises(SweepFormatError, match=re.escape(f"{where}: mean over periods at index (4, 1, :, 3)")):
        read_sweep(p)


def test_frf_only_run_needs_noise_source(tmp_path: Path) -> None:
    sw = _v2_sweep(periods=False)
    p = tmp_path / "s.h5"
    write_sweep(sw, p)
    back = read_sweep(p)
    fo = back.runs["analyser_0rpm"]
    assert fo.is_frf_only and fo.n_exc == 0 and fo.noise_source == "assumed: 1 % of |H| floor"
    with h5py.File(p, "r+") as h5:
        del h5["runs/analyser_0rpm"].attrs["noise_source"]
    with pytest.raises(SweepFormatError) as ei:
        read_sweep(p)
    assert ei.value.path_inside == "/runs/analyser_0rpm@noise_source"
    assert "FRF-only run" in str(ei.value) and "'measured' or 'assumed: <rule>'" in str(ei.value)
    with h5py.File(p, "r+") as h5:
        h5["runs/analyser_0rpm"].attrs["noise_source"] = "guessed"
    with pytest.raises(SweepFormatError, match="neither 'measured' nor 'assumed: <rule>'"):
        read_sweep(p)
    with pytest.raises(ValueError, match="neither 'measured'"):
        Run.frf_only("r", 0.0, [1.0], np.ones((1, 4, 2)), noise_source="assumed: ")


def test_single_pattern_views_refuse_several_patterns_and_frf_only() -> None:
    sw = _v2_sweep(periods=False)
    multi, fo = sw.runs["two_shakers_1000rpm"], sw.runs["analyser_0rpm"]
    with pytest.raises(SweepFormatError, match=r"run has 2 excitation patterns: the single-pattern view "
                                               r"input_phasor needs n_exc = 1; use input_phasor_exc"):
        _ = multi.input_phasor
    with pytest.raises(SweepFormatError, match="n_periods needs n_exc = 1"):
        _ = multi.n_periods
    with pytest.raises(SweepFormatError, match=r"FRF-only run \(noise_source 'assumed: 1 % of \|H\| floor'\) "
                                               r"has no output_var"):
        _ = fo.output_var
    assert fo.period_phasor is None
    # one pattern: the views are the v1 arrays, writable in place
    r = make_sweep().runs["healthy_0rpm"]
    assert r.output_phasor.shape == (131, 2) and r.n_periods.shape == (131,) and r.n_exc == 1
    r.output_phasor[0, 0] = 5.0
    assert r.output_phasor_exc[0, 0, 0] == 5.0


def test_summary_of_v2_sweep() -> None:
    sw = _v2_sweep()
    out = summarize(sw)
    assert out["schema_version"] == 2
    multi, fo = out["runs"]
    assert (multi["n_exc"], multi["frf_only"], multi["noise_source"]) == (2, False, None)
    run = sw.runs["two_shakers_1000rpm"]
    sd = np.sqrt(run.output_var_exc[:, :, 0]).ravel()  # d6x over all points and patterns
    assert multi["noise"]["per_output"]["d6x"]["n_points"] == 80
    assert multi["noise"]["per_output"]["d6x"]["max_std_m"] == pytest.approx(sd.max(), rel=1e-15)
    assert "pooled_bound_harmonics_removed_m" in multi["noise"]
    assert (fo["n_exc"], fo["frf_only"], fo["noise_source"]) == (None, True, "assumed: 1 % of |H| floor")
    assert fo["noise"]["noise_source"] == "assumed: 1 % of |H| floor" and fo["n_periods_min"] is None
    fv = sw.runs["analyser_0rpm"].frf_var
    assert fo["noise"]["frf_std_m_per_n"]["max"] == pytest.approx(np.sqrt(fv.max()), rel=1e-15)
    assert np.isnan(fo["noise"]["all_outputs"]["median_std_m"])
    assert summarize(make_sweep())["schema_version"] == 1


# --------------------------------------------------------------------------------------------
# the several-input simulator
# --------------------------------------------------------------------------------------------

SPEED = 1000.0
ACTUATORS = [Port(station=8, direction="x"), Port(station=8, direction="y")]
SENSORS = [Port(station=6, direction="x"), Port(station=6, direction="y"),
           Port(station=3, direction="x"), Port(station=3, direction="y")]
GRID = np.linspace(30.0, 600.0, 58)


@pytest.fixture(scope="module")
def quiet_truth():
    """The truth rig without unbalance and misalignment (no synchronous leaks)."""
    d = yaml.safe_load((REPO / "configs" / "crack_rig_truth.yaml").read_text())
    d = copy.deepcopy(d)
    d["measurement"].pop("misalignment", None)
    d["measurement"]["unbalance"] = []
    return parse_config(d)


def _dense(cfg, f: np.ndarray) -> np.ndarray:
    system = build_system(cfg)
    return dense_receptance(system, f, SPEED, [system.port_dof(s) for s in SENSORS],
                            [system.port_dof(a) for a in ACTUATORS])


def test_simulated_two_inputs_four_outputs_noiseless_equals_receptance(tmp_path: Path, quiet_truth) -> None:
    import dataclasses

    st = dataclasses.replace(step_settings(quiet_truth), output_noise_std=0.0, n_periods=8)
    sw = simulate_rig_patterns(quiet_truth, GRID, ACTUATORS, SENSORS, speed_rpm=SPEED, seed=4, settings=st)
    run = sw.runs["1000rpm"]
    assert [c.name for c in sw.channels] == ["force_s8_x", "force_s8_y", "disp_s6_x", "disp_s6_y",
                                            "disp_s3_x", "disp_s3_y"]
    assert run.n_exc == 2 and run.input_phasor_exc.shape == (58, 2, 2)
    np.testing.assert_array_equal(run.input_phasor_exc[:, [0, 1], [1, 0]], 0)  # one input per pattern
    np.testing.assert_array_equal(run.input_phasor_exc[:, [0, 1], [0, 1]], 1.0)
    h = _dense(quiet_truth, GRID)
    # relative to each output row's largest entry (the gyroscopic x-y cross terms are small)
    rel = np.abs(run.frf - h).max(axis=2) / np.abs(h).max(axis=2)
    assert rel.max() < 1e-8, rel.max()  # measured 8e-12 (engine vs dense solve)
    assert np.abs(h[:, 1, 0]).max() > 1e-3 * np.abs(h[:, 0, 0]).max()  # not vacuous: real cross-coupling
    p = tmp_path / "two.h5"
    write_sweep(sw, p)
    assert compare_sweeps(read_sweep(p), sw) == []


def test_simulated_two_inputs_noise_matches_rig_file(quiet_truth) -> None:
    sw = simulate_rig_patterns(quiet_truth, GRID, ACTUATORS, SENSORS, speed_rpm=SPEED, seed=8)
    run = sw.runs["1000rpm"]
    # restated from configs/crack_rig_truth.yaml: sigma 0.2 um per sample, 64 samples x 64 periods, 1 N
    s2 = 4.0 * (2.0e-7) ** 2 / (64 * 64)
    err = np.abs(run.frf - _dense(quiet_truth, GRID)) ** 2 / s2  # each ~ Exp(1): 2 sum ~ chi2(2 N)
    n = err.size
    stat = 2.0 * err.sum()
    lo, hi = stats.chi2.ppf([5e-4, 1 - 5e-4], 2 * n)
    assert lo < stat < hi, (stat, lo, hi)  # measured 1018 for 2 N = 928 (bounds 793-1076)
    ratio = float(np.mean(run.frf_var) / s2)  # the stored variance estimates the same level
    assert abs(ratio - 1) < 0.05, ratio  # measured 0.997
    # deterministic by seed; the one-input channel table is unchanged
    again = simulate_rig_patterns(quiet_truth, GRID, ACTUATORS, SENSORS, speed_rpm=SPEED, seed=8)
    assert compare_sweeps(sw, again) == []
    assert [c.name for c in rig_channels(quiet_truth)] == ["force_s8_x", "disp_s6_x"]


# --------------------------------------------------------------------------------------------
# UFF58 and tidy CSV of several-input and FRF-only runs
# --------------------------------------------------------------------------------------------


def test_uff58_several_inputs_roundtrip(tmp_path: Path) -> None:
    sw = _v2_sweep(periods=False)
    p = tmp_path / "s.uff"
    export_uff58(sw, p)
    back = import_uff58(p)
    # everything bit for bit (binary 58b); UFF58 carries no run notes
    assert compare_sweeps(sw, back, ignore=["generator"]) == [
        "/runs/two_shakers_1000rpm@notes: 'two inputs one at a time' != ''"
    ]
    # independent reader: plain pyuff sees one FRF record per output/input pair with node/direction
    sets = pyuff.UFF(str(p)).read_sets()
    frf_sets = [x for x in sets if x["func_type"] == 4]
    assert len(frf_sets) == 2 * 4 * 2
    run = sw.runs["two_shakers_1000rpm"]
    last = [x for x in frf_sets if "run=two_shakers_1000rpm" in x["id2"]][-1]  # d3y / F8y
    assert (last["rsp_node"], last["rsp_dir"], last["ref_node"], last["ref_dir"]) == (3, 2, 8, 2)
    np.testing.assert_array_equal(last["data"], run.frf[:, 3, 1])
    tables = read_uff58_frf(p)
    np.testing.assert_array_equal(tables["analyser_0rpm"].frf_var, sw.runs["analyser_0rpm"].frf_var)
    assert tables["analyser_0rpm"].noise_source == "assumed: 1 % of |H| floor"


def test_uff58_frf_only_import_needs_noise_source(tmp_path: Path) -> None:
    sw = _v2_sweep(periods=False)
    p = tmp_path / "frf.uff"
    export_uff58(sw, p, include_phasors=False)
    with pytest.raises(SweepFormatError) as ei:
        import_uff58(p)
    msg = str(ei.value)
    assert "run 'two_shakers_1000rpm': FRF-only file" in msg and "pass noise_source" in msg, msg
    back = import_uff58(p, noise_source="measured")
    run, src = back.runs["two_shakers_1000rpm"], sw.runs["two_shakers_1000rpm"]
    assert run.is_frf_only and run.noise_source == "measured"
    assert run.frf.tobytes() == src.frf.tobytes() and run.frf_var.tobytes() == src.frf_var.tobytes()
    q = tmp_path / "back.h5"
    write_sweep(back, q)
    assert read_sweep(q).runs["two_shakers_1000rpm"].noise_source == "measured"


def test_uff58_foreign_frf_only_file(tmp_path: Path) -> None:
    """A file from another tool: FRF records without rotorcheck ID tokens."""
    sw = _v2_sweep(periods=False)
    mine = tmp_path / "mine.uff"
    export_uff58(sw, mine, include_phasors=False)
    sets = [x for x in pyuff.UFF(str(mine)).read_sets() if x["func_type"] == 4 and "analyser" in x["id2"]]
    for x in sets:
        for line in ("id1", "id2", "id3", "id4", "id5"):
            x[line] = "NONE"
    foreign = tmp_path / "foreign.uff"
    pyuff.UFF(str(foreign)).write_sets(sets, mode="add")
    with pytest.raises(SweepFormatError, match=r"foreign UFF58 file .*pass \['rig_id', 'source', 'created_utc'\]"):
        import_uff58(foreign, run_id="r1", noise_source="measured")
    back = import_uff58(foreign, run_id="r1", rig_id="crack_rig", source="measured", created_utc=CREATED,
                        noise_source="assumed: 2 % of |H|")
    run = back.runs["r1"]
    assert run.is_frf_only and run.noise_source == "assumed: 2 % of |H|" and run.frf_var is None
    assert [c.name for c in back.channels] == ["F8x", "F8y", "d6x", "d6y", "d3x", "d3y"]  # d<node><dir> names
    np.testing.assert_array_equal(run.frf, sw.runs["analyser_0rpm"].frf)


def test_tidy_csv_several_inputs_to_frf_only(tmp_path: Path) -> None:
    sw = _v2_sweep(periods=False)
    p = tmp_path / "s.csv"
    export_tidy_csv(sw, p)
    with open(p, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0])[-2:] == V2_COLUMNS and len(rows) == (40 + 25) * 4 * 2
    src = sw.runs["two_shakers_1000rpm"]
    r = rows[7]  # first frequency, d3y / F8y
    assert (r["output"], r["input"], r["output_var"], r["input_re"]) == ("d3y", "F8y", "", "")
    assert complex(float(r["frf_re"]), float(r["frf_im"])) == src.frf[0, 3, 1]
    assert float(r["frf_var"]) == src.frf_var[0, 3, 1] and r["noise_source"] == "measured"
    back = import_tidy_csv(p, CH_2IN_4OUT, rig_id="crack_rig", source="measured", created_utc=CREATED)
    run = back.runs["two_shakers_1000rpm"]
    assert run.is_frf_only and run.noise_source == "measured"
    assert run.frf.tobytes() == src.frf.tobytes() and run.frf_var.tobytes() == src.frf_var.tobytes()
    fo = back.runs["analyser_0rpm"]
    assert fo.noise_source == "assumed: 1 % of |H| floor"
    a = Sweep("crack_rig", "measured", "g", CREATED, list(CH_2IN_4OUT), {"analyser_0rpm": sw.runs["analyser_0rpm"]})
    b = Sweep("crack_rig", "measured", "g", CREATED, list(CH_2IN_4OUT), {"analyser_0rpm": fo})
    assert compare_sweeps(a, b) == []  # the FRF-only run comes back bit for bit


def test_tidy_csv_v1_frf_only_import(tmp_path: Path) -> None:
    s = make_sweep()
    p = tmp_path / "frf.csv"
    export_tidy_csv(s, p, include_phasors=False)
    assert p.read_text().splitlines()[0].split(",")[-1] == "n_periods"  # v1 layout unchanged
    from sweep_helpers import CHANNELS

    kw = {"rig_id": s.rig_id, "source": s.source, "created_utc": s.created_utc}
    with pytest.raises(SweepFormatError, match=r"FRF-only content \(no phasor columns\) and no noise_source"):
        import_tidy_csv(p, CHANNELS, **kw)
    back = import_tidy_csv(p, CHANNELS, noise_source="assumed: 1 % of |H| floor", **kw)
    for rid, run in back.runs.items():
        assert run.is_frf_only and run.frf_var is None
        assert run.frf.tobytes() == s.runs[rid].frf.tobytes()
    assert read_tidy_csv(p)["healthy_0rpm"].noise_source is None


def test_one_plant_through_the_pattern_path_equals_simulate_fast() -> None:
    """The several-input path shares the timeline, lock-in and random draws of the one-input path."""
    from sweep_helpers import three_mass

    from rotorcheck.sim.simulator import StepSettings, matrix_plant, simulate_fast, simulate_fast_patterns

    m, c, k = three_mass()
    plant = matrix_plant(m, c, k, np.array([1.0, 0.0, 0.0]), np.eye(3)[[0, 2]])
    st = StepSettings(n_periods=[6, 7, 8], settle_periods=3, output_phasor_noise_std=1e-6,
                      input_phasor_noise_std=1e-3, keep_periods=True, dwell_s=0.1)
    f = [0.9, 2.0, 4.5]
    one = simulate_fast(plant, f, st, rng=12)
    pat = simulate_fast_patterns([plant], f, st, rng=12)
    np.testing.assert_array_equal(pat.t0_s[:, 0], one.t0_s)
    for a, b in ((pat.input_phasor, one.input_phasor), (pat.output_phasor, one.output_phasor),
                 (pat.output_var, one.output_var), (pat.input_var, one.input_var),
                 (pat.period_output, one.period_output)):
        assert a[:, 0].tobytes() == b.tobytes()
