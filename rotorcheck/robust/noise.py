"""Step 2: the noise bound V (m, output displacement, uniform in frequency).

Model: the averaged output phasor at each frequency point and output channel carries an error ``v``
that is complex circular Gaussian with ``E|v|^2 = var`` (m^2). Then ``|v|^2 / var`` is exponential
with mean 1 and ``P(|v| <= sqrt(var) sqrt(-ln(1 - p))) = p``. Over ``n`` independent points the
family-wise coverage ``P(all |v_k| <= V) >= 1 - alpha`` holds with the per-point level
``p = (1 - alpha)^(1/n)`` (Sidak; exact when all variances are equal) or ``p = 1 - alpha/n``
(Bonferroni, no independence needed, slightly larger V). ``V = max_k sqrt(var_k) sqrt(-ln(1-p))``
makes the bound uniform in frequency, as the validation LMI expects.

When ``var`` is itself estimated from ``K`` periods, ``|v|^2 / var_hat`` is F(2, 2(K-1))
distributed (independent numerator and denominator); pass ``n_periods`` to use that quantile
instead of the exponential one (wider for small K).

The dissertation (section 3.1) tuned V by hand to the noise floor of the data;
:func:`noise_bound_from_floor` automates that: a local polynomial (Savitzky-Golay) fit in frequency
separates the smooth FRF from the scatter, the scatter variance is estimated robustly (median of
``|r|^2``, corrected for the fit's own leverage) in a chosen band, and the same family-wise quantile
is applied.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "NoiseBound",
    "noise_bound_from_floor",
    "noise_bound_from_periods",
    "noise_bound_from_variance",
    "noise_bound_manual",
    "noise_bound_per_point",
    "phasor_mean_variance",
    "point_level",
]


@dataclass
class NoiseBound:
    """A noise bound: ``value_m`` (m), how it was obtained, the family-wise confidence it carries
    (None for a manual value) and method details (per-point level, counts, ...)."""

    value_m: float
    method: str
    confidence: float | None
    details: dict[str, Any] = field(default_factory=dict)


def point_level(confidence: float, n_points: int, family: str = "sidak") -> float:
    """Per-point coverage so that all ``n_points`` are covered with ``confidence``."""
    if not 0.0 < confidence < 1.0:
        raise ValueError("confidence must be in (0, 1)")
    if n_points < 1:
        raise ValueError("need at least one point")
    if family == "sidak":
        return float(confidence ** (1.0 / n_points))
    if family == "bonferroni":
        return float(1.0 - (1.0 - confidence) / n_points)
    if family == "none":
        return float(confidence)
    raise ValueError(f"family must be 'sidak', 'bonferroni' or 'none', got {family!r}")


def point_miss(confidence: float, n_points: int, family: str = "sidak") -> float:
    """``1 - point_level``, computed without cancellation (Sidak: ``-expm1(ln(confidence)/n)``)."""
    if family == "sidak":
        point_level(confidence, n_points, family)  # argument checks
        return float(-np.expm1(np.log(confidence) / n_points))
    return 1.0 - point_level(confidence, n_points, family)


def _exp_quantile(miss: float) -> float:
    """``q`` with ``P(|v| <= sqrt(var) q) = 1 - miss`` for a complex circular Gaussian v."""
    return float(np.sqrt(-np.log(miss)))


def _checked_variance(output_var: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """``(var, finite mask, number of finite points)``; negative variances are errors."""
    var = np.asarray(output_var, dtype=float)
    finite = np.isfinite(var)
    if np.any(var[finite] < 0):
        raise ValueError("variances must be >= 0")
    return var, finite, int(np.count_nonzero(finite))


def _quantile_factor(p: float, n_periods: int | None, miss: float | None = None) -> float:
    """``q`` with ``P(|v| <= sqrt(var) q) = p``: exponential, or F(2, 2(K-1)) for estimated var."""
    if n_periods is None:
        return _exp_quantile(1.0 - p if miss is None else miss)
    if n_periods < 2:
        raise ValueError("n_periods must be >= 2 to estimate a variance")
    nu = 2.0 * (n_periods - 1)  # F(2, nu) quantile in closed form: (nu/2) ((1 - p)^(-2/nu) - 1)
    m = 1.0 - p if miss is None else miss
    return float(np.sqrt(0.5 * nu * np.expm1(-2.0 / nu * np.log(m))))


def noise_bound_from_variance(output_var: np.ndarray, confidence: float = 0.99,
                              family: str = "sidak", n_periods: int | None = None
                              ) -> NoiseBound:
    """V from the per-point variance of the averaged output phasors.

    ``output_var``: ``(f, n_out)`` or ``(f,)``, ``E|v|^2`` of the averaged phasor error (m^2);
    NaN entries are ignored. ``n_periods``: number of periods the variance was estimated from (uses
    the F quantile), or None to treat the variance as known.
    """
    var, finite, n = _checked_variance(output_var)
    p = point_level(confidence, n, family)
    q = _quantile_factor(p, n_periods, point_miss(confidence, n, family))
    sd = np.sqrt(var[finite])
    value = float(sd.max() * q)
    return NoiseBound(value, "variance", confidence, {
        "family": family, "n_points": n, "point_level": p, "quantile_factor": q,
        "n_periods": n_periods, "max_sd_m": float(sd.max()), "median_sd_m": float(np.median(sd)),
        "argmax": int(np.flatnonzero(finite.ravel())[np.argmax(sd)]),
    })


def phasor_mean_variance(period_phasors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean over periods and the variance of that mean: ``period_phasors`` ``(f, K, ...)`` complex
    (m) -> ``(mean, var_of_mean)`` with ``var_of_mean = sum |x - mean|^2 / (K (K - 1))``."""
    X = np.asarray(period_phasors, dtype=complex)
    K = X.shape[1]
    if K < 2:
        raise ValueError("need at least two periods per point")
    mean = X.mean(axis=1)
    var = np.sum(np.abs(X - mean[:, None]) ** 2, axis=1) / (K * (K - 1))
    return mean, var


def noise_bound_from_periods(period_phasors: np.ndarray, confidence: float = 0.99,
                             family: str = "sidak") -> NoiseBound:
    """V from per-period output phasors ``(f, K, n_out)`` of the sweep (F quantile with K periods)."""
    _, var = phasor_mean_variance(period_phasors)
    nb = noise_bound_from_variance(var, confidence, family, n_periods=np.shape(period_phasors)[1])
    nb.method = "periods"
    return nb


def noise_bound_from_floor(output: np.ndarray, frequency_hz: np.ndarray,
                           band_hz: tuple[float, float] | None = None, window: int = 11,
                           order: int = 3, confidence: float = 0.99, family: str = "sidak"
                           ) -> NoiseBound:
    """V from the scatter of the measured output around a smooth local fit (the noise floor).

    ``output``: ``(f, n_out)`` or ``(f,)`` complex output phasors (m) on an increasing grid;
    ``band_hz``: frequency band where the scatter is estimated (default: all; choose a band where
    the response is smooth on the grid scale, e.g. the high-frequency floor). The residual of a
    Savitzky-Golay fit (``window`` points, polynomial ``order``, real and imaginary parts) has
    variance ``sigma^2 (1 - h0)`` with ``h0`` the filter's centre weight; ``sigma^2`` is estimated
    by ``median |r|^2 / ln 2 / (1 - h0)`` (robust to resonance leakage), per output channel.
    """
    Y = np.asarray(output, dtype=complex)
    Y = Y[:, None] if Y.ndim == 1 else Y
    fr = np.asarray(frequency_hz, dtype=float)
    if Y.shape[0] != fr.size:
        raise ValueError("output and frequency_hz lengths differ")
    if window % 2 == 0 or window <= order + 1 or window > fr.size:
        raise ValueError("window must be odd, larger than order + 1 and at most the point count")
    from scipy.signal import savgol_coeffs  # lazy: scipy.signal costs ~0.3 s to import: only here

    coeffs = savgol_coeffs(window, order)
    h0 = float(coeffs[window // 2])
    half = window // 2
    mask = np.ones(fr.size, dtype=bool) if band_hz is None else (
        (fr >= band_hz[0]) & (fr <= band_hz[1]))
    mask[:half] = False
    mask[fr.size - half:] = False
    if np.count_nonzero(mask) < 5:
        raise ValueError("too few interior points in the band to estimate the noise floor")
    sig2 = np.empty(Y.shape[1])
    for k in range(Y.shape[1]):
        sm = np.convolve(Y[:, k].real, coeffs, mode="same") + 1j * np.convolve(
            Y[:, k].imag, coeffs, mode="same")
        r2 = np.abs(Y[mask, k] - sm[mask]) ** 2
        sig2[k] = np.median(r2) / np.log(2.0) / (1.0 - h0)
    n = Y.shape[0] * Y.shape[1]
    p = point_level(confidence, n, family)
    q = _quantile_factor(p, None)
    value = float(np.sqrt(sig2.max()) * q)
    return NoiseBound(value, "floor", confidence, {
        "family": family, "n_points": n, "point_level": p, "quantile_factor": q,
        "sigma_m": np.sqrt(sig2).tolist(), "band_hz": band_hz, "window": window, "order": order,
        "leverage_h0": h0, "n_band_points": int(np.count_nonzero(mask)),
    })


def noise_bound_manual(value_m: float) -> NoiseBound:
    """A manual noise bound (m), e.g. the dissertation's 0.02 um."""
    if not np.isfinite(value_m) or value_m < 0:
        raise ValueError("noise bound must be finite and >= 0")
    return NoiseBound(float(value_m), "manual", None, {})


def noise_bound_pooled(output_var: np.ndarray, confidence: float = 0.99, family: str = "sidak",
                       n_periods: int | None = None) -> NoiseBound:
    """V from the noise level pooled over the points (uniform noise, method.md step 2).

    With N periods per point the stored variance of the mean is ``var_k ~ s^2 chi2(nu)/nu``,
    ``nu = 2 (N - 1)`` (complex scatter). The pooled ``s^2 = median(var) / (median chi2(nu) / nu)``
    is immune to the points whose scatter is inflated by synchronous-disturbance leaks (which a max
    over points would turn into a bound 10-50x too large); points beyond the excess level below
    are trimmed and the median re-pooled until the set is stable (at least a quarter kept); then
    ``V = s sqrt(-ln(1 - p))`` with ``p`` the per-point level for ``confidence`` family-wise over
    the points. Points whose variance exceeds ``s^2 chi2.ppf(p, nu)/nu`` (the same family-wise
    level) are listed in ``details["excess_scatter_index"]`` (flat indices).
    """
    from scipy.stats import chi2  # lazy: scipy.stats only for this bound

    var, finite, n = _checked_variance(output_var)
    p = point_level(confidence, n, family)
    flat = var.ravel()
    idx = np.flatnonzero(finite.ravel())
    if n_periods is not None and n_periods >= 2:
        nu = 2.0 * (n_periods - 1)
        med_ratio = float(chi2.median(nu) / nu)
        excess_ratio = float(chi2.ppf(p, nu) / nu)
    else:  # variance treated as known
        med_ratio, excess_ratio = 1.0, np.inf
    clean = idx
    s2 = float(np.median(flat[clean])) / med_ratio
    for _ in range(50):  # trim excess-scatter points and re-pool until the set is stable
        keep = idx[flat[idx] <= s2 * excess_ratio] if s2 > 0 else idx
        if keep.size < max(3, idx.size // 4) or np.array_equal(keep, clean):
            break
        clean = keep
        s2 = float(np.median(flat[clean])) / med_ratio
    value = float(np.sqrt(s2) * _exp_quantile(point_miss(confidence, n, family)))
    excess = np.setdiff1d(idx, clean) if clean.size < idx.size else np.zeros(0, dtype=int)
    return NoiseBound(value, "pooled", confidence, {
        "family": family, "n_points": n, "point_level": p, "pooled_sd_m": float(np.sqrt(s2)),
        "n_periods": n_periods, "excess_scatter_index": [int(i) for i in excess],
        "max_sd_m": float(np.sqrt(flat[idx].max())),
    })


def noise_bound_per_point(output_var: np.ndarray, dof: np.ndarray, confidence: float = 0.99,
                          family: str = "sidak") -> NoiseBound:
    """V(w) per point (m) from the stored variance of each averaged phasor and its own dof.

    ``output_var`` (f,) m^2, the estimated variance of the mean phasor; ``dof`` (f,) its real degrees
    of freedom (``2 (N - 1)`` for N periods, fewer after removing shaft harmonics). With the variance
    estimated, ``|v|^2 / var_hat ~ F(2, dof)`` exactly (complex circular Gaussian, independent
    periods), so ``V_k = sqrt(var_k F^-1(p; 2, dof_k))`` with the per-point level ``p`` for
    ``confidence`` family-wise (Sidak) holds with few periods and with the period count varying over
    the sweep (Monte Carlo in the tests). ``value_m`` is the largest V_k (a uniform fallback);
    ``details["per_point_m"]`` the array.
    """
    var, finite, n = _checked_variance(output_var)
    d = np.broadcast_to(np.asarray(dof, dtype=float), var.shape)
    if np.any(d[finite] <= 0):
        raise ValueError("degrees of freedom must be > 0")
    miss = point_miss(confidence, n, family)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q = np.where(np.isinf(d), -np.log(miss), 0.5 * d * np.expm1(-2.0 / d * np.log(miss)))
        per = np.sqrt(var * q)
    per = np.where(finite, per, np.nan)
    return NoiseBound(float(np.nanmax(per)), "per-point", confidence, {
        "family": family, "n_points": n, "point_miss": miss, "per_point_m": per,
        "median_m": float(np.nanmedian(per)),
    })
