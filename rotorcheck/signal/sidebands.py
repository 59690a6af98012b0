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

Shaft reference. The fit's phasors are in the point's local time; :func:`shaft_referenced` multiplies the
sideband of order ``k`` by ``exp(-j k theta)``, ``theta`` the shaft angle (rad, key-phasor mark 0) at
``tau = 0``, so that a linear time-periodic rotor gives the same phasor whatever angle the shaft had when the
point began (the sweep contract's version 3).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rotorcheck.signal.lockin import SHAFT_ORDERS

__all__ = ["FITTED_ORDERS", "ToneSet", "fit_tones", "point_times", "shaft_referenced", "tone_covariance", "tone_design",
           "tone_phasors", "tone_set", "tone_variance"]

#: sideband orders always fitted (requested or not): a breathing crack's response holds them, and a tone
#: left out of the design leaks into the ones fitted
FITTED_ORDERS = 4


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
    return tone_phasors(coef, tones), tone_covariance(tau_s, tones, drift_degree)[:, None] * s2[None, :]


def tone_covariance(tau_s: np.ndarray, tones: ToneSet, drift_degree: int = 0) -> np.ndarray:
    """``E|dB_g|^2 / sigma^2`` (g,) of the fit at local times ``tau_s`` (s) (white noise, unit variance per
    sample; a drift of degree ``drift_degree`` fitted too)."""
    x = tone_design(tau_s, tones.freq_hz, drift_degree)
    return tone_variance(np.linalg.inv(x.T @ x), tones)


def shaft_referenced(phasor: np.ndarray, orders: Sequence[int], theta_rad: float) -> np.ndarray:
    """Sideband phasors (..., K, c) of ``orders`` (K,) times ``exp(-j k theta)``: referenced to the shaft angle
    ``theta_rad`` (rad) at the point's local time 0."""
    k = np.asarray(orders, dtype=float)
    return np.asarray(phasor) * np.exp(-1j * k * float(theta_rad))[:, None]
