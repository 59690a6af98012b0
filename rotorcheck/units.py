"""Quantities with units in config files: bare numbers are SI, strings like ``"16 mm"`` are converted.

Only a small, explicit table of units per physical dimension is accepted; a unit of the wrong
dimension (``"16 kg"`` for a length) or an unknown unit is an error, never a guess.
"""

from __future__ import annotations

import math
import re

# factor to SI for each accepted unit, per dimension
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "µm": 1e-6, "in": 0.0254},
    "mass": {"kg": 1.0, "g": 1e-3},
    "density": {"kg/m^3": 1.0, "kg/m3": 1.0, "g/cm^3": 1e3, "g/cm3": 1e3},
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m^2": 1.0},
    "receptance": {"m/N": 1.0, "mm/N": 1e-3, "um/N": 1e-6, "µm/N": 1e-6, "nm/N": 1e-9},
    "stiffness": {"N/m": 1.0, "N/mm": 1e3, "kN/m": 1e3, "MN/m": 1e6, "N/um": 1e6},
    "damping": {"N s/m": 1.0, "Ns/m": 1.0, "N*s/m": 1.0, "kg/s": 1.0},
    "inertia": {"kg m^2": 1.0, "kg*m^2": 1.0, "kg m2": 1.0, "g mm^2": 1e-9, "kg mm^2": 1e-6},
    "frequency": {"Hz": 1.0, "kHz": 1e3, "rad/s": 1.0 / (2.0 * math.pi)},
    "speed": {"rpm": 1.0, "Hz": 60.0, "rad/s": 60.0 / (2.0 * math.pi)},
    "force": {"N": 1.0, "kN": 1e3, "MN": 1e6},
    "moment": {"N m": 1.0, "N*m": 1.0, "Nm": 1.0, "kN m": 1e3, "kN*m": 1e3, "kNm": 1e3},
    "unbalance": {"kg m": 1.0, "kg*m": 1.0, "g m": 1e-3, "g*m": 1e-3, "g mm": 1e-6, "g*mm": 1e-6},
    "angle": {"deg": math.pi / 180.0, "rad": 1.0},
    "dimensionless": {"": 1.0, "%": 0.01},
    "time": {"s": 1.0, "ms": 1e-3},
}

_NUM = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


class UnitError(ValueError):
    """A quantity string whose unit is unknown or of the wrong dimension."""


def parse_quantity(value: object, dimension: str) -> float:
    """Return ``value`` in SI units of ``dimension`` (speed: rpm; frequency: Hz; angle: rad).

    Accepts a bare number (already SI) or a string ``"<number> <unit>"``; NaN and infinite values
    (``1e400`` overflows to inf) are refused.
    """
    out = _parse(value, dimension)
    if not math.isfinite(out):
        raise UnitError(f"{value!r} is not a finite number (NaN, inf, or beyond the float range)")
    return out


def _parse(value: object, dimension: str) -> float:
    if isinstance(value, bool):
        raise UnitError("expected a number, got a boolean")
    if isinstance(value, (int, float)):
        return float(value)
    if not isinstance(value, str):
        raise UnitError(f"expected a number or a '<number> <unit>' string, got {type(value).__name__}")
    m = _NUM.match(value)
    if not m:
        raise UnitError(f"cannot read a number with a unit from {value!r}")
    number, unit = float(m.group(1)), m.group(2)
    if unit == "":  # YAML 1.1 reads 1.65e7 (no dot, unsigned exponent) as a string
        return number
    table = UNITS[dimension]
    if unit in table:
        return number * table[unit]
    allowed = ", ".join(repr(u) for u in table if u) or "no unit"
    raise UnitError(f"unit {unit!r} is not a {dimension} unit (use one of {allowed} or a bare SI number)")


#: the receptance units the plots draw in (``--frf-unit``)
PLOT_FRF_UNITS: tuple[str, ...] = ("m/N", "mm/N", "um/N")
