"""Stepped-sine simulator: exact FRF, noise statistics, fast path vs. time domain (oracle), 2X leak."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from sweep_helpers import CHANNELS, state_space_frf, three_mass

from rotorcheck.signal.lockin import white_noise_phasor_var
from rotorcheck.sim.simulator import StepSettings, Tone, matrix_plant, response_tones, simulate_fast
from rotorcheck.sweep import Sweep, read_sweep, write_sweep
from tests.oracles.hb import harmonic_balance_plant
from tests.oracles.time_domain import simulate_time_domain

B1 = np.array([1.0, 0.0, 0.0])  # force at mass 1
C13 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # displacement of masses 1 and 3
GRID = np.array([0.7, 1.3, 2.0, 2.9, 4.0, 5.5, 7.9])  # Hz, three-mass range 0.5-8 Hz


def _settle_s(m: np.ndarray, c: np.ndarray, k: np.ndarray, decades: float) -> float:
    """Time (s) for the slowest mode to decay by ``decades`` decades."""
    n = m.shape[0]
    minv = np.linalg.inv(m)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    sigma = -np.max(np.linalg.eigvals(a).real)
    return float(decades * np.log(10) / sigma)


def test_noiseless_time_domain_lockin_returns_exact_frf() -> None:
    m, c, k = three_mass()
    st = StepSettings(
        n_periods=8, settle_s=_settle_s(m, c, k, 14), samples_per_period=48, force_amplitude=2.5
    )
    res = simulate_time_domain(m, c, k, B1, C13, GRID, st)
    truth = np.array([state_space_frf(m, c, k, B1, C13, f) for f in GRID])
    frf = res.output_phasor / res.input_phasor
    err = np.abs(frf - truth).max() / np.abs(truth).max()
    assert err < 1e-9, err
    np.testing.assert_allclose(res.input_phasor, 2.5, rtol=1e-13)
    fast = simulate_fast(matrix_plant(m, c, k, B1, C13), GRID, st)
    assert np.abs(fast.output_phasor / fast.input_phasor - truth).max() / np.abs(truth).max() < 1e-12
    # noiseless: the period-to-period scatter is rounding only
    assert np.all(np.sqrt(res.output_var) < 1e-9 * np.abs(res.output_phasor))


def _rotor_like() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A 3-DOF stand-in with modes near 40-200 Hz, force at DOF 3, displacement at DOF 2."""
    m = np.diag([0.9, 0.75, 0.6])
    k = 1e5 * np.array([[1.6, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.5]])
    c = 2e-5 * k + 3.0 * m
    return m, c, k, np.array([0.0, 0.0, 1.0]), np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


@pytest.mark.parametrize("method", ["exact", pytest.param("ode", marks=pytest.mark.slow)])
def test_time_domain_equals_fast_path_with_synchronous_disturbances(method: str) -> None:
    m, c, k, b, cout = _rotor_like()
    speed = 1000 / 60
    dist_force = [
        Tone(speed, np.array([0.05, 0.0, 0.0]) * np.exp(0.3j)),  # 1X unbalance force (N)
        Tone(2 * speed, np.array([0.0, 0.0, 0.02j])),  # 2X misalignment force (N)
    ]
    f = np.array([30.0, 33.0, 47.3, 120.0]) if method == "exact" else np.array([33.0, 120.0])
    st = StepSettings(
        n_periods=16,
        settle_s=_settle_s(m, c, k, 10),
        samples_per_period=32,
        force_amplitude=lambda fr: 0.8 + 0.001 * fr,
        t_start_s=0.25,
        dwell_s=0.01,
    )
    td = simulate_time_domain(m, c, k, b, cout, f, st, disturbances=dist_force, method=method)
    fast = simulate_fast(
        matrix_plant(m, c, k, b, cout), f, st, disturbances=response_tones(m, c, k, cout, dist_force)
    )
    scale = np.abs(fast.output_phasor).max()
    err = np.abs(td.output_phasor - fast.output_phasor).max() / scale
    assert err < 1e-6, err
    np.testing.assert_allclose(td.input_phasor, fast.input_phasor, rtol=1e-12)
    np.testing.assert_array_equal(td.t0_s, fast.t0_s)
    # the disturbance is visible: the lock-in differs from the plain FRF near 2X (33 Hz)
    h = fast.output_phasor / fast.input_phasor
    h0 = np.array([state_space_frf(m, c, k, b, cout, x) for x in f])
    assert np.abs(h - h0)[1].max() > 1e-3 * np.abs(h0[1]).max()


@pytest.mark.slow
def test_time_varying_stiffness_hook_matches_harmonic_balance() -> None:
    """dK(t) = dK0 (1 + cos Omega t)/2 (breathing-like) through the hook vs. harmonic balance."""
    m, c, k, b, cout = _rotor_like()
    speed = 1000 / 60
    om = 2 * np.pi * speed
    dk0 = np.zeros((3, 3))
    dk0[:2, :2] = -0.2e5 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    dk_fourier = {0: dk0 / 2, 1: dk0 / 4, -1: dk0 / 4}
    f = np.array([30.0, 55.0])
    st = StepSettings(n_periods=8, settle_s=_settle_s(m, c, k, 10), samples_per_period=32, t_start_s=0.137)
    td = simulate_time_domain(
        m, c, k, b, cout, f, st, stiffness_perturbation=lambda t: dk0 * (1 + np.cos(om * t)) / 2
    )
    fast = simulate_fast(harmonic_balance_plant(m, c, k, dk_fourier, speed, b, cout, 6), f, st)
    err = np.abs(td.output_phasor - fast.output_phasor).max() / np.abs(fast.output_phasor).max()
    assert err < 1e-6, err
    # time-periodic: each period's phasor varies (sidebands leak), unlike the LTI plant
    assert np.max(td.output_var) > 0


def test_scatter_of_mean_matches_stored_variance_chi_square() -> None:
    """Over many seeds: e = mean - truth is circular complex Gaussian with E|e|^2 = s2 = 4 sigma^2 /
    (M N). With the true s2, sum 2|e|^2/s2 over all points and seeds ~ chi2(2 n). With the stored
    (estimated) variance v, |e|^2 / v ~ F(2, 2N - 2) per point (KS test)."""
    m, c, k = three_mass()
    plant = matrix_plant(m, c, k, B1, C13)
    sigma, mm, nper = 2e-6, 32, 16
    st = StepSettings(n_periods=nper, samples_per_period=mm, output_noise_std=sigma, input_noise_std=0.0)
    truth = np.array([state_space_frf(m, c, k, B1, C13, f) for f in GRID])
    errs, vars_ = [], []
    for seed in range(300):
        r = simulate_fast(plant, GRID, st, rng=seed)
        errs.append(r.output_phasor - truth)
        vars_.append(r.output_var)
    e2 = np.abs(np.array(errs)) ** 2
    v = np.array(vars_)
    s2 = white_noise_phasor_var(sigma, mm) / nper
    n = e2.size
    chi = float(np.sum(2 * e2 / s2))
    p_chi = 2 * min(stats.chi2.cdf(chi, 2 * n), stats.chi2.sf(chi, 2 * n))
    assert p_chi > 1e-3, (chi, 2 * n, p_chi)
    p_ks = stats.kstest((e2 / v).ravel(), stats.f(2, 2 * nper - 2).cdf).pvalue
    assert p_ks > 1e-3, p_ks
    assert np.mean(v) / s2 == pytest.approx(1.0, abs=0.02)  # unbiased variance of the mean
    assert np.mean(e2) / np.mean(v) == pytest.approx(1.0, abs=0.05)


def test_stored_variance_falls_as_one_over_n() -> None:
    m, c, k = three_mass()
    plant = matrix_plant(m, c, k, B1, C13)
    sigma, mm = 1e-6, 16
    ns = np.array([4, 8, 16, 32, 64, 128, 256])
    mean_var = []
    for n in ns:
        st = StepSettings(n_periods=int(n), samples_per_period=mm, output_noise_std=sigma)
        mean_var.append(np.mean([simulate_fast(plant, GRID, st, rng=s).output_var for s in range(100)]))
    slope, _ = np.polyfit(np.log(ns), np.log(mean_var), 1)
    assert slope == pytest.approx(-1.0, abs=0.03), slope
    # and the level: 4 sigma^2 / (M N) at every N (1400 values each, <= 1.6 % standard error)
    level = np.array(mean_var) * ns / white_noise_phasor_var(sigma, mm)
    np.testing.assert_allclose(level, 1.0, atol=0.06)


def test_time_domain_noise_matches_phasor_noise_formula() -> None:
    """White noise per sample in the time-domain run gives the per-period phasor scatter
    E|n|^2 = 4 sigma^2 / M assumed by the fast path (and by its input-noise model)."""
    m, c, k = three_mass()
    sigma, sig_in, mm = 3e-6, 0.01, 12
    st = StepSettings(
        n_periods=400,
        settle_s=_settle_s(m, c, k, 10),
        samples_per_period=mm,
        output_noise_std=sigma,
        input_noise_std=sig_in,
    )
    r = simulate_time_domain(m, c, k, B1, C13, np.array([6.0, 7.5]), st, rng=5)
    ratio_out = r.output_var * 400 / white_noise_phasor_var(sigma, mm)
    ratio_in = r.input_var * 400 / white_noise_phasor_var(sig_in, mm)
    # each ratio is an average of 400 (scaled) exponential variables: std 5 %
    np.testing.assert_allclose(ratio_out, 1.0, atol=0.2)
    np.testing.assert_allclose(ratio_in, 1.0, atol=0.2)


def test_deterministic_and_to_run_roundtrip(tmp_path) -> None:
    m, c, k, b, cout = _rotor_like()
    st = StepSettings(
        n_periods=8, samples_per_period=16, output_noise_std=1e-8, input_noise_std=1e-3, keep_periods=True
    )
    plant = matrix_plant(m, c, k, b, cout)
    f = np.linspace(30, 600, 20)
    a = simulate_fast(plant, f, st, rng=42)
    b2 = simulate_fast(plant, f, st, rng=np.random.default_rng(42))
    np.testing.assert_array_equal(a.output_phasor, b2.output_phasor)
    run = a.to_run("healthy_1000rpm", 1000.0, CHANNELS)
    sw = Sweep("crack_rig", "simulated", "test", "2024-01-01T00:00:00Z", list(CHANNELS), {run.run_id: run})
    write_sweep(sw, tmp_path / "s.h5")
    back = read_sweep(tmp_path / "s.h5").runs["healthy_1000rpm"]
    np.testing.assert_array_equal(back.period_phasor[:, :, 0], a.period_input[:, :, 0])
    np.testing.assert_array_equal(back.output_var, a.output_var)


def test_2x_leak_peaks_near_33hz_and_decays() -> None:
    """Healthy LTI rotor plus a 2X (33.33 Hz at 1000 rpm) misalignment response: the lock-in error
    |measured - H F| peaks where the excitation meets 2X and decays away from it."""
    m, c, k, b, cout = _rotor_like()
    speed = 1000 / 60
    d = 0.05e-6  # 2X response amplitude at the sensor (m)
    plant = matrix_plant(m, c, k, b, cout)
    dist = [Tone(2 * speed, np.array([d * np.exp(0.4j), 0.0]))]
    f = np.round(np.arange(28.0, 40.0001, 0.05), 10)
    st = StepSettings(n_periods=64, settle_periods=8, samples_per_period=32, force_amplitude=1.0)
    r = simulate_fast(plant, f, st, disturbances=dist)
    h = np.array([state_space_frf(m, c, k, b, cout, x) for x in f])
    err = np.abs(r.output_phasor[:, 0] - h[:, 0])
    i_peak = int(np.argmax(err))
    assert abs(f[i_peak] - 2 * speed) <= 0.05
    assert err[i_peak] > 0.9 * d
    df = np.abs(f - 2 * speed)
    # envelope of the averaged leak: |D| / (N |sin(pi df / f)|) (Dirichlet kernel over N periods)
    env = d / (64 * np.abs(np.sin(np.pi * df / f)))
    far = df > 0.5
    assert np.all(err[far] <= 1.05 * env[far] + 1e-3 * d)
    bands = [np.max(err[(df >= lo) & (df < lo + 1.0)]) for lo in (0.5, 1.5, 2.5, 3.5, 4.5)]
    assert all(bands[i] > bands[i + 1] for i in range(len(bands) - 1)), bands
    assert bands[-1] < 0.05 * d
    # without the disturbance there is no error
    clean = simulate_fast(plant, f, st)
    assert np.abs(clean.output_phasor[:, 0] - h[:, 0]).max() < 1e-12 * np.abs(h).max()
