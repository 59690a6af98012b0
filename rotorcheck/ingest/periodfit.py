r"""Per-period phasors by a least-squares sinusoid fit with a DC term, slow drift removed.

Why a fit and not the lock-in sum of :func:`rotorcheck.signal.lockin.lockin_periods`: a rig's sample
clock is not locked to the excitation, so ``fs / f`` is not an integer and a lock-in over a
non-integer number of samples leaks DC, drift and the image at ``-f`` into the phasor. Over the
``L = floor(fs / f)`` samples that start at the first sample of period ``p`` (inside the period, so
windows never overlap and the noise of different periods stays independent) the model

    x(t_i) = a cos(w tau_i) + b sin(w tau_i) + c + d_p (tau_i - mean tau),   tau_i = i / fs,

is fitted by least squares; it is exact for a sine of any phase plus an offset and a linear drift
whatever ``L`` is. The window's local phasor ``a - j b`` is turned to the step's time reference
``t_ref`` by ``exp(-j w (t_p - t_ref))`` (``t_p`` the window's first sample time), so a steady sine
``Re{X exp(j w (t - t_ref))}`` gives ``X`` in every period. All windows of a step share one design,
so one precomputed pseudo-inverse (3 x L) serves every period and channel: the samples are gathered
into (channels, periods, L) and multiplied once.

The drift slope ``d_p`` is not a free column of each window's fit: over one period a ramp is
strongly correlated with ``sin`` (correlation ~0.8), so a free slope would make the phasor noise
non-circular (``Var b`` ~2.5x ``Var a``), against the circular Gaussian noise the detection assumes.
Instead the slope comes from the per-period DC values ``c_p`` of the whole step (a quadratic in time,
its derivative at each period; estimated from all the step's samples, so its noise is negligible),
and its known leak into ``(a, b)`` (``pinv @ (tau - mean tau)``) is subtracted.

White noise of std ``sigma`` per sample gives circular per-period phasor noise of about
``4 sigma^2 / L``; the sweep's variance comes from the period scatter, not from this formula.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PeriodDesign", "fit_windows", "period_design", "remove_drift", "window_starts"]


@dataclass(frozen=True)
class PeriodDesign:
    """The shared least-squares design of a step's windows: ``L`` samples at ``fs_hz``, tone ``f_hz``;
    ``slope_leak``: what a unit ramp (1/s, centred) adds to the fitted ``(a, b, c)``."""

    f_hz: float
    fs_hz: float
    length: int
    design: np.ndarray  # (L, 3): cos, sin, 1
    pinv: np.ndarray  # (3, L)
    slope_leak: np.ndarray  # (3,)


def period_design(f_hz: float, fs_hz: float) -> PeriodDesign:
    """The design and its pseudo-inverse for windows of ``floor(fs/f)`` samples (at least 5)."""
    length = int(np.floor(fs_hz / f_hz + 1e-9))
    if length < 5:
        raise ValueError(f"{fs_hz:g} Hz sampling gives {length} samples per period of {f_hz:g} Hz (need >= 5)")
    tau = np.arange(length) / fs_hz
    w = 2.0 * np.pi * f_hz
    a = np.stack([np.cos(w * tau), np.sin(w * tau), np.ones(length)], axis=1)
    pinv = np.linalg.pinv(a)
    return PeriodDesign(f_hz, fs_hz, length, a, pinv, pinv @ (tau - tau.mean()))


def window_starts(t_first_s: float, n_periods: int, f_hz: float, rec_t0_s: float, fs_hz: float) -> np.ndarray:
    """Index (int64, from the record's first sample) of the first sample at or after each period start
    ``t_first_s + p / f``."""
    t = t_first_s + np.arange(n_periods) / f_hz
    return np.ceil((t - rec_t0_s) * fs_hz - 1e-6).astype(np.int64)


def fit_windows(block: np.ndarray, offsets: np.ndarray, des: PeriodDesign,
                residual_rows: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Local phasors and DC values (channels, periods) of the windows starting at ``offsets`` (indices
    into ``block``, (channels, n)) and, for the first ``residual_rows`` channels, the RMS residual of
    the fit (rows, periods; NaN except on up to 16 periods); phasors in the windows' own frame, drift not yet removed
    (:func:`remove_drift`)."""
    idx = offsets[:, None] + np.arange(des.length)[None, :]
    win = block[:, idx]  # (ch, P, L)
    coef = win @ des.pinv.T  # (ch, P, 3)
    ph = coef[..., 0] - 1j * coef[..., 1]
    res = None
    if residual_rows:  # on at most 16 periods spread over the chunk (a check, not an estimate)
        sel = np.unique(np.linspace(0, offsets.size - 1, min(16, offsets.size)).astype(int))
        r = win[:residual_rows, sel] - coef[:residual_rows, sel] @ des.design.T
        res = np.full((residual_rows, offsets.size), np.nan)
        res[:, sel] = np.sqrt(np.mean(r * r, axis=-1))
    return ph, coef[..., 2], res


def remove_drift(ph: np.ndarray, dc: np.ndarray, t_mid: np.ndarray, des: PeriodDesign,
                 t_all: np.ndarray | None = None) -> np.ndarray:
    """Local phasors (channels, periods) with the ramp's leak removed: the slope (units/s) from a
    quadratic fit of the DC values ``dc`` against the period mid times ``t_mid`` (s), evaluated at
    every period's mid time ``t_all`` (default ``t_mid``; periods left out of the fit, e.g. clipped)."""
    n = t_mid.size
    if n < 3:
        return ph
    t_eval = t_mid if t_all is None else t_all
    t0 = t_mid.mean()
    deg = 2 if n >= 6 else 1
    van = np.vander(t_mid - t0, deg + 1, increasing=True)  # (P, deg+1)
    coef = np.linalg.lstsq(van, dc.T, rcond=None)[0]  # (deg+1, ch)
    tc = t_eval - t0
    slope = coef[1][:, None] + (2.0 * coef[2][:, None] * tc[None, :] if deg == 2 else 0.0)  # (ch, P)
    leak = des.slope_leak[0] - 1j * des.slope_leak[1]
    return ph - slope * leak
