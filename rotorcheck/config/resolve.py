"""Benign ranges resolved against their rig (which config fields each changes, in which units); the
low-level form behind :mod:`rotorcheck.variability`, run when a rig file is loaded (not inside a validator)."""

from __future__ import annotations

import re
from typing import Any, NamedTuple

from pydantic import BaseModel, ValidationError

from rotorcheck.config.benign import BENIGN_KIND, BENIGN_PATH_ROOTS, BenignRange
from rotorcheck.config.errors import field_path, first_error
from rotorcheck.config.rig import RigConfig
from rotorcheck.config.supports import SpeedTable

Leaf = tuple[str | int, ...]


class ResolvedBenign(NamedTuple):
    """A ``variability`` entry resolved against its rig; see :class:`rotorcheck.variability.BenignParameter`.

    ``leaves``: the config fields it changes, as paths with 0-based list indices, e.g.
    ``("bearings", 0, "kxx")``; empty for gains and speed (not config changes).
    """

    name: str
    kind: str  # "factor" | "offset"
    lo: float
    hi: float
    unit: str
    target: tuple[str, ...]
    leaves: tuple[Leaf, ...]


#: display unit of an offset on a path parameter, by field name
_FIELD_UNITS = {
    "density": "kg/m^3", "youngs_modulus": "Pa", "shear_modulus": "Pa", "mass": "kg", "stiffness": "N/m",
    "damping": "N s/m", "kxx": "N/m", "kyy": "N/m", "kxy": "N/m", "kyx": "N/m", "k_rot": "N m/rad",
    "cxx": "N s/m", "cyy": "N s/m", "cxy": "N s/m", "cyx": "N s/m", "polar_inertia": "kg m^2",
    "transverse_inertia": "kg m^2", "outer_diameter": "m", "inner_diameter": "m", "stations": "m",
    "alpha": "1/s", "beta": "s", "ratios": "",
}


def leaf_text(leaf: Leaf) -> str:
    """``("bearings", 0, "kxx")`` -> ``"bearings[0].kxx"`` (the form of config error paths)."""
    return field_path(leaf)


def _by_name(items: list[Any], name: str, what: str, key: str) -> int:
    """Index of the one item of ``items`` called ``name``; ValueError ``"key: ..."`` otherwise."""
    hits = [k for k, item in enumerate(items) if item.name == name]
    if not hits:
        known = ", ".join(dict.fromkeys(item.name for item in items)) or "none"
        raise ValueError(f"{key}: unknown {what} {name!r} (known: {known})")
    if len(hits) > 1:
        raise ValueError(f"{key}: {len(hits)} {what}s are called {name!r}; give them unique names")
    return hits[0]


def _values(v: Any) -> list[float]:
    return list(v.values) if isinstance(v, SpeedTable) else [float(v)]


def _factor_range(r: BenignRange, nominal: float | None, what: str) -> tuple[float, float]:
    """Relative range (x in value = nominal (1 + x)) of a percent / range_percent / absolute entry."""
    if r.percent is not None:
        return -r.percent / 100.0, r.percent / 100.0
    if r.range_percent is not None:
        return r.range_percent[0] / 100.0, r.range_percent[1] / 100.0
    assert r.absolute is not None and nominal is not None
    a, b = r.absolute
    if not a <= nominal <= b:
        raise ValueError(f"absolute: [{a:g}, {b:g}] does not contain the nominal {what} {nominal:g}")
    x1, x2 = a / nominal - 1.0, b / nominal - 1.0
    return min(x1, x2), max(x1, x2)


def _check_floor(r: BenignRange, lo: float, what: str, allow_zero: bool = False) -> None:
    """A relative range must keep a positive quantity > 0 (>= 0 with ``allow_zero``)."""
    if lo > -1.0 or (allow_zero and lo >= -1.0):
        return
    rel = "< 0" if allow_zero else "<= 0"
    if r.percent is not None:
        limit = "<= 100" if allow_zero else "< 100"
        raise ValueError(f"percent: {r.percent:g} % would make {what} {rel} (must be {limit})")
    if r.range_percent is not None:
        limit = ">= -100" if allow_zero else "> -100"
        raise ValueError(f"range_percent: {r.range_percent[0]:g} % would make {what} {rel} (lower bound must be "
                         f"{limit})")
    if r.absolute is not None:
        raise ValueError(f"absolute: lower bound {r.absolute[0]:g} would make {what} {rel}")
    assert r.temperature_c is not None
    t0, t1 = r.temperature_c
    raise ValueError(f"temperature_c: {what} would be {rel} in [{t0:g}, {t1:g}] degC")


def _resolve_path(cfg: RigConfig, text: str) -> tuple[Leaf, tuple[str, ...], float]:
    """(leaf with 0-based indices, canonical segments, nominal value) of a ``path`` parameter."""
    segments = re.sub(r"\[(\d+)\]", r".\1", text.strip()).split(".")
    if not segments or any(not s for s in segments):
        raise ValueError(f"path: cannot read {text!r} (dotted names, e.g. materials.ss416.density)")
    if segments[0] not in BENIGN_PATH_ROOTS:
        raise ValueError(f"path: {segments[0]!r} is not a model section (use one of {', '.join(BENIGN_PATH_ROOTS)})")
    obj: Any = cfg
    leaf: list[str | int] = []
    for seg in segments:
        where = field_path(tuple(leaf)) or "the rig"
        if isinstance(obj, BaseModel):
            if seg not in type(obj).model_fields:
                raise ValueError(f"path: {where} has no field {seg!r}")
            obj = getattr(obj, seg)
            leaf.append(seg)
        elif isinstance(obj, dict):
            if seg not in obj:
                raise ValueError(f"path: {where} has no key {seg!r} (known: {', '.join(obj) or 'none'})")
            obj = obj[seg]
            leaf.append(seg)
        elif isinstance(obj, (list, tuple)):
            if seg.isdigit():
                k = int(seg)
                if k >= len(obj):
                    raise ValueError(f"path: {where} has {len(obj)} entries (0-based index {k})")
            elif obj and all(hasattr(item, "name") for item in obj):
                k = _by_name(list(obj), seg, "entry", "path")
            else:
                raise ValueError(f"path: {where} is a list: give a 0-based index, not {seg!r}")
            obj = obj[k]
            leaf.append(k)
        else:
            raise ValueError(f"path: {where} is a value, it has no {seg!r}")
    if isinstance(obj, SpeedTable):
        raise ValueError(f"path: {text} is a speed table (use bearing_stiffness / bearing_damping)")
    if not isinstance(obj, float):
        raise ValueError(f"path: {text} is not a real-valued quantity")
    return tuple(leaf), tuple(segments), obj


def _check_path_value(cfg: RigConfig, r: BenignRange, leaf: Leaf, value: float) -> None:
    """The rig must stay valid with the path parameter at ``value`` (field limits, e.g. poisson < 0.5)."""
    data = cfg.model_dump(by_alias=True, exclude={"variability"})
    node: Any = data
    for part in leaf[:-1]:
        node = node[part]
    if isinstance(node, tuple):
        raise ValueError(f"path: {r.path} is inside a fixed pair")
    node[leaf[-1]] = value
    try:
        RigConfig.model_validate(data)
    except ValidationError as exc:
        field, msg = first_error(exc)
        raise ValueError(f"{r.form}: {r.path} = {value:g} is not a valid rig ({field}: {msg})") from None


def _resolve_one(cfg: RigConfig, r: BenignRange) -> ResolvedBenign:
    p = r.parameter
    need = BENIGN_KIND.get(p)
    if need is not None and cfg.kind != need:
        raise ValueError(f"parameter: {p} applies to {need} rigs only (this rig is {cfg.kind})")
    pct = "%"
    if p == "speed":
        assert r.rpm is not None
        return ResolvedBenign("speed", "offset", -r.rpm, r.rpm, "rpm", ("speed",), ())
    if p in ("sensor_gain", "actuator_gain"):
        lo, hi = _factor_range(r, 1.0, p)
        _check_floor(r, lo, p)
        return ResolvedBenign(p, "factor", lo, hi, pct, ("gain", p.split("_")[0]), ())
    if p == "youngs_modulus":
        if r.material is not None:
            if r.material not in cfg.materials:
                known = ", ".join(cfg.materials) or "none"
                raise ValueError(f"material: unknown material {r.material!r} (known: {known})")
            names = [r.material]
        else:
            names = list(cfg.materials)
        moduli = {cfg.materials[m].youngs_modulus for m in names}
        if r.form in ("absolute", "temperature_c") and len(moduli) > 1:
            raise ValueError(f"material: required for {r.form} (the materials differ in youngs_modulus)")
        nominal = next(iter(moduli))
        if r.temperature_c is not None:
            assert r.de_dt is not None and r.reference_c is not None
            ends = [r.de_dt * (t - r.reference_c) / nominal for t in r.temperature_c]
            lo, hi = min(ends), max(ends)
        else:
            lo, hi = _factor_range(r, nominal, "youngs_modulus")
        _check_floor(r, lo, "youngs_modulus")
        leaves: list[Leaf] = []
        for m in names:
            leaves.append(("materials", m, "youngs_modulus"))
            if cfg.materials[m].shear_modulus is not None:
                leaves.append(("materials", m, "shear_modulus"))
        name = "youngs_modulus" if r.material is None else f"youngs_modulus.{r.material}"
        target = ("materials", r.material or "*", "youngs_modulus")
        return ResolvedBenign(name, "factor", lo, hi, pct, target, tuple(leaves))
    if p in ("bearing_stiffness", "bearing_damping"):
        assert r.bearing is not None
        k = _by_name(list(cfg.bearings), r.bearing, "bearing", "bearing")
        b = cfg.bearings[k]
        if p == "bearing_stiffness":
            what = f"bearing {r.bearing!r} stiffness"
            k_nominal: float | None = None
            if r.absolute is not None:
                if isinstance(b.kxx, SpeedTable) or isinstance(b.kyy, SpeedTable) or b.kxx != b.kyy:
                    raise ValueError(f"absolute: bearing {r.bearing!r} has kxx != kyy (or speed tables); give "
                                     "percent or range_percent")
                k_nominal = float(b.kxx)
            lo, hi = _factor_range(r, k_nominal, what)
            _check_floor(r, lo, what)
            leaves = [("bearings", k, c) for c in ("kxx", "kyy", "kxy", "kyx")]
            return ResolvedBenign(f"bearing_stiffness.{r.bearing}", "factor", lo, hi, pct,
                                  ("bearings", r.bearing, "stiffness"), tuple(leaves))
        what = f"bearing {r.bearing!r} damping"
        target = ("bearings", r.bearing, "damping")
        if r.absolute is not None:
            if isinstance(b.cxx, SpeedTable) or isinstance(b.cyy, SpeedTable) or b.cxx != b.cyy:
                raise ValueError(f"absolute: bearing {r.bearing!r} has cxx != cyy (or speed tables); give "
                                 "percent or range_percent")
            c = float(b.cxx)
            a, z = r.absolute
            if not a <= c <= z:
                raise ValueError(f"absolute: [{a:g}, {z:g}] does not contain the nominal {what} {c:g}")
            if a < 0:
                raise ValueError(f"absolute: lower bound {a:g} would make {what} < 0")
            leaves = [("bearings", k, "cxx"), ("bearings", k, "cyy")]
            return ResolvedBenign(f"bearing_damping.{r.bearing}", "offset", a - c, z - c, "N s/m", target,
                                  tuple(leaves))
        if not any(v != 0 for c in ("cxx", "cyy", "cxy", "cyx") for v in _values(getattr(b, c))):
            raise ValueError(f"{r.form}: bearing {r.bearing!r} has no damping (cxx = cyy = 0), a relative "
                             "range changes nothing; give absolute")
        lo, hi = _factor_range(r, None, what)
        _check_floor(r, lo, what, allow_zero=True)
        leaves = [("bearings", k, c) for c in ("cxx", "cyy", "cxy", "cyx")]
        return ResolvedBenign(f"bearing_damping.{r.bearing}", "factor", lo, hi, pct, target, tuple(leaves))
    if p in ("disc_mass", "mass", "spring_stiffness"):
        group, key, field, what_kind = {
            "disc_mass": ("discs", "disc", "mass", "disc"),
            "mass": ("masses", "mass", "mass", "mass"),
            "spring_stiffness": ("lumped_springs", "spring", "stiffness", "spring"),
        }[p]
        sel = getattr(r, key)
        k = _by_name(list(getattr(cfg, group)), sel, what_kind, key)
        nominal = float(getattr(getattr(cfg, group)[k], field))
        what = f"{what_kind} {sel!r} {field}"
        if nominal == 0:
            raise ValueError(f"{r.form}: {what} is 0 in the config; nothing to vary")
        lo, hi = _factor_range(r, nominal, what)
        _check_floor(r, lo, what)
        return ResolvedBenign(f"{p}.{sel}", "factor", lo, hi, pct, (group, sel, field), ((group, k, field),))
    # path
    assert r.path is not None
    leaf, segments, nominal = _resolve_path(cfg, r.path)
    name = f"path:{r.path.strip()}"
    if nominal == 0:
        if r.absolute is None:
            raise ValueError(f"{r.form}: {r.path} is 0 in the config, a relative range changes nothing; give absolute")
        a, z = r.absolute
        if not a <= 0 <= z:
            raise ValueError(f"absolute: [{a:g}, {z:g}] does not contain the nominal {r.path} 0")
        field = segments[-1] if not segments[-1].isdigit() else segments[-2]
        kind, lo, hi, unit = "offset", a, z, _FIELD_UNITS.get(field, "SI")
        extremes = (a, z)
    else:
        lo, hi = _factor_range(r, nominal, r.path)
        kind, unit = "factor", pct
        extremes = (nominal * (1 + lo), nominal * (1 + hi))
        if nominal > 0:
            _check_floor(r, lo, r.path, allow_zero=True)
    for value in extremes:
        _check_path_value(cfg, r, leaf, value)
    return ResolvedBenign(name, kind, lo, hi, unit, segments, (leaf,))


def resolve_benign(cfg: RigConfig) -> tuple[ResolvedBenign, ...]:
    """Every ``variability`` entry resolved against ``cfg``; ValueError ``"variability[i].key: ..."``.

    Low-level form behind the validation; use :func:`rotorcheck.variability.benign_parameters`.
    """
    out: list[ResolvedBenign] = []
    owner: dict[Leaf, int] = {}
    for i, r in enumerate(cfg.variability):
        try:
            res = _resolve_one(cfg, r)
        except ValueError as exc:
            msg = str(exc)
            head, _, tail = msg.partition(": ")
            if tail and " " not in head:
                raise ValueError(f"variability[{i}].{head}: {tail}") from None
            raise ValueError(f"variability[{i}]: {msg}") from None
        for j, prev in enumerate(out):
            if prev.name == res.name:
                raise ValueError(f"variability[{i}]: duplicate of variability[{j}] ({res.name})")
        for leaf in res.leaves:
            if leaf in owner:
                j = owner[leaf]
                raise ValueError(f"variability[{i}]: {res.name} changes {leaf_text(leaf)}, which "
                                 f"variability[{j}] ({out[j].name}) already varies; give each quantity one range")
            owner[leaf] = i
        out.append(res)
    return tuple(out)

