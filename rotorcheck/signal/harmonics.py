r"""Grid points of a stepped-sine sweep that sit on a shaft harmonic (1X .. 4X): the lock-in cannot tell
the excitation's response there from the rotor's own unbalance response and its harmonics.

Rule. A lock-in that integrates over ``T`` seconds passes every tone within about its equivalent noise
bandwidth ``1/T`` of the reference (the rectangular window's main lobe: a tone ``delta`` Hz away enters
with weight ``sinc(delta T)``, first null at ``delta = 1/T``; :func:`rotorcheck.signal.lockin.tone_lockin`).
A stepped-sine point at ``f`` Hz averaged over ``N`` excitation periods integrates ``T = N / f`` s, so its
resolution is

    r(f) = 1 / T = f / N                                                   (Hz)

and the point is **flagged for order k** (k = 1 .. :data:`~rotorcheck.signal.lockin.SHAFT_ORDERS`) when

    |f - k n / 60| < r(f)          (n: shaft speed, rpm; k n / 60 in Hz)

(strict: at ``|f - k n/60| = 1/T`` the tone sits on the first null and is rejected; fitting the harmonics
out of the per-period phasors, :func:`~rotorcheck.signal.lockin.shaft_harmonic_fit`, separates them only
where their per-period rotation ``2 pi (f - k n/60) T`` is well away from 0, i.e. outside the same lobe).
At standstill nothing is flagged. Where several orders qualify the nearest is named.

A sweep that does not say how many periods a point averaged (an FRF-only import) is read with
:data:`DEFAULT_PERIODS` periods, and the flags say so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorcheck.signal.lockin import SHAFT_ORDERS

__all__ = ["DEFAULT_PERIODS", "ShaftHarmonics", "lockin_resolution_hz", "shaft_harmonic_points"]

#: periods assumed averaged per point when a sweep does not store them (the dissertation's rig and the
#: bundled samples average 64; rigs.md)
DEFAULT_PERIODS = 64


def lockin_resolution_hz(frequency_hz: np.ndarray, n_periods: np.ndarray | None) -> tuple[np.ndarray, bool]:
    """The lock-in resolution ``r = f / N`` (Hz) of each point (f,) and whether any point fell back to
    :data:`DEFAULT_PERIODS` (``n_periods`` None, or a point's ``N <= 0``)."""
    f = np.asarray(frequency_hz, dtype=float)
    n = np.zeros(f.shape) if n_periods is None else np.asarray(n_periods, dtype=float).reshape(f.shape)
    missing = ~(n > 0)
    n = np.where(missing, float(DEFAULT_PERIODS), n)
    return f / n, bool(np.any(missing))


@dataclass(frozen=True)
class ShaftHarmonics:
    """Which points of a grid sit on a shaft harmonic (see the module's rule).

    ``frequency_hz`` (f,) Hz; ``order`` (f,) int: the order k each point is flagged for (0: not flagged);
    ``offset_hz`` (f,): ``f - k n/60`` for the nearest order (Hz); ``resolution_hz`` (f,): ``r = f / N``;
    ``speeds_rpm``: the shaft speeds checked (a new sweep and its baseline); ``assumed_periods``: True
    when ``N`` was not in the sweep and :data:`DEFAULT_PERIODS` was used."""

    frequency_hz: np.ndarray
    order: np.ndarray
    offset_hz: np.ndarray
    resolution_hz: np.ndarray
    speeds_rpm: tuple[float, ...]
    assumed_periods: bool = False

    @property
    def flagged(self) -> np.ndarray:
        """(f,) bool: the points flagged."""
        return np.asarray(self.order > 0)

    @property
    def n_flagged(self) -> int:
        return int(np.count_nonzero(self.flagged))

    def points(self) -> list[dict[str, float | int]]:
        """The flagged points as records: frequency, order k, harmonic k n/60, offset and resolution (Hz)."""
        return [{"frequency_hz": float(self.frequency_hz[j]), "order": int(self.order[j]),
                 "harmonic_hz": float(self.frequency_hz[j] - self.offset_hz[j]),
                 "offset_hz": float(self.offset_hz[j]), "resolution_hz": float(self.resolution_hz[j])}
                for j in np.flatnonzero(self.flagged)]

    def warning(self, kept_out: str = "") -> str:
        """One sentence naming every flagged point, its order and why ('' when none); ``kept_out``: what the
        caller kept them out of."""
        if not self.n_flagged:
            return ""
        speeds = " and ".join(f"{s:g} rpm ({s / 60.0:.4g} Hz)" for s in self.speeds_rpm)
        pts = ", ".join(f"{p['frequency_hz']:.4g} Hz ({p['order']}X = {p['harmonic_hz']:.4g} Hz, "
                        f"{abs(p['offset_hz']):.3g} Hz off)" for p in self.points())
        r = self.resolution_hz[self.flagged]
        how = (f"N = {DEFAULT_PERIODS} periods assumed: the sweep does not say how many it averaged"
               if self.assumed_periods else "N the periods each point averaged")
        rule = (f"within the lock-in's resolution f/N ({r.min():.3g}-{r.max():.3g} Hz; {how}) of a shaft "
                f"harmonic kX, k = 1..{SHAFT_ORDERS}, at {speeds}")
        what = "there the lock-in measures the unbalance response and its harmonics as well as the FRF"
        tail = f"; kept out of {kept_out}" if kept_out else ""
        return f"{self.n_flagged} point{'s' if self.n_flagged > 1 else ''} {rule}: {pts}; {what}{tail}"


def shaft_harmonic_points(frequency_hz: np.ndarray, speed_rpm: float | tuple[float, ...],
                          resolution_hz: np.ndarray | float, orders: int = SHAFT_ORDERS,
                          assumed_periods: bool = False) -> ShaftHarmonics:
    """Flag the points of ``frequency_hz`` (f,) Hz with ``|f - k n/60| < resolution_hz`` for some
    ``k = 1..orders`` (module rule); ``speed_rpm``: one speed or several (a point counts when it is flagged
    at any; its nearest harmonic over all of them is reported); ``resolution_hz``: per point or one value."""
    f = np.asarray(frequency_hz, dtype=float).reshape(-1)
    r = np.broadcast_to(np.asarray(resolution_hz, dtype=float), f.shape).copy()
    speeds = tuple(float(s) for s in np.atleast_1d(np.asarray(speed_rpm, dtype=float)))
    order = np.zeros(f.size, dtype=int)
    offset = np.full(f.size, np.inf)
    for s in speeds:
        shaft = abs(s) / 60.0
        if shaft == 0.0:
            continue
        for k in range(1, orders + 1):
            d = f - k * shaft
            hit = (np.abs(d) < r) & (np.abs(d) < np.abs(offset))
            order[hit], offset[hit] = k, d[hit]
    offset = np.where(order > 0, offset, np.nan)
    return ShaftHarmonics(f, order, offset, r, speeds, assumed_periods)
