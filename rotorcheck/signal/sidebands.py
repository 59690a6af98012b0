r"""Sidebands of a stepped-sine point on a rotating shaft: a least-squares fit of known tones.

A linear time-periodic rotor (a breathing crack) driven at ``f`` responds at ``f + k Omega`` as well
(``Omega = n / 60`` Hz, n the speed in rpm); a time-invariant rotor does not. The per-period lock-in of
:mod:`rotorcheck.signal.lockin` reads only ``f``; a sideband needs the record itself. Over the analysed
window of a point (``N`` excitation periods, ``M`` samples each, local time ``tau``) the record is fitted
by least squares with every tone it is known to hold::

    y(tau_i) = c + sum_g Re{B_g exp(j 2 pi g tau_i)} + noise,
    g in {f} u {|f + k Omega| : 0 < |k| <= K} u {j Omega : j = 1 .. SHAFT_ORDERS}

(``K = max(FITTED_ORDERS, max |requested order|)``), one cosine and one sine column per tone and a constant.
With white noise of variance ``sigma^2`` per sample the estimate's covariance is ``sigma^2 (X^T X)^-1``;
``B = a - j b`` (``a``, ``b`` the cosine and sine coefficients) has ``E|dB|^2 = var(a) + var(b)``, which for
tones well apart over the window is ``4 sigma^2 / (N M)``, the lock-in's. A negative ``f + k Omega`` is the
tone at ``|f + k Omega|`` with the conjugate phasor.

Separable. A tone closer than the window's resolution ``1 / T`` (``T = N / f`` s) to a tone fitted before
it (order of priority: the excitation, the shaft harmonics, then the sidebands by ``|k|``) is not fitted:
the window cannot tell the two apart. Its estimate is NaN.

Test. Without a crack each separable sideband receptance ``S`` (m/N) is complex Gaussian noise with the
fit's covariance; ``2 |S|^2 / var(S)`` summed over a point's ``n_j`` tones is ``u^T u`` for the normalised real
vector ``u`` (cosine and sine parts over ``sqrt(var/2)``), whose covariance ``W`` the window fixes: the tones of one
point are correlated where they are close (at 600 Hz, 64 periods are 0.107 s and the sidebands 16.7 Hz apart are
1.8 resolution widths apart: ``lambda_max(W)`` = 1.33). Since ``u^T u <= lambda_max(W) u^T W^-1 u`` and
``u^T W^-1 u ~ chi2(2 n_j)``, :func:`sideband_points` divides each point's sum by ``lambda_max(W)``
(:func:`correlation_scale`; the shaft reference and the conjugations are rotations and reflections of ``u``:
they leave the eigenvalues alone, so the stored phasors' angle is not needed): ``T_j`` is then at most
``chi2(2 n_j)`` in distribution, a conservative test.

Scan. :func:`sideband_scan` looks for sidebands where they are: a breathing crack's sidebands are strong near the
resonances that ``f`` or ``f + k Omega`` meets and absent elsewhere, so the sums over windows of
:data:`SCAN_WIDTHS` adjacent points (and over every point) are tested, each window's ``chi2`` p-value times the
number of windows tested (Bonferroni over windows and widths: valid whatever the dependence between windows, so
the stated false-alarm rate is an upper bound).

Shaft reference. The fit's phasors are in the point's local time; :func:`shaft_referenced` multiplies the
sideband of order ``k`` by ``exp(-j k theta)``, ``theta`` the shaft angle (rad, key-phasor mark 0) at
``tau = 0``, so that a linear time-periodic rotor gives the same phasor whatever angle the shaft had when the
point began (the sweep contract's version 3).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rotorcheck.lazy import lazy_module
from rotorcheck.signal.lockin import SHAFT_ORDERS

special = lazy_module("scipy.special")  # the chi-square tails

__all__ = [
    "COVARIANCE_SAMPLES",
    "FITTED_ORDERS",
    "HEALTHY_SIDEBAND_ALPHA",
    "SCAN_WIDTHS",
    "SidebandScan",
    "ToneSet",
    "correlation_scale",
    "correlation_scales",
    "fit_tones",
    "point_times",
    "requested_orders",
    "shaft_referenced",
    "sideband_points",
    "sideband_scan",
    "sideband_statistic",
    "tone_covariance",
    "tone_design",
    "tone_phasors",
    "tone_set",
    "tone_variance",
]

#: sideband orders always fitted (requested or not): a breathing crack's response holds them, and a tone
#: left out of the design leaks into the ones fitted
FITTED_ORDERS = 4
#: the widths (adjacent tested points) of the scan's windows; 0: every point (round 10: widths 2, 8, 32 and all
#: found 10-16 of 21 breathing cracks of 4 % depth with drift where the sum over every point alone found 5-14,
#: bench/results_sideband.md)
SCAN_WIDTHS = (2, 8, 32, 0)
#: samples per period with which the detector rebuilds the fit's covariance (the correlation between tones depends
#: on the window, N periods of f; the sampling changes it little once M f / 2 is above the highest tone)
COVARIANCE_SAMPLES = 16
#: the healthy sweeps' sidebands beyond noise at this rate: the healthy rotor is not time-invariant, and the
#: sideband test is not used against that baseline
HEALTHY_SIDEBAND_ALPHA = 0.01


@dataclass(frozen=True)
class ToneSet:
    """The tones fitted at one point: ``freq_hz`` (g,) Hz (>= 0), ``conj`` (g,) True where the tone is a
    negative ``f + k Omega`` (its phasor is the conjugate of the fitted one); ``requested`` maps each requested
    order to its tone's index in ``freq_hz`` (-1: not separable)."""

    freq_hz: np.ndarray
    conj: np.ndarray
    requested: dict[int, int]


def tone_set(f_hz: float, speed_hz: float, orders: Sequence[int], resolution_hz: float) -> ToneSet:
    """The tones of the module's fit at excitation ``f_hz`` and shaft frequency ``speed_hz`` (both Hz, > 0) for
    the requested sideband ``orders``; a tone within ``resolution_hz`` of one fitted before it is dropped."""
    k_max = max([FITTED_ORDERS, *[abs(int(k)) for k in orders]])
    cand: list[tuple[float, bool, int | None]] = [(f_hz, False, None)]
    cand += [(j * speed_hz, False, None) for j in range(1, SHAFT_ORDERS + 1)]
    for order in sorted({o for a in range(1, k_max + 1) for o in (-a, a)}, key=lambda o: (abs(o), o)):
        g0 = f_hz + order * speed_hz
        cand.append((abs(g0), g0 < 0, order))
    freqs: list[float] = []
    conj: list[bool] = []
    index: dict[int, int] = {}
    for g, c, k in cand:
        if g < resolution_hz or any(abs(g - h) < resolution_hz for h in freqs):
            if k is not None:
                index[k] = -1
            continue
        if k is not None:
            index[k] = len(freqs)
        freqs.append(g)
        conj.append(c)
    return ToneSet(np.asarray(freqs), np.asarray(conj, dtype=bool), {int(k): index[int(k)] for k in orders})


def point_times(f_hz: float, settle_periods: int, n_periods: int, samples_per_period: int) -> np.ndarray:
    """Local sample times (s) of a point's analysed window: ``N`` periods of ``1/f`` after ``settle_periods``,
    ``M`` samples per period."""
    m = int(samples_per_period)
    return (settle_periods + np.arange(n_periods * m) / m) / f_hz


def tone_design(tau_s: np.ndarray, freq_hz: np.ndarray, drift_degree: int = 0) -> np.ndarray:
    """The fit's design matrix (n, 1 + 2 g + d) at local times ``tau_s`` (n,) s: a constant, then
    ``cos(2 pi g tau)`` for each tone, then ``sin(2 pi g tau)``, then a slow drift (a probe's): the powers 1 .. d
    (``drift_degree``) of the time about the window's middle, scaled to the window."""
    tau = np.asarray(tau_s, dtype=float)
    ph = 2.0 * np.pi * np.outer(tau, freq_hz)
    span = max(float(np.ptp(tau)), 1e-300) if tau.size else 1.0
    drift = ((tau - tau.mean()) / span)[:, None] ** np.arange(1, drift_degree + 1)[None, :] if tau.size else \
        np.zeros((0, drift_degree))
    return np.concatenate([np.ones((ph.shape[0], 1)), np.cos(ph), np.sin(ph), drift], axis=1)


def tone_phasors(coef: np.ndarray, tones: ToneSet) -> np.ndarray:
    """The phasors (g, c) of the fit's coefficients (1 + 2 g [+ d], c): ``B = a - j b``, conjugated where
    ``tones.conj``."""
    g = tones.freq_hz.size
    amp = coef[1:1 + g] - 1j * coef[1 + g:1 + 2 * g]
    return np.asarray(np.where(tones.conj[:, None], np.conj(amp), amp))


def tone_variance(cov: np.ndarray, tones: ToneSet) -> np.ndarray:
    """``E|dB_g|^2`` (g,) from the coefficients' covariance (1 + 2 g [+ d] square): cosine plus sine variance."""
    g = tones.freq_hz.size
    d = np.diag(cov)
    return np.asarray(d[1:1 + g] + d[1 + g:1 + 2 * g])


def fit_tones(y: np.ndarray, tau_s: np.ndarray, tones: ToneSet, drift_degree: int = 0
              ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares phasors (g, c) of ``tones`` in the samples ``y`` (n, c) at local times ``tau_s`` (n,) s, with a
    drift of degree ``drift_degree`` fitted jointly, and their variances (g, c) from the residual's variance
    (``n - 1 - 2 g - d`` degrees of freedom); conjugated where ``tones.conj`` (the phasor of ``f + k Omega``
    itself)."""
    x = tone_design(tau_s, tones.freq_hz, drift_degree)
    yy = np.asarray(y, dtype=float).reshape(x.shape[0], -1)
    coef, *_ = np.linalg.lstsq(x, yy, rcond=None)
    dof = x.shape[0] - x.shape[1]
    s2 = np.sum((yy - x @ coef) ** 2, axis=0) / max(dof, 1)
    return tone_phasors(coef, tones), tone_variance(np.linalg.inv(x.T @ x), tones)[:, None] * s2[None, :]


def tone_covariance(tau_s: np.ndarray, tones: ToneSet, drift_degree: int = 0) -> np.ndarray:
    """``E|dB_g|^2 / sigma^2`` (g,) of the fit at local times ``tau_s`` (s) (white noise, unit variance per
    sample; a drift of degree ``drift_degree`` fitted too)."""
    x = tone_design(tau_s, tones.freq_hz, drift_degree)
    return tone_variance(np.linalg.inv(x.T @ x), tones)


def requested_orders(values: np.ndarray, tones: ToneSet, orders: Sequence[int]) -> np.ndarray:
    """The rows (K, ...) of ``values`` (g, ...; one row per fitted tone) that hold the requested ``orders``, NaN where
    an order was not separable."""
    v = np.asarray(values)
    dtype = np.result_type(v.dtype, np.float64)
    out = np.full((len(orders), *v.shape[1:]), np.nan + 1j * np.nan if dtype.kind == "c" else np.nan, dtype=dtype)
    for i, k in enumerate(orders):
        j = tones.requested[int(k)]
        if j >= 0:
            out[i] = v[j]
    return out


def shaft_referenced(phasor: np.ndarray, orders: Sequence[int], theta_rad: float) -> np.ndarray:
    """Sideband phasors (..., K, c) of ``orders`` (K,) times ``exp(-j k theta)``: referenced to the shaft angle
    ``theta_rad`` (rad) at the point's local time 0."""
    k = np.asarray(orders, dtype=float)
    return np.asarray(phasor) * np.exp(-1j * k * float(theta_rad))[:, None]


def correlation_scale(f_hz: float, speed_hz: float, orders: Sequence[int], n_periods: int,
                      samples: int = COVARIANCE_SAMPLES) -> float:
    """``lambda_max(W)`` at one point (module docstring): the largest eigenvalue of the normalised covariance of the
    separable ``orders``' cosine and sine estimates of the fit over ``n_periods`` periods of ``f_hz`` at shaft
    frequency ``speed_hz`` (Hz); 1 where no order is separable."""
    tones = tone_set(f_hz, speed_hz, orders, f_hz / n_periods)
    idx = [tones.requested[int(k)] for k in orders if tones.requested[int(k)] >= 0]
    if not idx:
        return 1.0
    x = tone_design(point_times(f_hz, 0, n_periods, samples), tones.freq_hz)
    cov = np.linalg.inv(x.T @ x)
    g = tones.freq_hz.size
    cols = [1 + i for i in idx] + [1 + g + i for i in idx]
    half = np.tile(tone_variance(cov, tones)[idx] / 2.0, 2)
    w = cov[np.ix_(cols, cols)] / np.sqrt(np.outer(half, half))
    return float(max(1.0, np.linalg.eigvalsh(w).max()))


def correlation_scales(frequency_hz: np.ndarray, speed_hz: float, orders: Sequence[int], n_periods: np.ndarray
                       ) -> np.ndarray:
    """:func:`correlation_scale` at every point (f,) (``n_periods`` (f,): the periods each point averaged)."""
    n = np.broadcast_to(np.asarray(n_periods), np.shape(frequency_hz))
    return np.array([correlation_scale(float(f), speed_hz, orders, int(k)) for f, k in zip(frequency_hz, n)])


def sideband_statistic(frf: np.ndarray, var: np.ndarray, frequency_hz: np.ndarray, speed_hz: float,
                       orders: Sequence[int], n_periods: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sideband_points` of the sideband receptances ``frf`` (f, ...) m/N and variances ``var`` (m/N)^2 of a
    run at ``frequency_hz`` (f,), shaft frequency ``speed_hz`` (Hz), ``n_periods`` (f,) a point, each point's sum
    divided by its :func:`correlation_scale` (the conservative chi-square the tests use)."""
    return sideband_points(frf, var, correlation_scales(frequency_hz, speed_hz, orders, n_periods))


def sideband_points(frf: np.ndarray, var: np.ndarray, scale: np.ndarray | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Per point (f,) the sum of ``2 |S|^2 / var`` over its separable tones divided by ``scale`` (f,) (the point's
    :func:`correlation_scale`; None: 1, tones taken as independent) and their count, from the sideband receptances
    ``frf`` (f, ...) m/N and variances ``var`` (f, ...) (m/N)^2 (NaN: left out)."""
    s = np.asarray(frf).reshape(np.shape(frf)[0], -1)
    v = np.asarray(var, dtype=float).reshape(s.shape)
    ok = np.isfinite(s) & np.isfinite(v) & (v > 0)
    z = np.where(ok, 2.0 * np.abs(np.where(ok, s, 0.0)) ** 2 / np.where(ok, v, 1.0), 0.0)
    t = z.sum(axis=1)
    return (t if scale is None else t / np.asarray(scale, dtype=float)), ok.sum(axis=1)


@dataclass(frozen=True)
class SidebandScan:
    """The scan over windows of adjacent points: ``p_value`` the smallest window p-value times the number of windows
    tested (at most 1); ``statistic`` (chi-square units) and ``dof`` of that window; ``points`` (start, stop) its
    indices into the points (stop exclusive); ``n_windows`` tested; ``n_tones`` over every point."""

    p_value: float
    statistic: float
    dof: int
    points: tuple[int, int]
    n_windows: int
    n_tones: int

    def threshold(self, alpha: float) -> float:
        """The statistic at which this window's adjusted p-value is ``alpha`` (chi-square units)."""
        return float(special.chdtri(self.dof, min(1.0, alpha / self.n_windows)))


def sideband_scan(t_point: np.ndarray, n_point: np.ndarray, widths: Sequence[int] = SCAN_WIDTHS) -> SidebandScan:
    """:data:`SCAN_WIDTHS` windows over the tested points (those with a separable tone; ``t_point``, ``n_point``
    from :func:`sideband_points`), each width slid by half its length (the last window ends at the last point;
    width 0 or wider than the points: every point), ``T ~ chi2(2 n)`` per window; Bonferroni over every window."""
    idx = np.flatnonzero(np.asarray(n_point) > 0)
    t, n = np.asarray(t_point, dtype=float)[idx], np.asarray(n_point, dtype=int)[idx]
    if idx.size == 0:
        return SidebandScan(1.0, 0.0, 0, (0, 0), 0, 0)
    ct = np.concatenate([[0.0], np.cumsum(t)])
    cn = np.concatenate([[0], np.cumsum(n)])
    best: tuple[float, float, int, int, int] = (np.inf, 0.0, 0, 0, 0)
    count = 0
    for w in sorted({idx.size if w <= 0 or w >= idx.size else int(w) for w in widths}):
        starts = np.arange(0, idx.size - w + 1, max(1, w // 2))
        if starts[-1] != idx.size - w:
            starts = np.append(starts, idx.size - w)
        tw, nw = ct[starts + w] - ct[starts], cn[starts + w] - cn[starts]
        p = special.chdtrc(2 * nw, tw)
        k = int(np.argmin(p))
        count += starts.size
        if p[k] < best[0]:
            best = (float(p[k]), float(tw[k]), int(2 * nw[k]), int(starts[k]), int(starts[k] + w))
    p_min, stat, dof, a, b = best
    return SidebandScan(min(1.0, p_min * count), stat, dof, (int(idx[a]), int(idx[b - 1]) + 1), count, int(n.sum()))
