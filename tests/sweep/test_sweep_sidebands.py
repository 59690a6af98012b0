"""Sidebands f + k x speed (sweep version 3): the least-squares tone fit, the simulator's sidebands against a time
integration of a time-periodic rotor, the shaft reference, the file round trip and its checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import stats
from sweep_helpers import CHANNELS

from rotorcheck.config import load_config
from rotorcheck.resources import configs_dir
from rotorcheck.signal.sidebands import fit_tones, point_times, tone_covariance, tone_set
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.sim.simulator import StepSettings, simulate_fast
from rotorcheck.sweep import Run, Sweep, read_sweep, write_sweep
from rotorcheck.sweep.format import SweepFormatError
from tests.oracles.hb import harmonic_balance_plant
from tests.oracles.time_domain import simulate_time_domain

ORDERS = (-2, -1, 1, 2)


def _signal(tau: np.ndarray, freqs: list[float], amps: list[complex]) -> np.ndarray:
    return np.sum([np.real(a * np.exp(2j * np.pi * g * tau)) for g, a in zip(freqs, amps)], axis=0)


def test_fit_recovers_every_tone_and_conjugates_a_negative_sideband() -> None:
    """Noise-free: the fit returns the synthesized phasors; f - 2 Omega < 0 is read as the tone at |f - 2 Omega|
    with the conjugate phasor (so the stored phasor is that of exp(j 2 pi (f - 2 Omega) t) itself)."""
    f, om = 20.0, 16.0
    tau = point_times(f, 4, 64, 32)
    tones = tone_set(f, om, ORDERS, f / 64)
    a = {f: 1.0 + 0.5j, om: 0.3j, f + om: 0.02 - 0.01j, f - om: 0.004 + 0.03j, f + 2 * om: -0.007j}
    neg = 0.011 - 0.006j  # the tone exp(j 2 pi (f - 2 om) t) with f - 2 om = -12 Hz
    y = _signal(tau, list(a), list(a.values())) + np.real(neg * np.exp(2j * np.pi * (f - 2 * om) * tau))
    amp, _ = fit_tones(y[:, None], tau, tones)
    got = {k: amp[tones.requested[k], 0] for k in ORDERS}
    np.testing.assert_allclose([got[1], got[-1], got[2], got[-2]], [a[f + om], a[f - om], a[f + 2 * om], neg],
                               atol=1e-12)


def test_fit_variance_is_the_lockin_one_for_tones_apart_and_matches_monte_carlo() -> None:
    """E|dB|^2 = 4 sigma^2 / (N M) for tones well apart (the lock-in's, closed form); the stated variance agrees
    with the scatter of 400 noisy fits (chi-square: 2 |dB|^2 / var has mean 2)."""
    f, om, n, m, sigma = 37.0, 16.6667, 64, 32, 0.1
    tau = point_times(f, 4, n, m)
    tones = tone_set(f, om, ORDERS, f / n)
    cov = tone_covariance(tau, tones)
    k1 = tones.requested[1]
    assert cov[k1] == pytest.approx(4.0 / (n * m), rel=0.02)
    rng = np.random.default_rng(3)
    z = []
    for _ in range(400):
        y = sigma * rng.standard_normal(tau.size)
        amp, var = fit_tones(y[:, None], tau, tones)
        z.append(2 * abs(amp[k1, 0]) ** 2 / var[k1, 0])
    # mean of chi2(2) over 400 draws: 2 +- 3 x 2/sqrt(400)
    assert abs(np.mean(z) - 2.0) < 0.3


def test_tone_within_the_resolution_of_the_excitation_or_a_harmonic_is_not_separable() -> None:
    """f = 1.3 Omega: every sideband separable; f = 1.5 Omega: |f - 2 Omega| = f - Omega (the mirror of a negative
    tone), so order -2 is not; f = 2 Omega (on a shaft harmonic): every sideband falls on a harmonic (1X, 3X, 4X) or
    on 0 Hz."""
    om = 16.0
    t0 = tone_set(1.3 * om, om, ORDERS, 1.3 * om / 64)
    assert all(t0.requested[k] >= 0 for k in ORDERS)
    t1 = tone_set(1.5 * om, om, ORDERS, 1.5 * om / 64)
    assert t1.requested[-2] == -1 and all(t1.requested[k] >= 0 for k in (-1, 1, 2))
    t2 = tone_set(2 * om, om, ORDERS, 2 * om / 64)
    assert all(t2.requested[k] == -1 for k in ORDERS)


@pytest.mark.slow
def test_time_integration_of_a_time_periodic_rotor_gives_the_simulators_sidebands() -> None:
    """dK(t) = dK0 (1 + cos Omega t) / 2 integrated in time (DOP853), the samples fitted, referenced to the shaft and
    divided by the force, against the phasor path (the dense harmonic balance oracle's tones, the simulator's
    sidebands); t_start 0.137 s makes every point start at another shaft angle."""
    m = np.diag([0.9, 0.75, 0.6])
    k = 1e5 * np.array([[1.6, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.5]])
    c = 2e-5 * k + 3.0 * m
    b, cout = np.array([0.0, 0.0, 1.0]), np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    speed_hz = 1000 / 60
    om = 2 * np.pi * speed_hz
    dk0 = np.zeros((3, 3))
    dk0[:2, :2] = -0.2e5 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    f = np.array([40.0, 55.0])  # every sideband apart from the other tones by more than f / 16
    sigma = c.max() / 0.9
    st = StepSettings(n_periods=16, settle_s=10 * np.log(10) / (0.5 * sigma), samples_per_period=32,
                      t_start_s=0.137, sideband_orders=ORDERS)
    td = simulate_time_domain(m, c, k, b, cout, f, st, keep_records=True,
                              stiffness_perturbation=lambda t: dk0 * (1 + np.cos(om * t)) / 2)
    fast = simulate_fast(harmonic_balance_plant(m, c, k, {0: dk0 / 2, 1: dk0 / 4, -1: dk0 / 4}, speed_hz, b, cout, 6),
                         f, st, speed_rpm=1000.0)
    assert td.records is not None and fast.sidebands is not None
    for j, rec in enumerate(td.records):
        settle = round(rec.tau.size / 32 - 16)
        tau, y = rec.tau[settle * 32:], rec.y[settle * 32:]
        tones = tone_set(f[j], speed_hz, ORDERS, f[j] / 16)
        amp, _ = fit_tones(y, tau, tones)
        theta = om * rec.t0_s
        s_time = np.array([amp[tones.requested[kk]] * np.exp(-1j * kk * theta) for kk in ORDERS])
        s_fast = fast.sidebands.phasor[j]
        assert np.all(np.isfinite(s_fast))
        scale = np.abs(s_fast).max()
        assert scale > 1e-3 * np.abs(fast.output_phasor[j]).max()  # the sidebands are there to compare
        # 4e-5 measured: 5e-8 of the main line, the integration's tolerance and the settling's residue
        assert np.abs(s_time - s_fast).max() < 1e-4 * scale


def _rig_sweep(angle: float, fault: str | None, noise: float = 1.0, seed: int = 4) -> Run:
    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    st = step_settings(cfg)
    st = dataclasses.replace(st, sideband_orders=ORDERS, output_noise_std=st.output_noise_std * noise)
    sw = simulate_rig(cfg, np.array([35.0, 48.0, 61.0, 95.0, 150.0]), 1000.0, fault=fault, seed=seed, settings=st,
                      shaft_angle_rad=angle)
    return next(iter(sw.runs.values()))


def test_shaft_referenced_sidebands_do_not_depend_on_the_start_angle() -> None:
    """The bundled truth rig's breathing crack, noise-free, the shaft at 0 and at 2.1 rad when the sweep starts:
    the same sideband receptances (the reference removes exp(j k theta)); unreferenced they would differ by the
    factor exp(2.1 j k), up to 180 deg. Measured: 3e-4 of the largest sideband, the leak of the harmonic balance's
    orders 5-8 (not in the fit's design; they turn with the shaft too)."""
    a, b = _rig_sweep(0.0, "breathing_crack", 0.0), _rig_sweep(2.1, "breathing_crack", 0.0)
    sa, sb = a.sideband_frf(), b.sideband_frf()
    assert sa is not None and sb is not None
    scale = np.nanmax(np.abs(sa[0]))
    assert scale > 0
    np.testing.assert_allclose(sb[0], sa[0], rtol=0, atol=1e-3 * scale)
    assert np.nanmax(np.abs(sb[0] - sa[0] * np.exp(2.1j * np.array(ORDERS))[None, :, None, None])) > 0.3 * scale


def test_healthy_rotor_sidebands_are_noise_and_the_main_results_do_not_change() -> None:
    """A time-invariant rotor: noise-free sidebands are 0 (beside the main line's 1e-12); with noise
    2|S|^2/var is chi2(2) (KS test); asking for sidebands leaves every other number of the sweep as it was."""
    quiet = _rig_sweep(0.7, None, 0.0)
    s0 = quiet.sideband_frf()
    assert s0 is not None
    assert np.nanmax(np.abs(s0[0])) < 1e-12 * np.abs(quiet.frf).max()
    z = []
    for seed in range(6):
        r = _rig_sweep(0.7, None, 1.0, seed)
        s = r.sideband_frf()
        assert s is not None
        ok = np.isfinite(s[0])
        z.extend((2 * np.abs(s[0][ok]) ** 2 / s[1][ok]).tolist())
    assert stats.kstest(z, stats.chi2(2).cdf).pvalue > 1e-3
    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    grid = np.array([35.0, 48.0, 61.0])
    plain = simulate_rig(cfg, grid, 1000.0, seed=9, shaft_angle_rad=0.7)
    with_sb = simulate_rig(cfg, grid, 1000.0, seed=9, shaft_angle_rad=0.7,
                           settings=dataclasses.replace(step_settings(cfg), sideband_orders=ORDERS))
    ra, rb = next(iter(plain.runs.values())), next(iter(with_sb.runs.values()))
    np.testing.assert_array_equal(ra.output_phasor, rb.output_phasor)
    np.testing.assert_array_equal(ra.output_var, rb.output_var)
    assert not ra.has_sidebands and rb.has_sidebands


def _sweep(run: Run) -> Sweep:
    return Sweep("crack_rig", "simulated", "test", "2026-01-01T00:00:00Z", list(CHANNELS[:2]), {run.run_id: run})


def _small_run(speed: float = 1000.0) -> Run:
    f = np.array([10.0, 20.0, 30.0])
    run = Run.from_phasors("r1", speed, f, np.ones((3, 1)), np.full((3, 1), 1e-6 + 0j), np.full((3, 1), 1e-14), 8)
    ph = np.full((3, 1, 2, 1), 2e-8 + 1e-8j)
    var = np.full((3, 1, 2, 1), 1e-16)
    ph[1, 0, 0, 0] = var[1, 0, 0, 0] = np.nan
    return run.with_sidebands(np.array([-1, 1]), ph, var)


def test_version_3_round_trip_and_older_versions_keep_their_number(tmp_path) -> None:
    run = _small_run()
    p = tmp_path / "v3.h5"
    write_sweep(_sweep(run), p)
    import h5py

    with h5py.File(p) as h5:
        assert int(h5.attrs["schema_version"]) == 3
    back = read_sweep(p).runs["r1"]
    np.testing.assert_array_equal(back.sideband_order, [-1, 1])
    np.testing.assert_array_equal(back.sideband_phasor_exc, run.sideband_phasor_exc)
    np.testing.assert_array_equal(back.sideband_var_exc, run.sideband_var_exc)
    plain = Run.from_phasors("r1", 1000.0, run.frequency, np.ones((3, 1)), np.full((3, 1), 1e-6 + 0j),
                             np.full((3, 1), 1e-14), 8)
    write_sweep(_sweep(plain), tmp_path / "v1.h5")
    with h5py.File(tmp_path / "v1.h5") as h5:
        assert int(h5.attrs["schema_version"]) == 1


@pytest.mark.parametrize("change, where, words", [
    (lambda r: setattr(r, "sideband_order", np.array([0, 1], dtype=np.int32)), "sideband_order", "nonzero"),
    (lambda r: setattr(r, "sideband_var_exc", np.asarray(r.sideband_var_exc)[:2]), "sideband_var", "wrong shape"),
    (lambda r: np.asarray(r.sideband_var_exc).__setitem__((0, 0, 0, 0), np.nan), "sideband_var", "NaN in one"),
    (lambda r: np.asarray(r.sideband_var_exc).__setitem__((0, 0, 1, 0), -1.0), "sideband_var", "> 0"),
    (lambda r: setattr(r, "sideband_phasor_exc", None), "sideband_phasor", "missing dataset"),
    (lambda r: setattr(r, "speed_rpm", 0.0), "sideband_order", "standstill"),
])
def test_bad_sidebands_are_refused_naming_the_dataset(tmp_path, change, where, words) -> None:
    run = _small_run()
    change(run)
    with pytest.raises(SweepFormatError) as e:
        write_sweep(_sweep(run), tmp_path / "bad.h5")
    assert f"/runs/r1/{where}" in str(e.value) and words in str(e.value)
    assert not (tmp_path / "bad.h5").exists()
