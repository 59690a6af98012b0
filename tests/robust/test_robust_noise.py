"""Noise bound: Monte Carlo coverage of the family-wise bound, floor estimate, manual value."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.robust import noise


def binom_tol(p: float, n: int, z: float = 4.0) -> float:
    return z * np.sqrt(p * (1 - p) / n)


def circ(rng: np.random.Generator, sd: np.ndarray, n_draws: int) -> np.ndarray:
    """Complex circular Gaussian draws with E|v|^2 = sd^2, shape (n_draws, *sd.shape)."""
    shape = (n_draws, *sd.shape)
    return sd / np.sqrt(2) * (rng.normal(size=shape) + 1j * rng.normal(size=shape))


@pytest.mark.parametrize("family", ["sidak", "bonferroni"])
def test_family_wise_coverage_equal_variances(family: str) -> None:
    """Equal variances, 262 points x 1 output, 2000 draws: P(all |v_k| <= V) is the confidence
    (Sidak exactly, Bonferroni slightly above)."""
    rng = np.random.default_rng(0)
    conf, n_draws = 0.95, 2000
    sd = np.full((262, 1), 4e-9)
    nb = noise.noise_bound_from_variance(sd**2, confidence=conf, family=family)
    assert nb.details["n_points"] == 262
    v = circ(rng, sd, n_draws)
    covered = np.all(np.abs(v) <= nb.value_m, axis=(1, 2))
    cov = covered.mean()
    tol = binom_tol(conf, n_draws)
    print(f"\n{family}: V = {nb.value_m:.3e} m, empirical coverage {cov:.4f} (target {conf})")
    assert abs(cov - conf) < tol if family == "sidak" else conf - tol < cov < conf + 0.02
    # per-point level and exact theory
    p = nb.details["point_level"]
    assert p**262 == pytest.approx(conf, rel=1e-12) if family == "sidak" else True
    assert nb.value_m == pytest.approx(4e-9 * np.sqrt(-np.log(1 - p)), rel=1e-12)


def test_coverage_unequal_variances_is_at_least_the_confidence() -> None:
    rng = np.random.default_rng(1)
    sd = 1e-9 * rng.uniform(1, 5, size=(200, 2))
    nb = noise.noise_bound_from_variance(sd**2, confidence=0.9)
    v = circ(rng, sd, 2000)
    cov = np.all(np.abs(v) <= nb.value_m, axis=(1, 2)).mean()
    assert cov >= 0.9 - binom_tol(0.9, 2000)
    assert nb.details["n_points"] == 400


def test_estimated_variance_from_periods_F_quantile() -> None:
    """Variance estimated per point from K = 6 periods: with the F(2, 2(K-1)) quantile factor q the
    family-wise event {all k: |v_k| <= sd_hat_k q} has exactly the stated probability (the
    exponential quantile, which treats sd_hat as known, falls short); the uniform V = max_k
    sd_hat_k q covers at least as often."""
    rng = np.random.default_rng(2)
    f, K, n_draws, conf = 100, 6, 2000, 0.9
    hits_f = hits_exp = hits_v = 0
    for _ in range(n_draws):
        X = circ(rng, np.full((f, K, 1), 3e-9), 1)[0]
        mean, var = noise.phasor_mean_variance(X)
        nb = noise.noise_bound_from_periods(X, confidence=conf)
        q_exp = noise.noise_bound_from_variance(var, confidence=conf).details["quantile_factor"]
        sd_hat = np.sqrt(var)
        hits_f += bool(np.all(np.abs(mean) <= sd_hat * nb.details["quantile_factor"]))
        hits_exp += bool(np.all(np.abs(mean) <= sd_hat * q_exp))
        hits_v += bool(np.all(np.abs(mean) <= nb.value_m))
    cov_f, cov_exp, cov_v = hits_f / n_draws, hits_exp / n_draws, hits_v / n_draws
    print(f"\nK={K}: per-point-bound coverage with F quantile {cov_f:.3f}, with exponential "
          f"{cov_exp:.3f}; uniform V {cov_v:.3f} (target {conf})")
    assert abs(cov_f - conf) < binom_tol(conf, n_draws)
    assert cov_exp < conf - binom_tol(conf, n_draws)
    assert cov_v >= cov_f


def test_floor_estimate_recovers_sigma() -> None:
    rng = np.random.default_rng(3)
    fr = np.linspace(30, 600, 2000)
    smooth = 1e-6 / (1 + 1j * fr / 200) + 2e-7 * np.exp(-1j * fr / 100)
    sigma = 2e-9
    y = smooth + circ(rng, np.full(fr.size, sigma), 1)[0]
    nb = noise.noise_bound_from_floor(y, fr, band_hz=(300, 600), window=21, order=3,
                                      confidence=0.99)
    assert nb.details["sigma_m"][0] == pytest.approx(sigma, rel=0.1)
    p = nb.details["point_level"]
    assert nb.value_m == pytest.approx(nb.details["sigma_m"][0] * np.sqrt(-np.log(1 - p)), rel=1e-12)


def test_manual_and_errors() -> None:
    nb = noise.noise_bound_manual(2e-8)
    assert nb.value_m == 2e-8 and nb.method == "manual" and nb.confidence is None
    with pytest.raises(ValueError):
        noise.noise_bound_manual(-1.0)
    with pytest.raises(ValueError):
        noise.noise_bound_from_variance(np.ones(3), confidence=1.0)
    with pytest.raises(ValueError):
        noise.point_level(0.9, 10, "holm")
