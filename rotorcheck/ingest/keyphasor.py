"""The keyphasor: once-per-revolution pulses -> shaft angle (rad) and speed (rpm).

Pulses are the rising crossings of ``threshold`` (default: the median plus half the height of the
first block, i.e. mid-way up a pulse), with hysteresis a fifth of the height. Repairs: an interval of
about twice the median revolution (1.7-2.3x) between normal ones is one missed pulse (one inserted
mid-way); an interval shorter than 0.7x whose sum with the next is about one revolution is a double
pulse (the extra one dropped). Anything else irregular, or repairs that are not isolated, is refused
(InputError naming the file, the channel and the time). The shaft angle between pulses is linear in
time (2 pi per revolution, 0 at a pulse).
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass, field

import numpy as np

from rotorcheck.errors import InputError
from rotorcheck.ingest.crossings import rising_crossings
from rotorcheck.ingest.record import TimeRecord

__all__ = ["Pulses", "find_pulses", "repair_pulses"]

#: height over the noise (robust std) below which a block holds no pulses
MIN_PULSE_SNR = 10.0


@dataclass
class Pulses:
    """Pulse times (s) after repair, and what was repaired (text lines for the run notes)."""

    times: np.ndarray
    repairs: list[str] = field(default_factory=list)

    @functools.cached_property
    def period_s(self) -> float:
        """Median revolution time, s."""
        return float(np.median(np.diff(self.times)))

    @property
    def speed_rpm(self) -> float:
        """Speed from the median revolution, rpm."""
        return 60.0 / self.period_s

    def angle(self, t: np.ndarray) -> np.ndarray:
        """Shaft angle (rad, unwrapped) at times ``t`` (s): linear between pulses, extrapolated with
        the median revolution beyond them."""
        k = np.arange(self.times.size, dtype=np.float64)
        t = np.asarray(t, dtype=np.float64)
        rev = np.interp(t, self.times, k)
        per = self.period_s
        rev = np.where(t < self.times[0], (t - self.times[0]) / per, rev)
        rev = np.where(t > self.times[-1], k[-1] + (t - self.times[-1]) / per, rev)
        return 2.0 * np.pi * rev

    def drift(self, t0: float, t1: float) -> float:
        """Relative spread (max - min) / median of the revolutions within [t0, t1] (0 with fewer than 2)."""
        inside = self.times[(self.times >= t0) & (self.times <= t1)]
        if inside.size < 3:
            return 0.0
        d = np.diff(inside)
        return float((d.max() - d.min()) / np.median(d))


def find_pulses(rec: TimeRecord, channel: str, threshold: float | None = None,
                block: int = 1 << 20) -> np.ndarray:
    """Rising-edge times (s, absolute) of the keyphasor channel, read block by block."""
    first = rec.read([channel], 0, block)[0]
    if first.size == 0:
        return np.empty(0)
    sub = first[:: max(1, first.size // 65536)]  # the level statistics from <= 64 k samples
    med = float(np.median(sub))
    height = float(first.max()) - med
    noise = 1.4826 * float(np.median(np.abs(sub - med)))
    if threshold is None:
        if height <= MIN_PULSE_SNR * max(noise, 1e-12 * max(abs(med), 1.0)):
            return np.empty(0)
        level, hyst = med + 0.5 * height, 0.2 * height
    else:
        level, hyst = float(threshold), 0.2 * max(abs(height), 1e-12)
    out = []
    armed = True
    for s in range(0, rec.n_samples, block):
        lo = max(0, s - 1)
        x = rec.read([channel], lo, s + block)[0]
        if x.size < 2:
            break
        t, armed = rising_crossings(x, rec.fs_hz, level, hyst, armed)
        out.append(rec.t0_s + lo / rec.fs_hz + t)
    return np.concatenate(out) if out else np.empty(0)


def repair_pulses(times: np.ndarray, path: str, channel: str, max_repairs: float = 0.02) -> Pulses:
    """Repair isolated missing or double pulses (see the module docstring); refuse the rest."""
    t = np.asarray(times, dtype=np.float64)
    where = f"channel {channel!r}"
    if t.size < 3:
        raise InputError(path, where, f"only {t.size} keyphasor pulse(s): cannot measure the speed")
    d = np.diff(t)
    med = float(np.median(d))
    r = d / med
    repairs: list[str] = []
    bad = np.flatnonzero((r < 0.7) | (r > 1.3))
    # doubles: a short interval whose sum with the next is one revolution -> drop the pulse between
    drop: list[int] = []
    insert: list[float] = []
    skip = set()
    for i in bad:
        if i in skip:
            continue
        if r[i] < 0.7 and i + 1 < r.size and abs(r[i] + r[i + 1] - 1.0) < 0.3:
            drop.append(i + 1)
            skip.add(i + 1)
            repairs.append(f"t = {t[i + 1]:.6f} s: double keyphasor pulse dropped")
        elif 1.7 <= r[i] <= 2.3:
            insert.append(0.5 * (t[i] + t[i + 1]))
            repairs.append(f"t = {t[i]:.6f} s: missing keyphasor pulse inserted")
        else:
            raise InputError(path, where, f"t = {t[i]:.6f} s: revolution of {d[i]:.6g} s against a median "
                                          f"{med:.6g} s is neither one missed nor one double pulse: refusing")
    n_fix = len(drop) + len(insert)
    if n_fix and (n_fix > max(1.0, max_repairs * d.size) or _adjacent(sorted(int(b) for b in bad), skip)):
        first = float(t[bad[0]])
        raise InputError(path, where, f"t = {first:.6f} s: {n_fix} irregular keyphasor revolutions of {d.size} "
                                      "(not isolated): refusing to repair")
    if drop:
        t = np.delete(t, drop)
    if insert:
        t = np.sort(np.concatenate([t, insert]))
    return Pulses(t, repairs)


def _adjacent(bad: list[int], pairs: set[int]) -> bool:
    """Two irregular intervals next to each other that are not one double pulse's pair."""
    return any(b - a == 1 and b not in pairs for a, b in itertools.pairwise(bad))
