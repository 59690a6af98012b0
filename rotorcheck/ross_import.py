"""Import a rotor saved by ROSS (ross-rotordynamics, ``Rotor.save(path)``, TOML) as a rotorcheck rig.

ROSS writes one top-level table per element, named ``"<ElementClass>_<tag>"`` (``ShaftElement_*``,
``DiskElement_*``, ``BearingElement_*``, ``SealElement_*``, ``PointMass_*``, ...), plus
``ross_version`` and a ``[parameters]`` table. :func:`import_ross` reads such a file and returns the
rig document (a mapping that :func:`rotorcheck.config.parse_config` validates) together with one
sentence for everything that could not be carried over exactly (:class:`RossImport`).

Mapping (ROSS 2.3.0's file format and analysis, ``ross/rotor_assembly.py``, ``shaft_element.py``,
``bearing_seal_element.py``):

* nodes: ROSS node ``k`` (0-based, shaft nodes 0..N, then extra nodes N+1, N+2, ... for pedestals)
  becomes station ``k + 1``; the extra nodes thus become the rig's support nodes after the last
  station. Numbering with gaps is closed up, and the import says so;
* shaft elements: the span of element number ``n`` joins stations ``n + 1`` and ``n + 2``; elements
  with the same ``n`` are concentric layers of that span (the rig takes them as several ``shaft``
  entries on one station pair, whose matrices add, as ROSS's do). Station positions are the running
  sum of the span lengths, as ROSS places its nodes. ``shear_method_calc = "cowper"`` is Cowper's
  formula in both programs; ROSS's ``"hutchinson"`` is not Hutchinson's formula (it lacks a factor
  ``1 + nu``), so such an element gets the coefficient ROSS actually uses as ``shear_coefficient``;
* materials: one rig material per distinct ``(rho, E, G_s)``, named as in ROSS;
* discs (``m``, ``Id``, ``Ip``) and point masses (``mx``, ``my``) carry over as they are;
* bearings and seals: each coefficient is a number, or a ``{speed_rpm, values}`` table sampled
  from the interpolant ROSS builds from the saved lists (a cubic smoothing spline,
  ``scipy.interpolate.UnivariateSpline`` with its default smoothing, for 4 or more speeds; linear or
  quadratic ``interp1d`` for 2 or 3), at ``speed_points`` evenly spaced speeds plus the saved ones.
  ROSS's "frequency" of a bearing coefficient is the rotor speed (rad/s); outside the saved speeds
  ROSS extrapolates, the rig's entry does so linearly (``extrapolate: linear``). Grounded bearings and seals
  on one node are summed into one entry (the rig allows one per station);
* damping: ROSS's rotor-level proportional damping (``parameters.alpha``, ``beta``: M and K of the
  rotor without bearings, discs and point masses included) becomes ``damping: {kind: rayleigh,
  scope: rotor}``; its element damping (``ShaftElement`` ``alpha``, ``beta``, the same on every
  element) becomes ``scope: shaft_elements`` (discs and point masses undamped, as in ROSS).

Axial and torsional terms are dropped: rotorcheck's model is lateral only.
"""

from __future__ import annotations

import itertools
import math
import re
import textwrap
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rotorcheck.config import BEARING_TERMS, MAX_RIG_BYTES, ConfigError, parse_config
from rotorcheck.errors import InputError
from rotorcheck.fileio import read_bounded_text
from rotorcheck.safeload import load_toml

__all__ = ["MAX_ROSS_BYTES", "RossImport", "import_ross", "ross_hutchinson_coefficient"]

#: a ROSS file larger than this is refused before it is parsed (bytes)
MAX_ROSS_BYTES = 50_000_000
#: the ROSS version whose file format and interpolation this module follows
ROSS_FORMAT_VERSION = "2.3.0"

_LATERAL = BEARING_TERMS  # the lateral coefficients ROSS and rotorcheck share
_AXIAL = ("kzz", "czz", "mzz")
_COSMETIC = frozenset({"tag", "color", "scale_factor"})
_SHAFT_KEYS = frozenset({
    "L", "idl", "odl", "idr", "odr", "n", "axial_force", "torque", "shear_effects", "rotary_inertia",
    "gyroscopic", "shear_method_calc", "alpha", "beta", "material",
}) | _COSMETIC
_MATERIAL_KEYS = frozenset({"name", "rho", "E", "G_s", "Poisson", "color", "specific_heat", "thermal_conductivity"})
_DISK_KEYS = frozenset({"n", "m", "Id", "Ip"}) | _COSMETIC
_POINT_MASS_KEYS = frozenset({"n", "m", "mx", "my", "mz"}) | _COSMETIC
_BEARING_KEYS = frozenset({"n", "n_link", "frequency", "seal_leakage", *_LATERAL, *_AXIAL}) | _COSMETIC
#: bearing classes that are nothing but their saved coefficients
_PLAIN_BEARINGS = frozenset({"BearingElement", "SealElement"})
_PARAMETERS = frozenset({"min_w", "max_w", "rated_w", "alpha", "beta", "modal_damping_ratio",
                         "default_damping_ratio", "tag"})
_RAD_S_TO_RPM = 30.0 / math.pi
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


# --------------------------------------------------------------------------------------------
# result


@dataclass(frozen=True)
class RossImport:
    """A ROSS rotor as a rotorcheck rig.

    Attributes
    ----------
    rig : the rig document (a mapping; :func:`rotorcheck.config.parse_config` validates it).
    not_carried : one sentence each: what was dropped or approximated, and why.
    source : the ROSS file read.
    ross_version : the ROSS version that saved it (``"unknown"`` when the file does not say).
    """

    rig: dict[str, Any]
    not_carried: tuple[str, ...]
    source: str = ""
    ross_version: str = "unknown"

    def to_yaml(self) -> str:
        """The rig file: YAML text, headed by comments naming the source, the ROSS version and
        every item of :attr:`not_carried`."""
        lines = [
            f"# Imported from the ROSS rotor {self.source or '(unnamed)'} (saved by ROSS {self.ross_version})",
            "# by rotorcheck import-ross. Bare numbers are SI; ROSS node k is station k + 1; bearing",
            "# coefficient tables are against rotor speed (rpm).",
        ]
        if self.not_carried:
            lines.append(f"# Not carried over or approximated ({len(self.not_carried)}):")
            for item in self.not_carried:
                wrapped = textwrap.wrap(item, width=100, break_long_words=False, break_on_hyphens=False)
                lines.extend(("# - " if i == 0 else "#   ") + w for i, w in enumerate(wrapped))
        else:
            lines.append("# Everything was carried over.")
        body = yaml.dump(self.rig, Dumper=_Dumper, sort_keys=False, default_flow_style=None, width=120,
                         allow_unicode=True)
        return "\n".join(lines) + "\n" + body


class _Dumper(yaml.SafeDumper):
    """Safe YAML without anchors and aliases (the speed lists of one bearing are one object)."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


# --------------------------------------------------------------------------------------------
# reading typed fields


def _key(name: str) -> str:
    """A TOML key as written in a dotted path: bare when it can be, else quoted."""
    if _BARE_KEY.fullmatch(name):
        return name
    return '"' + name.replace("\\", "\\\\").replace('"', '\\"') + '"'


class _Table:
    """One TOML table of the ROSS file, with typed getters whose errors name ``table.key``."""

    def __init__(self, source: str, path: str, data: dict[str, Any]):
        self.source = source
        self.path = path  # dotted path of the table, e.g. '"ShaftElement_Shaft Element 3".material'
        self.data = data

    def field(self, key: str) -> str:
        return f"{self.path}.{_key(key)}"

    def error(self, key: str, message: str) -> InputError:
        return InputError(self.source, self.field(key) if key else self.path, message)

    def has(self, key: str) -> bool:
        return key in self.data

    def _number(self, value: Any, field: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(self.source, field, f"must be a number, not {_kind(value)}")
        x = float(value)
        if not math.isfinite(x):
            raise InputError(self.source, field, "must be a finite number")
        return x

    def number(self, key: str, default: float | None = None) -> float:
        """A finite number; ``default`` when absent (``None``: required)."""
        if key not in self.data:
            if default is None:
                raise self.error(key, "required field is missing")
            return default
        return self._number(self.data[key], self.field(key))

    def integer(self, key: str) -> int | None:
        """An integer (an integral float is accepted), None when absent."""
        if key not in self.data:
            return None
        value = self.data[key]
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be an integer, not {_kind(value)}")
        if value < 0:
            raise self.error(key, "must be >= 0 (a ROSS node number)")
        return value

    def flag(self, key: str, default: bool) -> bool:
        if key not in self.data:
            return default
        value = self.data[key]
        if not isinstance(value, bool):
            raise self.error(key, f"must be true or false, not {_kind(value)}")
        return value

    def text(self, key: str, default: str) -> str:
        if key not in self.data:
            return default
        value = self.data[key]
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, not {_kind(value)}")
        return value

    def numbers(self, key: str) -> np.ndarray | None:
        """A list of finite numbers (a single number is a list of one), None when absent."""
        if key not in self.data:
            return None
        value = self.data[key]
        if not isinstance(value, list):
            return np.array([self._number(value, self.field(key))])
        if not value:
            raise self.error(key, "must not be empty")
        return np.array([self._number(v, f"{self.field(key)}[{i}]") for i, v in enumerate(value)])

    def table(self, key: str) -> _Table:
        if key not in self.data:
            raise self.error(key, "required table is missing")
        value = self.data[key]
        if not isinstance(value, dict):
            raise self.error(key, f"must be a table, not {_kind(value)}")
        return _Table(self.source, self.field(key), value)

    def unknown(self, known: frozenset[str]) -> list[str]:
        return sorted(k for k in self.data if k not in known)


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return f"the string {value!r}" if len(value) <= 40 else "a string"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def _listing(names: Sequence[str], limit: int = 4) -> str:
    """``a, b and c``; long lists cut after ``limit`` names with the count."""
    items = list(names)
    if len(items) <= limit:
        return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]
    return ", ".join(items[:limit]) + f", ... ({len(items)} in all)"


def _slug(text: str, fallback: str) -> str:
    s = re.sub(r"[^0-9a-z]+", "_", text.strip().lower()).strip("_")
    return s or fallback


def _unique(name: str, taken: set[str]) -> str:
    out, k = name, 2
    while out in taken:
        out, k = f"{name}_{k}", k + 1
    taken.add(out)
    return out


# --------------------------------------------------------------------------------------------
# ROSS formulas


def ross_hutchinson_coefficient(poisson: float, outer_diameter: float, inner_diameter: float) -> float:
    """The shear coefficient ROSS 2.3.0 uses for ``shear_method_calc="hutchinson"``.

    ``kappa = 6 (1 + r^2)^2 (1 + nu) / ((1 + r^2)^2 (7 + 12 nu + 4 nu^2) + 4 r^2 (5 + 6 nu + 2 nu^2))``
    with ``r = inner / outer`` (ROSS passes the mean diameters of a tapered element). Hutchinson's
    (2001) own formula has ``(1 + nu)^2``; ROSS's gives 0.712 for a solid section at nu = 0.3.

    Parameters
    ----------
    poisson : Poisson's ratio (ROSS: ``E / (2 G_s) - 1``).
    outer_diameter, inner_diameter : m (only their ratio matters).
    """
    from rotorcheck.fe.elements import shear_coefficient

    return float(shear_coefficient(poisson, outer_diameter, inner_diameter)) / (1.0 + poisson)


Interpolant = Callable[[np.ndarray], np.ndarray]


def _ross_interpolant(
    table: _Table, key: str, freq: np.ndarray | None, values: np.ndarray
) -> tuple[Interpolant | None, str]:
    """ROSS's interpolant of one coefficient list against speed (rad/s): ``(None, "constant")`` for a
    single value or equal values, else ``(callable, kind)`` as ROSS 2.3.0's
    ``BearingElement._process_coefficient`` builds it."""
    if values.size == 1 or bool(np.all(values == values[0])):
        return None, "constant"
    if freq is None:
        raise table.error(key, f"{values.size} values but no frequency list (ROSS needs one per value)")
    from scipy import interpolate

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


# --------------------------------------------------------------------------------------------
# parsed elements


@dataclass
class _Shaft:
    table: _Table
    order: int
    n: int
    L: float
    idl: float
    odl: float
    idr: float
    odr: float
    axial_force: float
    torque: float
    shear: bool
    rotary_inertia: bool
    gyroscopic: bool
    method: str
    alpha: float
    beta: float
    material: tuple[float, float, float]  # rho, E, G_s
    material_name: str

    @property
    def poisson(self) -> float:
        """ROSS's Poisson's ratio, E / (2 G_s) - 1."""
        return self.material[1] / (2.0 * self.material[2]) - 1.0


@dataclass
class _Bearing:
    table: _Table
    cls: str
    tag: str
    n: int
    n_link: int | None
    freq: np.ndarray | None
    interpolants: dict[str, tuple[Interpolant | None, str]]
    constants: dict[str, float]  # value of each constant coefficient
    raw: dict[str, np.ndarray]


def _read_shaft(table: _Table, order: int) -> _Shaft:
    n = table.integer("n")
    L = table.number("L")
    if L <= 0:
        raise table.error("L", "must be > 0 (element length, m)")
    idl, odl = table.number("idl", 0.0), table.number("odl")
    idr, odr = table.number("idr", idl), table.number("odr", odl)
    for key, value in (("odl", odl), ("odr", odr)):
        if value <= 0:
            raise table.error(key, "must be > 0 (outer diameter, m)")
    for key, value, outer in (("idl", idl, odl), ("idr", idr, odr)):
        if value < 0:
            raise table.error(key, "must be >= 0 (inner diameter, m)")
        if value >= outer:
            raise table.error(key, f"must be < the outer diameter {outer:g} m")
    shear = table.flag("shear_effects", True)
    method = table.text("shear_method_calc", "cowper")
    if shear and method not in ("cowper", "hutchinson"):
        raise table.error("shear_method_calc", f"{method!r}: ROSS knows 'cowper' and 'hutchinson'")
    mat = table.table("material")
    rho = mat.number("rho")
    E = mat.number("E") if mat.has("E") else None
    G = mat.number("G_s") if mat.has("G_s") else None
    nu = mat.number("Poisson") if mat.has("Poisson") else None
    if E is not None and G is not None:
        pass
    elif E is not None and nu is not None:
        G = E / (2.0 * (1.0 + nu))
    elif G is not None and nu is not None:
        E = G * 2.0 * (1.0 + nu)
    else:
        raise mat.error("", "needs two of E, G_s and Poisson")
    assert E is not None and G is not None
    for key, value in (("rho", rho), ("E", E), ("G_s", G)):
        if value <= 0:
            raise mat.error(key if mat.has(key) else "", f"{key} must be > 0")
    return _Shaft(
        table=table, order=order, n=order if n is None else n, L=L, idl=idl, odl=odl, idr=idr, odr=odr,
        axial_force=table.number("axial_force", 0.0), torque=table.number("torque", 0.0), shear=shear,
        rotary_inertia=table.flag("rotary_inertia", True), gyroscopic=table.flag("gyroscopic", True),
        method=method, alpha=table.number("alpha", 0.0), beta=table.number("beta", 0.0),
        material=(rho, E, G), material_name=mat.text("name", ""),
    )


def _read_bearing(table: _Table, cls: str, tag: str) -> _Bearing:
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
    for key in (*_LATERAL, *_AXIAL):
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
    interpolants = {key: _ross_interpolant(table, key, freq, raw[key]) for key in _LATERAL}
    constants = {key: float(raw[key][0]) for key, (f, _) in interpolants.items() if f is None}
    return _Bearing(table, cls, tag, n, n_link, freq, interpolants, constants, raw)


# --------------------------------------------------------------------------------------------
# bearing entries


def _rpm(speed_rad_s: np.ndarray) -> np.ndarray:
    """rad/s -> rpm; speeds within 1e-12 of a whole rpm are rounded to it (6000.000000000001 -> 6000)."""
    rpm = speed_rad_s * _RAD_S_TO_RPM
    whole = np.round(rpm)
    return np.where(np.abs(rpm - whole) <= 1e-12 * np.maximum(np.abs(rpm), 1.0), whole, rpm)


def _grid(members: Sequence[_Bearing], speed_points: int) -> tuple[np.ndarray, np.ndarray]:
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
    rad_s = np.concatenate([saved, even_rpm[~near] / _RAD_S_TO_RPM])
    order = np.argsort(rpm, kind="stable")
    rpm, rad_s = rpm[order], rad_s[order]
    keep = np.r_[True, np.diff(rpm) > 0]  # distinct speeds in rpm (two saved lists may differ by rounding)
    return rad_s[keep], rpm[keep]


def _bearing_entry(
    members: Sequence[_Bearing], station: int, n_link: int | None, name: str, speed_points: int
) -> tuple[dict[str, Any], list[str]]:
    """The rig entry of one bearing (or the sum of grounded ones on one node) and its notes."""
    entry: dict[str, Any] = {"name": name, "station": station}
    if n_link is not None:
        entry["n_link"] = n_link
    notes: list[str] = []
    tables = _listing([b.table.path for b in members])
    tabulated = [k for k in _LATERAL if any(b.interpolants[k][0] is not None for b in members)]
    grid, grid_rpm = _grid(members, speed_points) if tabulated else (np.zeros(0), np.zeros(0))
    values: dict[str, float | np.ndarray] = {}
    for key in _LATERAL:
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
    for key in _LATERAL:
        v = values[key]
        if isinstance(v, np.ndarray):
            entry[key] = {"speed_rpm": rpm, "values": [float(x) for x in v]}
        elif v != 0.0 or key in ("kxx", "kyy"):
            entry[key] = v
    speed_keys = [k for k in _LATERAL if isinstance(values[k], np.ndarray)]
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


# --------------------------------------------------------------------------------------------
# the import


def _load_toml(path: Path) -> dict[str, Any]:
    source = str(path)
    text = read_bounded_text(path, MAX_ROSS_BYTES, "ROSS rotor file")
    return load_toml(text, source)  # nesting bounded before parsing


def import_ross(path: str | Path, rig_id: str | None = None, speed_points: int = 65) -> RossImport:
    """Read a rotor saved by ROSS (``Rotor.save``, TOML) as a rotorcheck rig.

    Parameters
    ----------
    path : the ROSS TOML file.
    rig_id : the rig's ``rig_id`` (default: from the file name).
    speed_points : evenly spaced speeds at which a speed-dependent bearing coefficient is sampled
        (besides the speeds saved with it); at least 2.

    Returns
    -------
    RossImport
        The rig document (validated) and what could not be carried over.

    Raises
    ------
    InputError
        Unreadable file, not TOML, not a ROSS rotor, a field of the wrong type or value; the field
        names the TOML table and key, e.g. ``"ShaftElement_Shaft Element 3".odl``.
    """
    if isinstance(speed_points, bool) or not isinstance(speed_points, int) or speed_points < 2:
        raise InputError(None, "speed_points", f"must be an integer >= 2, not {speed_points!r}")
    p = Path(path)
    source = str(path)
    data = _load_toml(p)
    notes: list[str] = []

    version = data.get("ross_version", "unknown")
    if not isinstance(version, str):
        raise InputError(source, "ross_version", f"must be a string, not {_kind(version)}")

    shafts: list[_Shaft] = []
    discs: list[tuple[_Table, str, str]] = []  # table, class, tag
    point_masses: list[tuple[_Table, str]] = []
    bearings: list[_Bearing] = []
    span_like: list[tuple[str, int]] = []  # unsupported elements that occupy a shaft span (couplings)
    parameters: _Table | None = None
    for name, value in data.items():
        if name == "ross_version" or name.startswith("_"):
            continue
        if name == "parameters":
            if not isinstance(value, dict):
                raise InputError(source, "parameters", f"must be a table, not {_kind(value)}")
            parameters = _Table(source, "parameters", value)
            continue
        cls, sep, tag = name.partition("_")
        if sep and not isinstance(value, dict):
            raise InputError(source, _key(name), f"must be a table (a ROSS element \"<ElementClass>_<tag>\" is "
                             f"one), not {_kind(value)}: this import does not drop it unread")
        if not isinstance(value, dict) or not sep:
            notes.append(f"{_key(name)}: not a ROSS element table (expected \"<ElementClass>_<tag>\"); ignored.")
            continue
        table = _Table(source, _key(name), value)
        if cls == "ShaftElement":
            shafts.append(_read_shaft(table, len(shafts)))
            extra = table.unknown(_SHAFT_KEYS)
        elif cls == "DiskElement" or (table.has("Id") and table.has("Ip") and table.has("m") and table.has("n")):
            discs.append((table, cls, tag))
            extra = table.unknown(_DISK_KEYS)
            if cls != "DiskElement":
                notes.append(f"{table.path}: a ROSS {cls}, carried as a rigid disc (m, Id, Ip) only"
                             + (f"; its {', '.join(extra)} are not" if extra else "") + ".")
                extra = []
        elif cls == "PointMass":
            point_masses.append((table, tag))
            extra = table.unknown(_POINT_MASS_KEYS)
        elif cls in _PLAIN_BEARINGS or table.has("kxx"):
            bearings.append(_read_bearing(table, cls, tag))
            extra = table.unknown(_BEARING_KEYS)
            if cls not in _PLAIN_BEARINGS:
                notes.append(f"{table.path}: a ROSS {cls}, carried as the linear coefficients saved with it (what "
                             "ROSS's modal and frequency response analyses use)"
                             + (f"; its own parameters ({', '.join(extra)}) and model are not" if extra else "") + ".")
                extra = []
        else:
            n_span = table.integer("n") if table.has("n") and table.has("L") else None
            if n_span is not None:
                span_like.append((table.path, n_span))
            notes.append(f"{table.path}: ROSS element class {cls} has no counterpart in a rotorcheck rig; left out.")
            continue
        if extra:
            notes.append(f"{table.path}: field{'s' if len(extra) > 1 else ''} {', '.join(extra)} not carried "
                         "(not used by this import).")
    if not shafts:
        raise InputError(source, "ShaftElement_*",
                         "no shaft element table: this is no rotor saved by ROSS (Rotor.save)")

    # ---- spans, stations, layers
    shafts.sort(key=lambda s: (s.n, s.order))  # ROSS sorts by n, stably (file order within a span)
    span_ns = sorted({s.n for s in shafts})
    for tpath, n_span in span_like:
        if n_span not in span_ns:
            raise InputError(source, f"{tpath}.n", f"span {n_span} holds no ShaftElement, only this element, which a "
                             "rotorcheck rig cannot represent: replace it by a shaft element in ROSS and save again")
    n_spans = len(span_ns)
    first = {n: next(s for s in shafts if s.n == n) for n in span_ns}
    for left, right in itertools.pairwise(span_ns):
        if right == left + 2:  # ROSS's CoAxialRotor numbers the next shaft's first node one after the last one's end
            raise InputError(source, first[right].table.field("n"),
                             f"shaft element numbers jump from {left} to {right}: node {left + 1} ends one shaft and "
                             f"node {right} starts another, as ROSS numbers the shafts of a CoAxialRotor; coaxial "
                             "(two-shaft) rotors are not supported by rotorcheck (one shaft per rig)")
    stations = [0.0]
    for n in span_ns:
        stations.append(stations[-1] + first[n].L)
    for s in shafts:
        f = first[s.n]
        if s is not f and abs(s.L - f.L) > 1e-12 * f.L:
            notes.append(f"{s.table.path}: a layer of span n = {s.n} with L = {s.L:g} m, but the span is {f.L:g} m "
                         f"long ({f.table.path}, as ROSS places the nodes); carried on the span, with its length.")
    contiguous = span_ns == list(range(span_ns[0], span_ns[0] + n_spans))
    node_station: dict[int, int] = {n: i + 1 for i, n in enumerate(span_ns)}
    last_node = span_ns[-1] + 1
    node_station[last_node] = n_spans + 1
    if not contiguous or span_ns[0] != 0:
        notes.append(f"ROSS shaft element numbers n ({_listing([str(n) for n in span_ns], 6)}) do not run 0, 1, 2, ... "
                     "without gaps (ROSS's own node positions and degrees of freedom disagree then): the spans are "
                     "joined in the order of n as stations 1, 2, ...")
    referenced: set[int] = set()
    for b in bearings:
        referenced.add(b.n)
        if b.n_link is not None:
            referenced.add(b.n_link)
    pm_nodes: list[int] = []
    for table, _ in point_masses:
        node = table.integer("n")
        if node is None:
            raise table.error("n", "required field is missing")
        pm_nodes.append(node)
        referenced.add(node)
    extra_nodes = sorted(k for k in referenced if k > last_node)
    for j, k in enumerate(extra_nodes):
        node_station[k] = n_spans + 2 + j
    if extra_nodes and extra_nodes != list(range(last_node + 1, last_node + 1 + len(extra_nodes))):
        notes.append(f"ROSS extra nodes {_listing([str(k) for k in extra_nodes], 6)} do not follow the last shaft node "
                     f"{last_node} without gaps: renumbered as support nodes {n_spans + 2}, {n_spans + 3}, ...")

    def station_of(table: _Table, key: str, node: int, shaft_only: bool = False) -> int:
        st = node_station.get(node)
        if st is None:
            raise table.error(key, f"node {node} is no node of the shaft (nodes {span_ns[0]}..{last_node}) or of "
                              "a pedestal after it")
        if shaft_only and st > n_spans + 1:
            raise table.error(key, f"node {node} is an extra node (pedestal) after the shaft; ROSS places discs on "
                              "shaft nodes only")
        return st

    # ---- materials
    mats: dict[tuple[float, float, float], list[str]] = {}
    for s in shafts:
        names = mats.setdefault(s.material, [])
        if s.material_name not in names:
            names.append(s.material_name)
    taken: set[str] = set()
    mat_name: dict[tuple[float, float, float], str] = {}
    materials: dict[str, dict[str, float]] = {}
    for props, names in mats.items():
        clean = sorted({n if re.fullmatch(r"[A-Za-z0-9_.-]+", n) else _slug(n, "material") for n in names})
        name = _unique("+".join(clean), taken)
        mat_name[props] = name
        materials[name] = {"density": props[0], "youngs_modulus": props[1], "shear_modulus": props[2]}

    # ---- shaft entries
    def majority(values: list[bool]) -> bool:
        return sum(values) * 2 >= len(values)

    rig_shear = majority([s.shear for s in shafts])
    rig_rotary = majority([s.rotary_inertia for s in shafts])
    shaft_entries: list[dict[str, Any]] = []
    hutchinson: list[str] = []
    for s in shafts:
        start = node_station[s.n]
        e: dict[str, Any] = {"start": start, "end": start + 1, "material": mat_name[s.material],
                             "outer_diameter": s.odl}
        if s.idl:
            e["inner_diameter"] = s.idl
        if s.odr != s.odl or s.idr != s.idl:
            e["outer_diameter_right"] = s.odr
            e["inner_diameter_right"] = s.idr
        if s.axial_force:
            e["axial_force"] = s.axial_force
        if s.torque:
            e["torque"] = s.torque
        if s.shear != rig_shear:
            e["shear"] = s.shear
        if s.shear and s.method == "hutchinson":
            mean_od, mean_id = 0.5 * (s.odl + s.odr), 0.5 * (s.idl + s.idr)
            e["shear_coefficient"] = ross_hutchinson_coefficient(s.poisson, mean_od, mean_id)
            hutchinson.append(s.table.path)
        if s.rotary_inertia != rig_rotary:
            e["rotary_inertia"] = s.rotary_inertia
        if not s.gyroscopic:
            e["gyroscopic"] = False
        shaft_entries.append(e)
    if hutchinson:
        notes.append(f"{_listing(hutchinson)}: ROSS's shear_method_calc 'hutchinson' is not Hutchinson's (2001) "
                     "formula (it lacks a factor 1 + nu); written as the shear_coefficient ROSS actually uses, "
                     "6 (1+r^2)^2 (1+nu) / ((1+r^2)^2 (7+12nu+4nu^2) + 4 r^2 (5+6nu+2nu^2)) with r = mean inner / "
                     "mean outer diameter, not as rotorcheck's shear_method hutchinson.")

    # ---- discs and point masses
    names_taken: set[str] = set()
    disc_entries: list[dict[str, Any]] = []
    for table, _cls, tag in discs:
        node = table.integer("n")
        if node is None:
            raise table.error("n", "required field is missing")
        station = station_of(table, "n", node, shaft_only=True)
        m, Id, Ip = table.number("m"), table.number("Id", 0.0), table.number("Ip", 0.0)
        for key, value in (("Id", Id), ("Ip", Ip)):
            if value < 0:
                raise table.error(key, "must be >= 0 (kg m^2)")
        if m < 0:
            raise table.error("m", "must be >= 0 (kg)")
        if m == 0:
            if Id or Ip:
                notes.append(f"{table.path}: a disc without mass (m = 0) but with inertia; rotorcheck's discs need "
                             "a mass, so it is left out.")
            continue
        disc_entries.append({"name": _unique(_slug(tag, "disc"), names_taken), "station": station, "mass": m,
                             "polar_inertia": Ip, "transverse_inertia": Id})
    pm_entries: list[dict[str, Any]] = []
    mz_tables: list[str] = []
    for (table, tag), node in zip(point_masses, pm_nodes):
        station = station_of(table, "n", node)
        m_all = table.number("m") if table.has("m") else None
        mx = table.number("mx") if table.has("mx") else m_all
        my = table.number("my") if table.has("my") else m_all
        if mx is None or my is None:
            raise table.error("mx" if mx is None else "my", "required field is missing (or give m)")
        for key, value in (("mx", mx), ("my", my)):
            if value < 0:
                raise table.error(key if table.has(key) else "m", "must be >= 0 (kg)")
        mz = table.number("mz", 0.0) if table.has("mz") else (m_all or 0.0)
        if mz:
            mz_tables.append(table.path)
        pm_name = _unique(_slug(tag, "point_mass"), names_taken)
        if mx == 0 and my == 0:
            notes.append(f"{table.path}: a point mass of zero lateral mass; left out.")
            continue
        if mx == 0 or my == 0:
            raise table.error("mx" if mx == 0 else "my", "0 in one direction only: rotorcheck's point masses carry "
                              "mass in x and y")
        pm_entries.append({"name": pm_name, "station": station, "mass": mx} if mx == my else
                          {"name": pm_name, "station": station, "mx": mx, "my": my})

    # ---- bearings
    grounded: dict[int, list[_Bearing]] = {}
    linked: list[tuple[_Bearing, int, int]] = []
    for b in bearings:
        st = station_of(b.table, "n", b.n)
        if b.n_link is None:
            grounded.setdefault(st, []).append(b)
            continue
        link = station_of(b.table, "n_link", b.n_link)
        if st > n_spans + 1 and link <= n_spans + 1:
            st, link = link, st  # the rig links a station to its pedestal; the coupling is symmetric
        linked.append((b, st, link))
    bearing_entries: list[tuple[int, dict[str, Any]]] = []
    order = {id(b): i for i, b in enumerate(bearings)}
    for st, members in grounded.items():
        name = _unique("+".join(_slug(b.tag, "bearing") for b in members), names_taken)
        entry, extra_notes = _bearing_entry(members, st, None, name, speed_points)
        bearing_entries.append((order[id(members[0])], entry))
        notes.extend(extra_notes)
        if len(members) > 1:
            notes.append(f"{_listing([b.table.path for b in members])}: grounded on the same node (station {st}); "
                         "summed into one bearing entry (a rig takes one grounded bearing per station).")
    for b, st, link in linked:
        entry, extra_notes = _bearing_entry([b], st, link, _unique(_slug(b.tag, "bearing"), names_taken), speed_points)
        bearing_entries.append((order[id(b)], entry))
        notes.extend(extra_notes)
    bearing_entries.sort(key=lambda t: t[0])
    numbers = sum(2 * len(v["values"]) for _, e in bearing_entries for v in e.values() if isinstance(v, dict))
    if numbers * 22 > 0.9 * MAX_RIG_BYTES:  # ~22 characters per number written
        raise InputError(None, "speed_points", f"{speed_points} speeds per coefficient table would make a rig file "
                         f"of about {numbers * 22 / 1e6:.1f} MB, more than rotorcheck reads ({MAX_RIG_BYTES / 1e6:g} "
                         "MB): give fewer")

    # ---- damping and rotor parameters
    damping: dict[str, Any] = {"kind": "none"}
    analysis: dict[str, Any] = {}
    global_ab = (0.0, 0.0)
    if parameters is not None:
        speeds = {}
        for key in ("min_w", "rated_w", "max_w"):
            if parameters.has(key):
                speeds[key] = parameters.number(key)
        picks = sorted({round(v * _RAD_S_TO_RPM, 9) for v in speeds.values() if v >= 0})
        if picks:
            analysis["speeds_rpm"] = picks
        if speeds.get("max_w", 0.0) > 0:
            analysis["campbell_max_rpm"] = speeds["max_w"] * _RAD_S_TO_RPM
        global_ab = (parameters.number("alpha", 0.0), parameters.number("beta", 0.0))
        if any(global_ab):
            if min(global_ab) >= 0:
                damping = {"kind": "rayleigh", "alpha": global_ab[0], "beta": global_ab[1], "scope": "rotor"}
            else:
                notes.append(f"parameters: alpha = {global_ab[0]:g}, beta = {global_ab[1]:g}: negative proportional "
                             "damping has no counterpart (rotorcheck's Rayleigh damping takes alpha, beta >= 0); "
                             "left out.")
        if parameters.has("modal_damping_ratio"):
            notes.append("parameters.modal_damping_ratio: ROSS builds its modal damping from every mode of its 6-DOF "
                         "model (axial and torsional modes included) at zero speed, not per lateral mode pair as "
                         "rotorcheck's damping: {kind: modal}; left out (give damping: {kind: modal, ratios: [...]} "
                         "by hand if wanted).")
        other = parameters.unknown(_PARAMETERS)
        if other:
            notes.append(f"parameters: {', '.join(other)} not carried (not used by this import).")
    elemental = sorted({(s.alpha, s.beta) for s in shafts})
    damped = [s.table.path for s in shafts if s.alpha or s.beta]
    if damped:
        if any(global_ab):
            notes.append(f"{_listing(damped)}: element proportional damping (alpha, beta) left out, as ROSS ignores it "
                         "when the rotor has global proportional damping.")
        elif len(elemental) == 1 and min(elemental[0]) >= 0:
            # the same alpha, beta on every element: sum of alpha M_e + beta K_e over the shaft elements
            damping = {"kind": "rayleigh", "alpha": elemental[0][0], "beta": elemental[0][1],
                       "scope": "shaft_elements"}
        else:
            values = _listing([f"alpha = {a:g}, beta = {b:g}" for a, b in elemental], 3)
            notes.append(f"{_listing(damped)}: element proportional damping ({values}) left out: rotorcheck's "
                         "Rayleigh damping of scope shaft_elements takes one alpha >= 0 and one beta >= 0 for every "
                         "shaft element.")

    # ---- lateral only
    axial_terms = []
    for b in bearings:
        nonzero = [k for k in _AXIAL if bool(np.any(b.raw[k] != 0))]
        if nonzero:
            axial_terms.append(f"{'/'.join(nonzero)} of {b.table.path}")
    if mz_tables:
        axial_terms.append(f"mz of {_listing(mz_tables, 2)}")
    sentence = ("ROSS's model has 6 degrees of freedom per node, rotorcheck's is lateral only (x, y and the two "
                "tilts): the axial and torsional degrees of freedom and terms are not carried (kzz, czz, mzz of "
                "bearings and seals, mz of point masses, the axial and torsional part of shaft elements and discs)")
    if axial_terms:
        sentence += "; nonzero here: " + _listing(axial_terms, 3)
    notes.append(sentence + ".")
    if version != ROSS_FORMAT_VERSION:
        notes.append(f"The file says ROSS {version}; this import follows the file format and bearing interpolation "
                     f"of ROSS {ROSS_FORMAT_VERSION}, which may differ.")

    # ---- the rig
    n_layers = len(shafts) - n_spans
    desc = (f"Imported from the ROSS rotor {p.name} (ROSS {version}): {n_spans} shaft spans"
            + (f" ({n_layers} further concentric layers)" if n_layers else "")
            + f", {len(disc_entries)} disc(s), {len(bearing_entries)} bearing/seal entries"
            + (f", {len(pm_entries)} point mass(es)" if pm_entries else "") + ".")
    if parameters is not None and parameters.has("tag"):
        desc += f" ROSS rotor tag: {parameters.text('tag', '')}."
    rig: dict[str, Any] = {
        "schema": "rotorcheck.rig",
        "version": 1,
        "rig_id": rig_id if rig_id is not None else _slug(p.stem, "ross_rotor"),
        "kind": "rotor",
        "description": desc,
        "shear_method": "cowper",
    }
    if any("outer_diameter_right" in e or "inner_diameter_right" in e for e in shaft_entries):
        rig["tapered_element"] = "greenhill"  # ROSS's tapered element (one mid-section shear parameter)
        notes.append("tapered elements use ROSS's formulation (tapered_element: greenhill, Greenhill et al. 1985) "
                     "so the frequencies reproduce ROSS's; rotorcheck's default (exact) is the exact static "
                     "stiffness of the tapered beam, whose modes converge faster under refinement from 8 elements "
                     "per taper on (at 4 elements only its first mode is closer).")
    if not rig_shear:
        rig["shear"] = False
        if not any(e.get("shear") for e in shaft_entries):
            del rig["shear_method"]  # no element has shear: the method would be unused (refused)
    if not rig_rotary:
        rig["rotary_inertia"] = False
    rig["materials"] = materials
    rig["stations"] = stations
    rig["shaft"] = shaft_entries
    if disc_entries:
        rig["discs"] = disc_entries
    if pm_entries:
        rig["point_masses"] = pm_entries
    if bearing_entries:
        rig["bearings"] = [e for _, e in bearing_entries]
    rig["damping"] = damping
    if analysis:
        rig["analysis"] = analysis
    try:
        parse_config(rig, source)
    except ConfigError as exc:
        raise InputError(source, "", f"cannot be expressed as a rotorcheck rig: {exc.field}: {exc.message}") from None
    return RossImport(rig=rig, not_carried=tuple(notes), source=source, ross_version=version)
