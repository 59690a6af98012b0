"""The ``variability`` section's schema: benign parameter ranges as written in the rig file."""

from __future__ import annotations

from typing import Annotated, Any, Literal, get_args

from pydantic import BeforeValidator, Field, model_validator

from rotorcheck.config.base import Strict
from rotorcheck.config.quantities import SpeedRpm
from rotorcheck.units import parse_quantity

BenignName = Literal[
    "youngs_modulus",
    "bearing_stiffness",
    "bearing_damping",
    "sensor_gain",
    "actuator_gain",
    "speed",
    "disc_mass",
    "mass",
    "spring_stiffness",
    "path",
]


BENIGN_PARAMETERS: tuple[str, ...] = get_args(BenignName)


#: the forms of a range; an entry gives exactly one
BENIGN_FORMS = ("percent", "range_percent", "absolute", "rpm", "temperature_c")


#: the key that names what a parameter changes (youngs_modulus: optional, all materials without it)
_BENIGN_SELECTOR = {
    "youngs_modulus": "material",
    "bearing_stiffness": "bearing",
    "bearing_damping": "bearing",
    "disc_mass": "disc",
    "mass": "mass",
    "spring_stiffness": "spring",
    "path": "path",
}


#: physical dimension of an ``absolute`` range (quantity strings are converted); path: bare SI numbers
_BENIGN_DIMENSION = {
    "youngs_modulus": "pressure",
    "bearing_stiffness": "stiffness",
    "bearing_damping": "damping",
    "sensor_gain": "dimensionless",
    "actuator_gain": "dimensionless",
    "disc_mass": "mass",
    "mass": "mass",
    "spring_stiffness": "stiffness",
}


BENIGN_KIND = {  # parameters that apply to one rig kind only
    "youngs_modulus": "rotor",
    "bearing_stiffness": "rotor",
    "bearing_damping": "rotor",
    "disc_mass": "rotor",
    "speed": "rotor",
    "mass": "lumped",
    "spring_stiffness": "lumped",
}


#: top-level sections a ``path`` parameter may reach (the model, not analysis, faults or ports)
BENIGN_PATH_ROOTS = (
    "materials", "stations", "shaft", "discs", "bearings", "springs", "masses", "lumped_springs", "damping",
)


def _parse_de_dt(value: Any) -> float:
    """dE/dT in Pa/K: a number or a string such as ``"-60 MPa/K"``."""
    if isinstance(value, str):
        s = value.strip()
        for suffix in ("/K", "/degC", "/°C"):
            if s.endswith(suffix):
                return parse_quantity(s[: -len(suffix)].strip() or "1", "pressure")
        try:
            return float(s)
        except ValueError:
            raise ValueError(f"expected Pa/K: a number or a string such as '-60 MPa/K', got {value!r}") from None
    return parse_quantity(value, "pressure")


class BenignRange(Strict):
    """One benign parameter and its range (``variability:``): a change the detector must not call damage.

    ``parameter`` names the quantity; ``material`` / ``bearing`` / ``disc`` / ``mass`` / ``spring`` /
    ``path`` say which one. Exactly one range form: ``percent`` (symmetric, % of nominal),
    ``range_percent: [lo, hi]`` (% of nominal), ``absolute: [lo, hi]`` (the value itself, SI or a
    quantity string; must contain the nominal), ``rpm`` (speed only: +- rpm) or ``temperature_c: [lo,
    hi]`` with ``reference_c`` and ``de_dt`` (youngs_modulus only: E(T) = E + de_dt (T - reference_c),
    E the config's value, de_dt in Pa/K). See :mod:`rotorcheck.variability` for the normalized view.
    """

    parameter: BenignName
    material: str | None = Field(default=None, description="youngs_modulus: one material (default all)")
    bearing: str | None = Field(default=None, description="bearing_stiffness, bearing_damping: bearing name")
    disc: str | None = Field(default=None, description="disc_mass: disc name")
    mass: str | None = Field(default=None, description="mass: lumped mass name")
    spring: str | None = Field(default=None, description="spring_stiffness: lumped spring name")
    path: str | None = Field(default=None, description="path: dotted path of a real-valued config field")
    percent: float | None = Field(default=None, gt=0, description="symmetric range, +- % of nominal")
    range_percent: tuple[float, float] | None = Field(default=None, description="[lo, hi], % of nominal")
    absolute: tuple[float, float] | None = Field(default=None, description="[lo, hi] of the value, SI")
    rpm: SpeedRpm | None = Field(default=None, gt=0, description="speed: +- rpm")
    temperature_c: tuple[float, float] | None = Field(default=None, description="youngs_modulus: [lo, hi], degC")
    reference_c: float | None = Field(default=None, description="temperature of the config's E, degC")
    de_dt: Annotated[float, BeforeValidator(_parse_de_dt)] | None = Field(default=None, description="dE/dT, Pa/K")

    @model_validator(mode="before")
    @classmethod
    def _convert(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        data = dict(data)
        if "parameter" not in data and "path" in data:
            data["parameter"] = "path"
        absolute = data.get("absolute")
        param = data.get("parameter")
        if isinstance(param, str) and param not in BENIGN_PARAMETERS:
            raise ValueError(f"parameter: unknown parameter {param!r} (known: {', '.join(BENIGN_PARAMETERS)})")
        if isinstance(absolute, (list, tuple)) and isinstance(param, str) and param in BENIGN_PARAMETERS:
            dim = _BENIGN_DIMENSION.get(param)
            out = []
            for v in absolute:
                if isinstance(v, str):
                    try:
                        v = parse_quantity(v, dim) if dim else float(v)
                    except ValueError as exc:
                        why = exc if dim else f"a path parameter takes bare SI numbers, got {v!r}"
                        raise ValueError(f"absolute: {why}") from None
                out.append(v)
            data["absolute"] = out
        return data

    @model_validator(mode="after")
    def _form(self) -> BenignRange:
        given = [f for f in BENIGN_FORMS if getattr(self, f) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of " + ", ".join(BENIGN_FORMS))
        form, p = given[0], self.parameter
        if p == "speed" and form != "rpm":
            raise ValueError(f"{form}: speed takes rpm (a +- tolerance in rpm)")
        if form == "rpm" and p != "speed":
            raise ValueError(f"rpm: only for parameter speed, not {p}")
        if form == "temperature_c" and p != "youngs_modulus":
            raise ValueError(f"temperature_c: only for parameter youngs_modulus, not {p}")
        for extra in ("reference_c", "de_dt"):
            value = getattr(self, extra)
            if form == "temperature_c" and value is None:
                raise ValueError(f"{extra}: required with temperature_c")
            if form != "temperature_c" and value is not None:
                raise ValueError(f"{extra}: only with temperature_c")
        if self.de_dt == 0:
            raise ValueError("de_dt: must not be 0")
        for pair in ("range_percent", "absolute", "temperature_c"):
            v = getattr(self, pair)
            if v is not None and not v[0] < v[1]:
                raise ValueError(f"{pair}: must be [lo, hi] with lo < hi")
        wanted = _BENIGN_SELECTOR.get(p)
        for key in ("material", "bearing", "disc", "mass", "spring", "path"):
            if getattr(self, key) is not None and key != wanted:
                raise ValueError(f"{key}: not used by parameter {p}")
        if wanted is not None and wanted != "material" and getattr(self, wanted) is None:
            raise ValueError(f"{wanted}: required for parameter {p}")
        return self

    @property
    def form(self) -> str:
        """The range form given: one of :data:`BENIGN_FORMS`."""
        return next(f for f in BENIGN_FORMS if getattr(self, f) is not None)

