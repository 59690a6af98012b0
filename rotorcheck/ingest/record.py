"""The common time-record type every reader returns: named channels, sample rate (Hz), start time (s).

A channel is anything that slices like a 1-D array (a numpy array, a memory map, an h5py dataset, a
streaming TDMS channel, a CSV column read on demand), so a record larger than memory is read step by
step: :meth:`TimeRecord.read` returns only the samples asked for. Several contiguous records (one
sweep written in several files) are joined in time order by :func:`concatenate`.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from rotorcheck.errors import InputError

__all__ = ["Column", "ConcatColumn", "TimeRecord", "concatenate"]


class Column(Protocol):
    """One channel's samples: ``len`` and slicing ``[start:stop]`` to a 1-D array."""

    def __len__(self) -> int: ...

    def __getitem__(self, key: slice) -> Any: ...


@dataclass
class TimeRecord:
    """A uniformly sampled multi-channel record: sample ``i`` of every channel is at ``t0_s + i / fs_hz`` (s).

    ``channels``: name -> samples (raw units of the file, e.g. V or A); ``path``: the file(s) read
    (for messages); ``close``: releases open files (call once done; also via ``with``).
    """

    path: str
    fs_hz: float
    t0_s: float
    channels: Mapping[str, Column]
    close_fns: list[Callable[[], None]] = field(default_factory=list, repr=False)

    @property
    def n_samples(self) -> int:
        """Samples per channel (all channels have the same length)."""
        return min((len(c) for c in self.channels.values()), default=0)

    @property
    def t_end_s(self) -> float:
        """Time just after the last sample, s."""
        return self.t0_s + self.n_samples / self.fs_hz

    def column(self, name: str) -> Column:
        """The channel ``name``; an InputError naming the file and the channels present if absent."""
        if name not in self.channels:
            have = ", ".join(sorted(self.channels)) or "none"
            raise InputError(self.path, f"channel {name!r}", f"not in the record (channels: {have})")
        return self.channels[name]

    def read(self, names: Sequence[str], start: int, stop: int) -> np.ndarray:
        """Samples ``start:stop`` of the channels ``names`` as a (len(names), n) float64 array."""
        start, stop = max(0, int(start)), min(int(stop), self.n_samples)
        out = np.empty((len(names), max(0, stop - start)))
        for k, name in enumerate(names):
            out[k] = np.asarray(self.column(name)[start:stop], dtype=np.float64).reshape(-1)
        return out

    def close(self) -> None:
        """Close the files behind the channels."""
        for fn in self.close_fns:
            fn()
        self.close_fns.clear()

    def __enter__(self) -> TimeRecord:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class ConcatColumn:
    """Several columns end to end (slicing reads only the parts touched)."""

    def __init__(self, parts: Sequence[Column]):
        self.parts = list(parts)
        self.ends = np.cumsum([len(p) for p in self.parts])

    def __len__(self) -> int:
        return int(self.ends[-1]) if len(self.ends) else 0

    def __getitem__(self, key: slice) -> np.ndarray:
        start, stop, _ = key.indices(len(self))
        pieces = []
        begin = 0
        for part, end in zip(self.parts, self.ends):
            lo, hi = max(start, begin), min(stop, int(end))
            if lo < hi:
                pieces.append(np.asarray(part[lo - begin : hi - begin], dtype=np.float64).reshape(-1))
            begin = int(end)
        return np.concatenate(pieces) if pieces else np.empty(0)


def concatenate(records: Sequence[TimeRecord], tol_samples: float = 0.5) -> list[TimeRecord]:
    """Records of one sweep in time order, contiguous ones joined.

    Records that overlap in time, or differ in sample rate or channel names, are refused
    (InputError naming the files and the time). A gap (the next record starts more than
    ``tol_samples`` samples after the previous one ends) starts a new segment: the analysis treats
    segments separately and refuses a step across a gap.
    """
    if not records:
        return []
    recs = sorted(records, key=lambda r: r.t0_s)
    segments: list[list[TimeRecord]] = [[recs[0]]]
    for prev, cur in itertools.pairwise(recs):
        if not np.isclose(prev.fs_hz, cur.fs_hz, rtol=1e-9, atol=0.0):
            raise InputError(cur.path, "sample rate", f"{cur.fs_hz:g} Hz differs from {prev.path}'s "
                                                      f"{prev.fs_hz:g} Hz (one sweep needs one sample rate)")
        if set(prev.channels) != set(cur.channels):
            raise InputError(cur.path, "channels", f"{sorted(cur.channels)} differ from {prev.path}'s "
                                                   f"{sorted(prev.channels)}")
        step = (cur.t0_s - prev.t_end_s) * cur.fs_hz
        if step < -tol_samples:
            raise InputError(cur.path, f"t = {cur.t0_s:.6f} s",
                             f"starts before {prev.path} ends ({prev.t_end_s:.6f} s): records overlap")
        if step > tol_samples:
            segments.append([cur])
        else:
            segments[-1].append(cur)
    out = []
    for seg in segments:
        if len(seg) == 1:
            out.append(seg[0])
            continue
        cols: dict[str, Column] = {n: ConcatColumn([r.channels[n] for r in seg]) for n in seg[0].channels}
        closers = [fn for r in seg for fn in r.close_fns]
        out.append(TimeRecord(" + ".join(r.path for r in seg), seg[0].fs_hz, seg[0].t0_s, cols, closers))
    return out
