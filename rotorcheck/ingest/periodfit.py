r"""Per-period phasors by a least-squares sinusoid fit with DC and slope terms.

Why a fit and not the lock-in sum of :func:`rotorcheck.signal.lockin.lockin_periods`: a rig's sample
clock is not locked to the excitation, so ``fs / f`` is not an integer and a lock-in over a
non-integer number of samples leaks DC, drift and the image at ``-f`` into the phasor. Over the
``L = floor(fs / f)`` samples that start at the first sample of period ``p`` (inside the period, so
windows never overlap and the noise of different periods stays independent) the model

    x(t_i) = a cos(w tau_i) + b sin(w tau_i) + c + d (tau_i - mean tau),   tau_i = i / fs,

is fitted by least squares; it is exact for a sine of any phase plus an offset and a linear drift
whatever ``L`` is. The window's local phasor ``a - j b`` is turned to the step's time reference
``t_ref`` by ``exp(-j w (t_p - t_ref))`` (``t_p`` the window's first sample time), so a steady sine
``Re{X exp(j w (t - t_ref))}`` gives ``X`` in every period. All windows of a step share one design,
so one precomputed pseudo-inverse (4 x L) serves every period and channel: the samples are gathered
into (channels, periods, L) and multiplied once.

White noise of std ``sigma`` per sample gives per-period phasor noise of about ``4 sigma^2 / L``
(slightly more for the DC and slope terms); the sweep's variance comes from the period scatter, not
from this formula.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PeriodDesign", "fit_windows", "period_design", "window_starts"]


@dataclass(frozen=True)
class PeriodDesign:
    """The shared least-squares design of a step's windows: ``L`` samples at ``fs_hz``, tone ``f_hz``."""

    f_hz: float
    fs_hz: float
    length: int
    design: np.ndarray  # (L, 4): cos, sin, 1, centred time
    pinv: np.ndarray  # (4, L)


def period_design(f_hz: float, fs_hz: float) -> PeriodDesign:
    """The design and its pseudo-inverse for windows of ``floor(fs/f)`` samples (at least 5)."""
    length = int(np.floor(fs_hz / f_hz + 1e-9))
    if length < 5:
        raise ValueError(f"{fs_hz:g} Hz sampling gives {length} samples per period of {f_hz:g} Hz (need >= 5)")
    tau = np.arange(length) / fs_hz
    w = 2.0 * np.pi * f_hz
    a = np.stack([np.cos(w * tau), np.sin(w * tau), np.ones(length), tau - tau.mean()], axis=1)
    return PeriodDesign(f_hz, fs_hz, length, a, np.linalg.pinv(a))


def window_starts(t_first_s: float, n_periods: int, f_hz: float, rec_t0_s: float, fs_hz: float) -> np.ndarray:
    """Index (int64, from the record's first sample) of the first sample at or after each period start
    ``t_first_s + p / f``."""
    t = t_first_s + np.arange(n_periods) / f_hz
    return np.ceil((t - rec_t0_s) * fs_hz - 1e-6).astype(np.int64)


def fit_windows(block: np.ndarray, offsets: np.ndarray, des: PeriodDesign,
                residual_rows: int = 0) -> tuple[np.ndarray, np.ndarray | None]:
    """Local phasors (channels, periods) of the windows starting at ``offsets`` (indices into
    ``block``, (channels, n)) and, for the first ``residual_rows`` channels, the RMS residual of the
    fit per period (rows, periods); the phasors are in the windows' own frame (see the module docstring)."""
    idx = offsets[:, None] + np.arange(des.length)[None, :]
    win = block[:, idx]  # (ch, P, L)
    coef = win @ des.pinv.T  # (ch, P, 4)
    ph = coef[..., 0] - 1j * coef[..., 1]
    res = None
    if residual_rows:
        r = win[:residual_rows] - coef[:residual_rows] @ des.design.T
        res = np.sqrt(np.mean(r * r, axis=-1))
    return ph, res
