"""Benign variability: the normalized view of a rig's ``variability:`` section.

A benign parameter is an operating or environmental quantity that changes between healthy runs
(temperature through Young's modulus, bearing stiffness and damping, sensor and actuator gains, spin
speed, ...): the detector must not call such a change damage. The YAML section is validated in
:mod:`rotorcheck.config` (:class:`~rotorcheck.config.BenignRange`); this module gives detection code

- :func:`benign_parameters`: one :class:`BenignParameter` per entry, its range as a relative change
  (``kind == "factor"``: value = nominal (1 + x)) or an offset (``kind == "offset"``: value = nominal
  + x; the speed in rpm, an absolute bearing-damping range in N s/m, a path parameter whose nominal
  is 0);
- :func:`with_benign`: the rig with chosen values x applied (a new, frozen config), plus the parts
  that are not config changes (speed offset, sensor and actuator gain factors);
- :func:`recentred_rig`: the rig with its ranges moved and widened (drift learned from several sweeps).

Ranges are relative to the config the section belongs to (the nominal rig); ``with_benign`` does
not re-derive them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel

from rotorcheck.config import BenignRange, Leaf, ResolvedBenign, RigConfig, SpeedTable, leaf_text, resolve_benign

__all__ = ["BenignParameter", "benign_at", "benign_parameters", "pair_ranges", "recentred_rig", "with_benign"]


@dataclass(frozen=True)
class BenignParameter:
    """One benign parameter of a rig and its range."""

    name: str  # stable display/report name, e.g. "youngs_modulus", "bearing_stiffness.nme", "speed"
    kind: str  # "factor" (value = nominal * (1 + x)) or "offset" (value = nominal + x)
    lo: float  # range of x: relative change for "factor", absolute offset for "offset"
    hi: float
    unit: str  # unit of x for display: "%" (show x * 100) for factors, "rpm", "N s/m", ...
    target: tuple[str, ...]  # what it touches, e.g. ("bearings", "nme", "stiffness"), ("speed",)

    @property
    def is_gain(self) -> bool:
        """A transducer gain: it scales the measured FRF, the model is not re-solved."""
        return self.target[0] == "gain"

    @property
    def is_speed(self) -> bool:
        return self.target[0] == "speed"

    @property
    def changes_model(self) -> bool:
        """A parameter of the rig description (not a gain, not the speed)."""
        return not (self.is_gain or self.is_speed)


def _public(r: ResolvedBenign) -> BenignParameter:
    return BenignParameter(name=r.name, kind=r.kind, lo=r.lo, hi=r.hi, unit=r.unit, target=r.target)


def benign_parameters(config: RigConfig) -> tuple[BenignParameter, ...]:
    """The rig's benign parameters, in the order of its ``variability:`` section (empty without one)."""
    return tuple(_public(r) for r in resolve_benign(config))


def _set(obj: Any, leaf: Leaf, fn: Callable[[float], float]) -> Any:
    """``obj`` with the value at ``leaf`` replaced by ``fn(value)`` (a speed table: every value)."""
    if not leaf:
        if isinstance(obj, SpeedTable):
            return obj.model_copy(update={"values": [fn(float(v)) for v in obj.values]})
        return fn(float(obj))
    head, rest = leaf[0], leaf[1:]
    if isinstance(obj, BaseModel):
        assert isinstance(head, str)
        return obj.model_copy(update={head: _set(getattr(obj, head), rest, fn)})
    if isinstance(obj, dict):
        return {**obj, head: _set(obj[head], rest, fn)}
    if isinstance(obj, (list, tuple)):
        assert isinstance(head, int)
        items = list(obj)
        items[head] = _set(items[head], rest, fn)
        return type(obj)(items) if isinstance(obj, tuple) else items
    raise TypeError(f"cannot follow {head!r} into {type(obj).__name__}")


def _get(obj: Any, leaf: Leaf) -> Any:
    for part in leaf:
        obj = getattr(obj, str(part)) if isinstance(obj, BaseModel) else obj[part]
    return obj


def _scale(factor: float) -> Callable[[float], float]:
    return lambda v: v * factor


def _shift(offset: float) -> Callable[[float], float]:
    return lambda v: v + offset


def benign_at(config: RigConfig, speed_rpm: float) -> tuple[BenignParameter, ...]:
    """The rig's benign parameters that act at ``speed_rpm`` (at standstill a speed tolerance does not)."""
    return tuple(p for p in benign_parameters(config) if not (p.is_speed and speed_rpm == 0.0))


def with_benign(config: RigConfig, values: Mapping[str, float]) -> tuple[RigConfig, float, float, float]:
    """config with the benign parameter values applied; returns (new_config, speed_offset_rpm,
    sensor_gain_factor, actuator_gain_factor).

    ``values`` maps :attr:`BenignParameter.name` -> x (relative change for factors, offset for
    offsets); names not in the config's variability are an error (ValueError naming them); missing
    names mean 0. Values outside the configured range are applied (a detector may probe beyond it)
    but must keep the quantity physical: a factor needs 1 + x > 0 (>= 0 for bearing damping), an
    offset must not make a bearing's damping negative.

    Bearing stiffness scales kxx, kyy, kxy, kyx (speed tables: every value); bearing damping scales
    cxx, cyy, cxy, cyx (factor) or adds to cxx, cyy (offset); Young's modulus scales E and, when
    given, shear_modulus of every material (or the one named) by the same factor. Speed and gains
    are not config changes: they are returned (``speed_offset_rpm`` adds to the spin speed, the gain
    factors multiply the measured output and the applied force).
    """
    resolved = resolve_benign(config)
    known = [r.name for r in resolved]
    unknown = [name for name in values if name not in known]
    if unknown:
        raise ValueError(
            f"not benign parameters of rig {config.rig_id!r}: {', '.join(map(str, unknown))} "
            f"(its variability section has: {', '.join(known) or 'none'})"
        )
    speed_offset, sensor, actuator = 0.0, 1.0, 1.0
    new = config
    for r in resolved:
        x = float(values.get(r.name, 0.0))
        if not math.isfinite(x):
            raise ValueError(f"{r.name}: value must be finite, got {x}")
        if r.target == ("speed",):
            speed_offset = x
            continue
        if r.kind == "factor":
            floor_ok = 1.0 + x >= 0.0 if r.name.startswith("bearing_damping.") else 1.0 + x > 0.0
            if not floor_ok:
                raise ValueError(f"{r.name}: x = {x:g} (a {100 * x:g} % change) would make the quantity <= 0")
        if r.target == ("gain", "sensor"):
            sensor = 1.0 + x
            continue
        if r.target == ("gain", "actuator"):
            actuator = 1.0 + x
            continue
        if x == 0.0:
            continue
        if r.kind == "factor":
            factor = 1.0 + x
            for leaf in r.leaves:
                new = _set(new, leaf, _scale(factor))
        else:
            for leaf in r.leaves:
                if r.name.startswith("bearing_damping.") and float(_get(new, leaf)) + x < 0:
                    raise ValueError(f"{r.name}: offset {x:g} would make {leaf_text(leaf)} < 0")
                new = _set(new, leaf, _shift(x))
    return new, speed_offset, sensor, actuator


def recentred_rig(rig: RigConfig, shift: dict[str, float], widen: dict[str, float]) -> RigConfig:
    """``rig`` with each named benign factor's range ``[lo, hi]`` moved to ``[lo + shift - widen, hi + shift + widen]``
    (relative changes; written as ``range_percent``). The speed tolerance and offsets (``absolute`` ranges of an
    offset kind, which must hold the nominal value) keep their declared ranges."""
    if not shift and not widen:
        return rig
    params = benign_parameters(rig)
    entries: list[BenignRange] = []
    for r, p in zip(rig.variability, params):
        s, w = float(shift.get(p.name, 0.0)), float(widen.get(p.name, 0.0))
        if (s == 0.0 and w == 0.0) or p.is_speed or p.kind != "factor":
            entries.append(r)
            continue
        lo, hi = max(p.lo + s - w, -0.99), p.hi + s + w
        data = r.model_dump(exclude_none=True)
        for key in ("percent", "range_percent", "absolute", "temperature_c", "reference_c", "de_dt"):
            data.pop(key, None)
        data["range_percent"] = (100.0 * lo, 100.0 * hi)
        entries.append(BenignRange.model_validate(data))
    return rig.model_copy(update={"variability": entries})


def pair_ranges(rig: RigConfig, speed_rpm: float) -> RigConfig:
    """``rig`` with every benign factor's range ``[lo, hi]`` replaced by ``[lo - hi, hi - lo]``: the change between
    two states inside the declared ranges (what one healthy sweep may differ from another by)."""
    params = benign_at(rig, speed_rpm)
    return recentred_rig(rig, {p.name: -(p.lo + p.hi) / 2.0 for p in params},
                         {p.name: (p.hi - p.lo) / 2.0 for p in params})
