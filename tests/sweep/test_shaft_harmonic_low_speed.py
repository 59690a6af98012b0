"""The shaft-harmonic fit at very low speeds, where the harmonics' ratios nearly coincide with the mean's."""

from __future__ import annotations

import numpy as np

from rotorcheck.signal.lockin import shaft_harmonic_fit


def test_variance_never_negative_at_low_shaft_speed() -> None:
    """120 fits at shaft speeds 0.01-2 Hz (near-dependent regressors): every variance finite and >= 0
    (inverting the Gram matrix gave 3 negative ones on these draws)."""
    rng = np.random.default_rng(0)
    for shaft in np.geomspace(0.01, 2.0, 40):
        for f in (30.0, 31.7, 45.3):
            x = 1e-6 * (1 + 0.3j) + 1e-8 * (rng.normal(size=64) + 1j * rng.normal(size=64))
            _, var, dof = shaft_harmonic_fit(x, f, shaft, 4)
            assert np.isfinite(var) and var >= 0.0 and dof > 0


def test_variance_is_the_least_squares_formula_when_well_conditioned() -> None:
    """At 1000 rpm and 47.3 Hz: var = s^2 [(A^H A)^-1]_00 with A the mean and 1X..4X regressors, written
    out here, and the mean the first least-squares coefficient."""
    rng = np.random.default_rng(1)
    n, f, shaft = 64, 47.3, 1000.0 / 60.0
    x = 2e-6 + 1e-7 * (rng.normal(size=n) + 1j * rng.normal(size=n))
    p = np.arange(n)
    cols = [np.ones(n, complex)]
    for k in range(1, 5):
        z = np.exp(2j * np.pi * k * shaft / f)
        cols += [z**p, np.conj(z) ** p]
    A = np.stack(cols, axis=1)
    coef = np.linalg.lstsq(A, x, rcond=None)[0]
    s2 = np.sum(np.abs(x - A @ coef) ** 2) / (n - A.shape[1])
    ref = s2 * np.real(np.linalg.inv(A.conj().T @ A)[0, 0])
    mean, var, dof = shaft_harmonic_fit(x, f, shaft, 4)
    assert abs(mean - coef[0]) < 1e-12 * abs(coef[0])
    assert abs(var / ref - 1) < 1e-9
    assert dof == 2 * (n - 9)
