"""The sideband test (issue 29: crack-specific evidence that benign change cannot imitate): its false-alarm rate by
Monte Carlo, its statistic against the crack's depth and against benign drift, and ``detect`` with it (the default
on a sweep with sidebands, and ``--rule sideband``)."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from shared_runs import CliRun

from rotorcheck import workflow
from rotorcheck.cli import main
from rotorcheck.config import RigConfig, load_config
from rotorcheck.errors import InputError
from rotorcheck.resources import configs_dir, samples_dir
from rotorcheck.signal.sidebands import sideband_points, sideband_scan
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.sweep import read_sweep, write_sweep
from rotorcheck.variability import with_benign
from rotorcheck.workflow.detectors import DetectorSettings
from rotorcheck.workflow.detectors.sideband import SidebandDetector
from rotorcheck.workflow.measured import SidebandFRF

ORDERS = (-2, -1, 1, 2)
GRID = np.linspace(30.0, 120.0, 40)


def _truth_with_crack(depth: float, element: int = 4) -> RigConfig:
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    faults = dict(truth.faults)
    faults["c"] = truth.faults["breathing_crack"].model_copy(update={"depth": depth, "element": element})
    return truth.model_copy(update={"faults": faults})


def _run(cfg: RigConfig, fault: str | None, noise: float, seed: int = 1, benign: dict[str, float] | None = None,
         grid: np.ndarray = GRID) -> workflow.MeasuredRun:
    rpm = 1000.0
    if benign:
        cfg, d_rpm, _, _ = with_benign(cfg, benign)
        rpm += d_rpm
    st = step_settings(cfg)
    st = dataclasses.replace(st, sideband_orders=ORDERS, output_noise_std=st.output_noise_std * noise)
    sw = simulate_rig(cfg, grid, rpm, fault=fault, seed=seed, settings=st, shaft_angle_rad=0.4)
    return workflow.measured_run(sw, load_config(configs_dir() / "crack_rig.yaml"))


def test_false_alarm_rate_and_p_values_by_monte_carlo() -> None:
    """Pure noise sidebands (tones left out as NaN where the simulator left them out), 2,000 sweeps: the sum over
    every point alone has uniform p-values (Kolmogorov-Smirnov: chi2(2n) is exact); the scan over windows, with
    its Bonferroni over windows, calls damage at most at alpha = 0.05 (one-sided binomial, 99.9 %) and not below
    alpha / 4 (it is not a test that never fires)."""
    base = _run(load_config(configs_dir() / "crack_rig_truth.yaml"), None, 1.0, grid=GRID[:24])
    assert base.sidebands is not None
    var = np.asarray(base.sidebands.var)
    rng = np.random.default_rng(11)
    det = SidebandDetector(DetectorSettings(false_alarm=0.05))
    hits, p_all = 0, []
    for _ in range(2000):
        noise = np.sqrt(np.nan_to_num(var) / 2) * (rng.standard_normal(var.shape) + 1j * rng.standard_normal(var.shape))
        frf = np.where(np.isfinite(var), noise, np.nan)
        run = dataclasses.replace(base, sidebands=SidebandFRF(base.sidebands.frequency_hz, base.sidebands.order, frf,
                                                               var))
        hits += det.detect(run).verdict.verdict == "damage"
        p_all.append(sideband_scan(*sideband_points(frf, var), widths=(0,)).p_value)
    assert stats.kstest(p_all, "uniform").pvalue > 1e-3
    assert 0.05 / 4 * 2000 <= hits <= stats.binom.ppf(0.999, 2000, 0.05), hits


def test_scan_finds_a_few_strong_points_the_sum_over_every_point_misses() -> None:
    """Sidebands at 3 adjacent points of 200 (a crack's near a resonance): the window of 2 or 8 finds them where
    the sum over every point does not; its Bonferroni-adjusted p-value is that window's chi2 p-value times the
    number of windows (closed form)."""
    rng = np.random.default_rng(5)
    n = np.full(200, 4)
    t = rng.chisquare(8, 200)
    t[100:103] += 40.0
    whole = sideband_scan(t, n, widths=(0,))
    scan = sideband_scan(t, n)
    assert whole.p_value > 0.01 > scan.p_value
    lo, hi = scan.points
    assert lo <= 100 and hi >= 103 and hi - lo <= 8
    assert scan.p_value == pytest.approx(stats.chi2.sf(scan.statistic, scan.dof) * scan.n_windows, rel=1e-9)
    # widths 2, 8, 32 slid by 1, 4, 16 (the last window ending at the last point) and every point
    assert scan.n_windows == len(range(0, 199, 1)) + len(range(0, 193, 4)) + (len(range(0, 169, 16)) + 1) + 1


def test_statistic_grows_with_depth_and_benign_drift_makes_no_sideband() -> None:
    """Sweeps of the truth rig at 1000 rpm at 1 % of its noise: T for a breathing crack of element 4 grows with the
    depth (5, 10, 20, 40 % of the diameter); noise-free, a healthy rotor with E -2 %, a bearing +3 % and the speed
    +20 rpm (the corner of the ranges) gives T = 0 to rounding (a time-invariant rotor has no sidebands)."""
    det = SidebandDetector(DetectorSettings())
    ts = [det.detect(_run(_truth_with_crack(d), "c", 0.01)).statistic for d in (0.05, 0.1, 0.2, 0.4)]
    assert all(t is not None for t in ts)
    assert np.all(np.diff(np.asarray(ts, dtype=float)) > 0), ts
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    truth = truth.model_copy(update={"variability": load_config(configs_dir() / "crack_rig.yaml").variability})
    drifted = _run(truth, None, 0.0,
                   benign={"youngs_modulus": -0.02, "bearing_stiffness.nme": 0.03, "speed": 20.0})
    sb = drifted.sidebands
    assert sb is not None
    ok = np.isfinite(sb.frf)
    # the noise-free sidebands of a time-invariant rotor against those of the shallowest crack
    crack = _run(_truth_with_crack(0.05), "c", 0.0).sidebands
    assert crack is not None
    assert np.abs(sb.frf[ok]).max() < 1e-9 * np.nanmax(np.abs(crack.frf))


@pytest.fixture(scope="module")
def sideband_sweeps(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 10 % deep breathing crack (element 4) and a healthy repeat, both with sidebands, on the samples' grid."""
    d = tmp_path_factory.mktemp("sidebands")
    grid = next(iter(read_sweep(samples_dir() / "crack_rig" / "healthy_1000rpm.h5").runs.values())).frequency
    truth = _truth_with_crack(0.1)
    st = dataclasses.replace(step_settings(truth, keep_periods=True), sideband_orders=ORDERS)
    write_sweep(simulate_rig(truth, grid, 1000.0, fault="c", seed=11, settings=st, shaft_angle_rad=1.0),
                d / "crack10.h5")
    write_sweep(simulate_rig(truth, grid, 1000.0, seed=12, settings=st, shaft_angle_rad=2.0), d / "healthy.h5")
    return d


def _detect(folder: Path, baseline: Path, sweep: Path, *extra: str) -> tuple[int, dict]:
    out = folder / f"out_{sweep.stem}_{'_'.join(extra) or 'default'}"
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["detect", str(sweep), "--baseline", str(baseline), "--out", str(out), "--no-plots", *extra])
    doc = json.loads((out / "report.json").read_text()) if (out / "report.json").exists() else {}
    return code, doc | {"_output": err.getvalue()}


def test_detect_uses_the_sidebands_beside_the_joint_test(sideband_sweeps: Path, detected_breathing_1000rpm: CliRun,
                                                         tmp_path: Path) -> None:
    """The 10 % crack: the joint test alone calls it healthy (its detectability on this rig is about 11 % depth);
    with the sidebands the sweep is damage, each test at half the 1 % rate; the healthy repeat stays healthy; the
    report says which test decided and on what it rests."""
    baseline = tmp_path / "baseline.h5"
    shutil.copy(detected_breathing_1000rpm.out / "baseline.h5", baseline)
    code, doc = _detect(tmp_path, baseline, sideband_sweeps / "crack10.h5")
    assert code == 1 and doc["verdict"] == "damage"
    sb = doc["sideband_test"]
    assert sb["verdict"] == "damage" and sb["false_alarm"] == pytest.approx(0.005)
    assert doc["false_alarm"] == pytest.approx(0.005)  # the joint test's share
    assert doc["joint_p_value"] > 0.005  # the joint test alone: healthy
    assert "f + k x speed" in doc["conclusion"] and "time-invariant" in doc["conclusion"]
    code, doc = _detect(tmp_path, baseline, sideband_sweeps / "healthy.h5")
    assert code == 0 and doc["verdict"] == "healthy" and doc["sideband_test"]["verdict"] == "healthy"
    code, doc = _detect(tmp_path, baseline, sideband_sweeps / "crack10.h5", "--rule", "sideband")
    assert code == 1 and doc["verdict"] == "damage" and doc["sideband_test"]["false_alarm"] == pytest.approx(0.01)
    code, doc = _detect(tmp_path, baseline, samples_dir() / "crack_rig" / "breathing_crack_1000rpm.h5", "--rule",
                        "sideband")
    assert code == 2 and "sideband_phasor" in doc["_output"] and "no sidebands" in doc["_output"]


def test_a_healthy_sweep_with_sidebands_turns_the_sideband_test_off(tmp_path: Path) -> None:
    """validate on a 'healthy' sweep that holds sidebands (a 30 % crack already there): the baseline records the
    scan's p-value (file round trip), validate warns, and detect tests the main line alone at the full rate, saying
    why; a healthy sweep with sidebands gives a p-value above 0.01 and keeps the test."""
    rig = load_config(configs_dir() / "crack_rig.yaml")
    grid = np.linspace(30.0, 200.0, 60)

    def sweep(depth: float, seed: int) -> workflow.MeasuredRun:
        truth = _truth_with_crack(depth) if depth else load_config(configs_dir() / "crack_rig_truth.yaml")
        st = dataclasses.replace(step_settings(truth), sideband_orders=ORDERS)
        sw = simulate_rig(truth, grid, 1000.0, fault="c" if depth else None, seed=seed, settings=st)
        return workflow.measured_run(sw, rig)

    cracked = sweep(0.3, 1)
    out = workflow.validate(rig, [cracked], workflow.fit_noise(cracked))
    p = out.baseline.healthy.sideband_p_value
    assert p is not None and p < 1e-10
    assert "not time-invariant" in workflow.sideband_warning(out)
    from rotorcheck.baseline import read_baseline, write_baseline

    write_baseline(out.baseline, tmp_path / "b.h5")
    assert read_baseline(tmp_path / "b.h5").healthy.sideband_p_value == pytest.approx(p)
    det = workflow.detect(rig, out.baseline, sweep(0.3, 2))
    assert det.found.sideband is None and det.found.joint is not None
    assert det.found.joint.false_alarm == pytest.approx(0.01)
    assert any("not tested" in n for n in det.found.notes)
    healthy = sweep(0.0, 3)
    out_h = workflow.validate(rig, [healthy], workflow.fit_noise(healthy))
    assert out_h.baseline.healthy.sideband_p_value is not None and out_h.baseline.healthy.sideband_p_value > 0.01
    assert workflow.sideband_warning(out_h) == ""
    det_h = workflow.detect(rig, out_h.baseline, sweep(0.0, 4))
    assert det_h.found.sideband is not None and det_h.found.joint is not None
    assert det_h.found.joint.false_alarm == pytest.approx(0.005)


def test_rule_sideband_refuses_a_resampled_run() -> None:
    """A run interpolated onto another grid keeps its sidebands on its own grid: --rule sideband refuses it,
    naming the run's frequency dataset (the default rule tests them beside the joint test)."""
    run = _run(load_config(configs_dir() / "crack_rig_truth.yaml"), None, 1.0, grid=GRID[:10])
    moved = workflow.resample_run(run, np.linspace(GRID[0], GRID[9], 7))
    assert moved.sidebands is not None and moved.sidebands.frequency_hz.size == 10
    with pytest.raises(InputError) as e:
        SidebandDetector(DetectorSettings()).detect(moved)
    assert "/frequency" in str(e.value) and "--resample" in str(e.value)


def test_correlated_tones_are_scaled_to_a_conservative_chi_square() -> None:
    """At 597.8 Hz, 64 periods (0.107 s), the sidebands 16.7 Hz apart are 1.8 resolution widths apart and their
    estimates correlated: 400,000 draws of the fit's exact noise (its covariance from the design) exceed the
    chi2(8) quantile at 1e-4 1.5-2.2x as often as stated when the tones are taken as independent; divided by
    lambda_max(W) (correlation_scale, 1.33 here) never more often than stated (conservative)."""
    from rotorcheck.signal.sidebands import (
        correlation_scale,
        point_times,
        tone_design,
        tone_phasors,
        tone_set,
        tone_variance,
    )

    om, f = 1000 / 60, 597.8
    tones = tone_set(f, om, ORDERS, f / 64)
    x = tone_design(point_times(f, 16, 64, 64), tones.freq_hz)
    cov = np.linalg.inv(x.T @ x)
    draws = np.linalg.cholesky(cov) @ np.random.default_rng(1).standard_normal((cov.shape[0], 400_000))
    amp, v = tone_phasors(draws, tones), tone_variance(cov, tones)
    idx = [tones.requested[k] for k in ORDERS]
    t = (2 * np.abs(amp[idx]) ** 2 / v[idx, None]).sum(axis=0)
    lam = correlation_scale(f, om, ORDERS, 64)
    assert 1.3 < lam < 1.36
    for a in (1e-2, 1e-3, 1e-4):
        q = stats.chi2.isf(a, 8)
        assert (t / lam > q).mean() <= a
    assert 1.5 * 1e-4 < (t > stats.chi2.isf(1e-4, 8)).mean() < 2.2 * 1e-4


def test_the_default_tests_the_sidebands_of_a_resampled_run_on_their_own_grid() -> None:
    """A new sweep on another grid, resampled onto the baseline's (detect --resample): the default rule still tests
    its sidebands, on the sweep's own grid (before the mend this raised the --rule sideband refusal); a 30 % crack
    is damage by the sideband test."""
    rig = load_config(configs_dir() / "crack_rig.yaml")
    grid = np.linspace(30.0, 120.0, 30)
    healthy = _run(load_config(configs_dir() / "crack_rig_truth.yaml"), None, 1.0, seed=5, grid=grid)
    base = workflow.validate(rig, [healthy], workflow.fit_noise(healthy)).baseline
    own = np.linspace(30.0, 121.0, 37)
    new = workflow.resample_run(_run(_truth_with_crack(0.3), "c", 1.0, seed=6, grid=own), grid)
    det = workflow.detect(rig, base, new)
    sb = det.found.sideband
    assert sb is not None and sb.frequency_hz.size == own.size
    assert sb.verdict.verdict == "damage" and det.verdict.verdict == "damage"
