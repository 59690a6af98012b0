"""ROSS bearings and seals: reading their coefficient lists, the interpolant ROSS builds from them
against rotor speed, the speed grid a rig table samples it at, and the rig's ``bearings`` entries.

ROSS's "frequency" of a bearing coefficient is the rotor speed (rad/s). Its interpolant (ROSS 2.3.0,
``BearingElement._process_coefficient``) is a cubic smoothing spline (``UnivariateSpline`` with its default
smoothing) for 4 or more speeds, a linear or quadratic ``interp1d`` for 2 or 3. A rig entry tabulates it
in rpm at ``speed_points`` evenly spaced speeds plus the saved ones, and extrapolates linearly outside
them (``extrapolate: linear``). Grounded bearings on one node are summed into one entry."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotorcheck.config import BEARING_TERMS, MAX_RIG_BYTES
from rotorcheck.errors import InputError
from rotorcheck.ross_import.layout import Layout
from rotorcheck.ross_import.tables import COSMETIC, RAD_S_TO_RPM, Table, listing, slug, unique_name

#: the lateral coefficients ROSS and rotorcheck share
LATERAL = BEARING_TERMS
#: ROSS's axial coefficients (not carried: the rig's model is lateral)
AXIAL = ("kzz", "czz", "mzz")
#: the keys of a ROSS bearing or seal table this import reads
BEARING_KEYS = frozenset({"n", "n_link", "frequency", "seal_leakage", *LATERAL, *AXIAL}) | COSMETIC
#: bearing classes that are nothing but their saved coefficients
PLAIN_BEARINGS = frozenset({"BearingElement", "SealElement"})

Interpolant = Callable[[np.ndarray], np.ndarray]


def _ross_interpolant(
    table: Table, key: str, freq: np.ndarray | None, values: np.ndarray
) -> tuple[Interpolant | None, str]:
    """ROSS's interpolant of one coefficient list against speed (rad/s): ``(None, "constant")`` for a
    single value or equal values, else ``(callable, kind)`` as ROSS 2.3.0's
    ``BearingElement._process_coefficient`` builds it."""
    if values.size == 1 or bool(np.all(values == values[0])):
        return None, "constant"
    if freq is None:
        raise table.error(key, f"{values.size} values but no frequency list (ROSS needs one per value)")
    from scipy import interpolate  # lazy: scipy only when a coefficient depends on speed

    if values.size >= 4:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                spline = interpolate.UnivariateSpline(freq, values)
        except Exception as exc:  # ROSS leaves such a coefficient without an interpolant
            raise table.error(key, f"ROSS cannot interpolate this list (UnivariateSpline: {exc})") from None
        return spline, "spline"
    f = interpolate.interp1d(freq, values, kind=values.size - 1, fill_value="extrapolate")
    return f, ("linear" if values.size == 2 else "quadratic")



@dataclass
class Bearing:
    """One ROSS bearing or seal as read: its nodes, saved speeds (rad/s), each coefficient's saved values
    (``raw``, SI units), ROSS's interpolant of each lateral one and the value of each constant one."""

    table: Table
    cls: str
    tag: str
    n: int
    n_link: int | None
    freq: np.ndarray | None
    interpolants: dict[str, tuple[Interpolant | None, str]]
    constants: dict[str, float]  # value of each constant coefficient
    raw: dict[str, np.ndarray]



def read_bearing(table: Table, cls: str, tag: str) -> Bearing:
    """A bearing or seal table (ROSS class ``cls``, tag ``tag``), checked, with ROSS's defaults
    (``kyy = kxx``, ``cyy = cxx``, ``myy = mxx``, the rest 0)."""
    n = table.integer("n")
    if n is None:
        raise table.error("n", "required field is missing")
    n_link = table.integer("n_link")
    if n_link is not None and n_link == n:
        raise table.error("n_link", f"links node {n} to itself")
    freq = table.numbers("frequency")
    if freq is not None and freq.size > 1 and bool(np.any(np.diff(freq) <= 0)):
        raise table.error("frequency", "must be strictly increasing (rotor speeds, rad/s)")
    raw: dict[str, np.ndarray] = {}
    for key in ("kxx", "cxx"):
        arr = table.numbers(key)
        if arr is None:
            raise table.error(key, "required field is missing")
        raw[key] = arr
    for key in (*LATERAL, *AXIAL):
        if key in raw:
            continue
        arr = table.numbers(key)
        if arr is None:  # ROSS's defaults: kyy = kxx, cyy = cxx, myy = mxx, the rest 0
            same = {"kyy": "kxx", "cyy": "cxx", "myy": "mxx"}.get(key)
            arr = raw[same].copy() if same is not None and same in raw else np.zeros(1)
        raw[key] = arr
    expected = freq.size if freq is not None and freq.size > 1 else 1
    for key, arr in raw.items():
        if arr.size > 1 and arr.size != expected:
            what = f"the {expected} speeds of frequency" if freq is not None else "a single value (no frequency list)"
            raise table.error(key, f"{arr.size} values, but {what}")
        if arr.size == 1 and expected > 1:
            raw[key] = np.full(expected, arr[0])
    interpolants = {key: _ross_interpolant(table, key, freq, raw[key]) for key in LATERAL}
    constants = {key: float(raw[key][0]) for key, (f, _) in interpolants.items() if f is None}
    return Bearing(table, cls, tag, n, n_link, freq, interpolants, constants, raw)


def _rpm(speed_rad_s: np.ndarray) -> np.ndarray:
    """rad/s -> rpm; speeds within 1e-12 of a whole rpm are rounded to it (6000.000000000001 -> 6000)."""
    rpm = speed_rad_s * RAD_S_TO_RPM
    whole = np.round(rpm)
    return np.where(np.abs(rpm - whole) <= 1e-12 * np.maximum(np.abs(rpm), 1.0), whole, rpm)


def _grid(members: Sequence[Bearing], speed_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Speeds of a tabulated entry, ``(rad/s, rpm)``: ``speed_points`` evenly spaced in rpm over the
    members' range, plus every saved speed; a lone 2-point (linear) table keeps its own 2 speeds."""
    tabulated = [b for b in members if b.freq is not None and any(f is not None for f, _ in b.interpolants.values())]
    assert tabulated
    saved = np.unique(np.concatenate([b.freq for b in tabulated if b.freq is not None]))
    saved_rpm = _rpm(saved)
    if len(members) == 1 and saved.size == 2:
        return saved, saved_rpm
    even_rpm = np.linspace(saved_rpm[0], saved_rpm[-1], speed_points)
    tol = 1e-9 * max(abs(saved_rpm[0]), abs(saved_rpm[-1]))
    near = np.abs(even_rpm[:, None] - saved_rpm[None, :]).min(axis=1) <= tol
    rpm = np.concatenate([saved_rpm, even_rpm[~near]])
    rad_s = np.concatenate([saved, even_rpm[~near] / RAD_S_TO_RPM])
    order = np.argsort(rpm, kind="stable")
    rpm, rad_s = rpm[order], rad_s[order]
    keep = np.r_[True, np.diff(rpm) > 0]  # distinct speeds in rpm (two saved lists may differ by rounding)
    return rad_s[keep], rpm[keep]


def _bearing_entry(
    members: Sequence[Bearing], station: int, n_link: int | None, name: str, speed_points: int
) -> tuple[dict[str, Any], list[str]]:
    """The rig entry of one bearing (or the sum of grounded ones on one node) and its notes."""
    entry: dict[str, Any] = {"name": name, "station": station}
    if n_link is not None:
        entry["n_link"] = n_link
    notes: list[str] = []
    tables = listing([b.table.path for b in members])
    tabulated = [k for k in LATERAL if any(b.interpolants[k][0] is not None for b in members)]
    grid, grid_rpm = _grid(members, speed_points) if tabulated else (np.zeros(0), np.zeros(0))
    values: dict[str, float | np.ndarray] = {}
    for key in LATERAL:
        if key not in tabulated:
            values[key] = float(sum(b.constants[key] for b in members))
            continue
        total = np.zeros(grid.size)
        for b in members:
            f = b.interpolants[key][0]
            total = total + (b.constants[key] if f is None else np.asarray(f(grid), dtype=float))
        values[key] = float(total[0]) if bool(np.all(total == total[0])) else total
    for key in ("cxx", "cyy", "mxx", "myy"):
        v = values[key]
        low = float(np.min(v))
        if low < 0:
            where = " (as ROSS interpolates it)" if isinstance(v, np.ndarray) else ""
            raise InputError(members[0].table.source, f"{members[0].table.path}.{key}",
                             f"{low:g}{where}: rotorcheck's bearings take direct {key} >= 0")
    rpm = [float(x) for x in grid_rpm]
    for key in LATERAL:
        v = values[key]
        if isinstance(v, np.ndarray):
            entry[key] = {"speed_rpm": rpm, "values": [float(x) for x in v]}
        elif v != 0.0 or key in ("kxx", "kyy"):
            entry[key] = v
    speed_keys = [k for k in LATERAL if isinstance(values[k], np.ndarray)]
    if speed_keys:
        kinds = sorted({b.interpolants[k][1] for b in members for k in speed_keys} - {"constant"})
        kind_text = {"spline": "cubic smoothing spline", "linear": "linear interpolant",
                     "quadratic": "quadratic interpolant"}
        smooth = 0.0
        for b in members:
            for k in speed_keys:
                f = b.interpolants[k][0]
                if f is not None and b.interpolants[k][1] == "spline" and b.freq is not None:
                    data = b.raw[k]
                    smooth = max(smooth, float(np.max(np.abs(f(b.freq) - data)) / np.max(np.abs(data))))
        fine = np.sort(np.concatenate([grid, *(grid[:-1] + np.diff(grid) * t for t in (0.25, 0.5, 0.75))]))
        worst = 0.0
        for k in speed_keys:
            exact = np.zeros(fine.size)
            for b in members:
                f = b.interpolants[k][0]
                exact = exact + (b.constants[k] if f is None else np.asarray(f(fine), dtype=float))
            lin = np.interp(fine, grid, np.asarray(values[k]))
            worst = max(worst, float(np.max(np.abs(lin - exact)) / max(np.max(np.abs(exact)), 1e-300)))
        sentence = (f"{tables}: speed-dependent {', '.join(speed_keys)} written as tables at {grid.size} speeds, "
                    f"{rpm[0]:.6g}-{rpm[-1]:.6g} rpm, sampled from ROSS's {' and '.join(kind_text[k] for k in kinds)}")
        if smooth > 0:
            sentence += f", which departs from the saved values by up to {smooth:.1e} of a coefficient's largest value"
        if len(members) > 1:
            sentence += ", each member's extrapolated over the combined range before summing"
        all_linear = all(b.interpolants[k][1] in ("linear", "constant") for b in members for k in speed_keys)
        sentence += (f"; linear in between (within {worst:.1e} of ROSS's curve, relative to a coefficient's largest "
                     "value) and, as ROSS extrapolates its interpolants outside the saved speeds, extrapolated "
                     "linearly from the end segments there (extrapolate: linear"
                     + (", exactly ROSS's linear interpolant)" if all_linear else
                        "; ROSS's spline or quadratic extrapolates with its curvature, so far outside they part)"))
        notes.append(sentence + ".")
        entry["extrapolate"] = "linear"
    return entry, notes


def rig_bearings(
    bearings: Sequence[Bearing], layout: Layout, names_taken: set[str], speed_points: int
) -> tuple[list[dict[str, Any]], list[str]]:
    """The rig's bearing entries (in the order of ``bearings``; grounded ones on one station summed into the
    first's place) and their notes; names unique within ``names_taken`` (which grows).

    Raises
    ------
    InputError
        A direct damping or mass coefficient below 0; tables too large for a rig file (``speed_points``).
    """
    notes: list[str] = []
    n_spans = layout.n_spans
    grounded: dict[int, list[Bearing]] = {}
    linked: list[tuple[Bearing, int, int]] = []
    for b in bearings:
        st = layout.station_of(b.table, "n", b.n)
        if b.n_link is None:
            grounded.setdefault(st, []).append(b)
            continue
        link = layout.station_of(b.table, "n_link", b.n_link)
        if st > n_spans + 1 and link <= n_spans + 1:
            st, link = link, st  # the rig links a station to its pedestal; the coupling is symmetric
        linked.append((b, st, link))
    bearing_entries: list[tuple[int, dict[str, Any]]] = []
    order = {id(b): i for i, b in enumerate(bearings)}
    for st, members in grounded.items():
        name = unique_name("+".join(slug(b.tag, "bearing") for b in members), names_taken)
        entry, extra_notes = _bearing_entry(members, st, None, name, speed_points)
        bearing_entries.append((order[id(members[0])], entry))
        notes.extend(extra_notes)
        if len(members) > 1:
            notes.append(f"{listing([b.table.path for b in members])}: grounded on the same node (station {st}); "
                         "summed into one bearing entry (a rig takes one grounded bearing per station).")
    for b, st, link in linked:
        name = unique_name(slug(b.tag, "bearing"), names_taken)
        entry, extra_notes = _bearing_entry([b], st, link, name, speed_points)
        bearing_entries.append((order[id(b)], entry))
        notes.extend(extra_notes)
    bearing_entries.sort(key=lambda t: t[0])
    numbers = sum(2 * len(v["values"]) for _, e in bearing_entries for v in e.values() if isinstance(v, dict))
    if numbers * 22 > 0.9 * MAX_RIG_BYTES:  # ~22 characters per number written
        raise InputError(None, "speed_points", f"{speed_points} speeds per coefficient table would make a rig file "
                         f"of about {numbers * 22 / 1e6:.1f} MB, more than rotorcheck reads ({MAX_RIG_BYTES / 1e6:g} "
                         "MB): give fewer")
    return [e for _, e in bearing_entries], notes
