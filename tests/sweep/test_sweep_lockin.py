"""Lock-in: exactness, closed-form multi-tone lock-in, white-noise phasor statistics."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from rotorcheck.signal.lockin import (
    average_periods,
    lockin_periods,
    tone_lockin,
    white_noise_phasor_var,
)


@pytest.mark.parametrize("m", [3, 4, 7, 64])
def test_single_tone_exact(m: int) -> None:
    f, t0, x_true = 33.0, 0.4321, 1.7e-6 * np.exp(0.9j)
    fs = m * f
    t = t0 + np.arange(5 * m) / fs
    x = np.real(x_true * np.exp(2j * np.pi * f * t))
    ph = lockin_periods(x, fs, f, t0)
    assert ph.shape == (5,)
    np.testing.assert_allclose(ph, x_true, rtol=1e-13, atol=0)


def test_dc_and_harmonics_rejected_exactly() -> None:
    m, f = 8, 50.0
    t = np.arange(4 * m) / (m * f)
    x = (
        3.0
        + np.cos(2 * np.pi * 2 * f * t + 0.3)
        + 0.5 * np.sin(2 * np.pi * 6 * f * t)
        + np.cos(2 * np.pi * f * t)
    )
    np.testing.assert_allclose(lockin_periods(x, m * f, f), 1.0, atol=1e-14)


def test_refuses_non_integer_samples_per_period() -> None:
    with pytest.raises(ValueError, match="integer"):
        lockin_periods(np.zeros(100), 1000.0, 33.0)


def _multi_tone() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(7)
    freqs = np.array([33.0, 1000 / 60, 2000 / 60, 3000 / 60, 0.0, 250.3, -5.5, 33.0 + 1000 / 60])
    amps = rng.standard_normal((freqs.size, 2)) + 1j * rng.standard_normal((freqs.size, 2))
    return freqs, amps


@pytest.mark.parametrize("m", [3, 16, 64, 257])
def test_tone_lockin_equals_numerical_lockin_of_samples(m: int) -> None:
    freqs, amps = _multi_tone()
    f, t0, p = 33.0, 12.345, 9
    t = t0 + np.arange(p * m) / (m * f)
    x = np.real(np.exp(2j * np.pi * np.outer(t, freqs)) @ amps)  # (samples, 2)
    numeric = lockin_periods(x, m * f, f, t0)
    closed = tone_lockin(freqs, amps, f, t0, p, samples_per_period=m)
    assert closed.shape == (p, 2)
    err = np.abs(closed - numeric).max() / np.abs(numeric).max()
    assert err < 1e-12, err


def test_tone_lockin_continuous_equals_quadrature_of_definition() -> None:
    freqs, amps = _multi_tone()
    amps = amps[:, 0]
    f, t0, p = 33.0, 0.77, 3
    w, period = 2 * np.pi * f, 1 / f

    def x(t: float) -> float:
        return float(np.real(np.sum(amps * np.exp(2j * np.pi * freqs * t))))

    ref = []
    for k in range(p):
        a, b = t0 + k * period, t0 + (k + 1) * period
        re = quad(lambda t: x(t) * np.cos(w * t), a, b, epsabs=1e-14, epsrel=1e-13, limit=200)[0]
        im = quad(lambda t: -x(t) * np.sin(w * t), a, b, epsabs=1e-14, epsrel=1e-13, limit=200)[0]
        ref.append(2 / period * (re + 1j * im))
    closed = tone_lockin(freqs, amps, f, t0, p)
    np.testing.assert_allclose(closed, np.array(ref), rtol=0, atol=1e-11 * np.abs(ref).max())


def test_average_periods_matches_numpy_variance() -> None:
    rng = np.random.default_rng(3)
    x = rng.standard_normal((50, 4)) + 1j * rng.standard_normal((50, 4))
    mean, var, n = average_periods(x)
    np.testing.assert_allclose(mean, x.mean(axis=0), rtol=1e-15)
    np.testing.assert_allclose(var, np.var(x, axis=0, ddof=1) / 50, rtol=1e-13)
    assert n == 50


@pytest.mark.parametrize("m", [3, 8, 64])
def test_white_noise_phasor_distribution(m: int) -> None:
    """Lock-in of white noise (std sigma per sample, M samples/period): circular complex Gaussian,
    E|n|^2 = 4 sigma^2 / M, Re and Im each 2 sigma^2 / M, uncorrelated."""
    sigma, f, p = 0.3, 40.0, 40000
    rng = np.random.default_rng(11 + m)
    w = sigma * rng.standard_normal(p * m)
    n = lockin_periods(w, m * f, f, 0.123)
    expected = 4 * sigma**2 / m
    assert white_noise_phasor_var(sigma, m) == pytest.approx(expected)
    tol = 5 / np.sqrt(p)  # 5 standard errors of a sample mean of an exponential variable
    assert np.mean(np.abs(n) ** 2) / expected == pytest.approx(1, abs=tol)
    assert np.var(n.real) / (expected / 2) == pytest.approx(1, abs=2 * tol)
    assert np.var(n.imag) / (expected / 2) == pytest.approx(1, abs=2 * tol)
    assert abs(np.mean(n * n)) / expected < tol  # circular: pseudo-covariance ~ 0
    # independent between periods
    r = np.mean(n[1:] * np.conj(n[:-1])) / expected
    assert abs(r) < tol
