"""Rig description (YAML), validated on load.

Two model kinds share one config family:

- ``kind: rotor``: a Timoshenko finite element rotor (stations, shaft elements, discs, bearings).
- ``kind: lumped``: masses, springs and dampers to ground or between masses (the three-mass example).

Bare numbers are SI; strings such as ``"16 mm"`` or ``"224.08 GPa"`` are converted (see
:mod:`rotorcheck.units`). Unknown keys are rejected. Errors name the file and the field by path,
e.g. ``configs/x.yaml: bearings[1].kxx: must be > 0``.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, NamedTuple, get_args

import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    model_validator,
)

from rotorcheck.errors import InputError
from rotorcheck.fileio import read_bounded_text
from rotorcheck.units import parse_quantity

# --------------------------------------------------------------------------------------------
# quantity types


def _q(dimension: str) -> Any:
    return BeforeValidator(lambda v: parse_quantity(v, dimension))


Length = Annotated[float, _q("length")]
Mass = Annotated[float, _q("mass")]
Density = Annotated[float, _q("density")]
Pressure = Annotated[float, _q("pressure")]
Stiffness = Annotated[float, _q("stiffness")]
Damping = Annotated[float, _q("damping")]
Inertia = Annotated[float, _q("inertia")]
FrequencyHz = Annotated[float, _q("frequency")]
SpeedRpm = Annotated[float, _q("speed")]
Force = Annotated[float, _q("force")]
Moment = Annotated[float, _q("moment")]
Unbalance = Annotated[float, _q("unbalance")]
Angle = Annotated[float, _q("angle")]
Ratio = Annotated[float, _q("dimensionless")]


class Strict(BaseModel):
    """Base: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)


# --------------------------------------------------------------------------------------------
# rotor parts


class Material(Strict):
    density: Density = Field(gt=0, le=1e5, description="kg/m^3 (plausible: up to 1e5)")
    youngs_modulus: Pressure = Field(gt=0, le=1e20, description="Pa (up to 1e20: a near-rigid stand-in)")
    shear_modulus: Pressure | None = Field(default=None, gt=0, le=1e20, description="Pa")
    poisson: Ratio | None = Field(default=None, ge=0, lt=0.5, description="Poisson's ratio")

    @model_validator(mode="after")
    def _shear(self) -> Material:
        if self.shear_modulus is None and self.poisson is None:
            raise ValueError("give shear_modulus or poisson")
        return self

    def consistency_note(self, name: str) -> str | None:
        """With E, G and Poisson's ratio all given, a note when ``E / 2G - 1`` differs from ``poisson`` by
        more than 0.02: G is what the shear stiffness uses, ``poisson`` what the shear coefficient uses."""
        if self.shear_modulus is None or self.poisson is None:
            return None
        implied = self.youngs_modulus / (2.0 * self.shear_modulus) - 1.0
        if abs(implied - self.poisson) <= 0.02:
            return None
        return (f"materials.{name}: E / 2G - 1 = {implied:.3f} beside poisson {self.poisson:g}: the shear stiffness "
                f"uses shear_modulus, the shear coefficient (and crack compliance) poisson")

    @property
    def G(self) -> float:
        """Shear modulus (Pa), from ``poisson`` when not given."""
        if self.shear_modulus is not None:
            return self.shear_modulus
        assert self.poisson is not None
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson))

    @property
    def nu(self) -> float:
        """Poisson's ratio, from E and G when not given."""
        if self.poisson is not None:
            return self.poisson
        return self.youngs_modulus / (2.0 * self.G) - 1.0


ShearMethod = Literal["hutchinson", "cowper"]


class TaperedSection:
    """Diameters of a linearly tapered hollow section: ``outer_diameter`` / ``inner_diameter`` at the
    start, ``*_right`` at the end (None: as at the start). A mixin of the rig's shaft element and the
    mesh's element info."""

    if TYPE_CHECKING:
        outer_diameter: float
        inner_diameter: float
        outer_diameter_right: float | None
        inner_diameter_right: float | None

    @property
    def outer_right(self) -> float:
        """Outer diameter at the end (m)."""
        return self.outer_diameter if self.outer_diameter_right is None else self.outer_diameter_right

    @property
    def inner_right(self) -> float:
        """Inner diameter at the end (m)."""
        return self.inner_diameter if self.inner_diameter_right is None else self.inner_diameter_right

    @property
    def tapered(self) -> bool:
        """True when a diameter changes along the element."""
        return self.outer_right != self.outer_diameter or self.inner_right != self.inner_diameter


class ShaftElement(Strict, TaperedSection):
    """A shaft segment between two stations (1-based), optionally split into ``refine`` elements.

    A linear taper: ``outer_diameter_right`` / ``inner_diameter_right`` at the ``end`` station
    (default: as at the start). Several entries on one station pair are concentric layers (a sleeve,
    a hub, a shrink fit): their matrices add. ``shear_method`` / ``shear_coefficient`` / ``shear`` /
    ``rotary_inertia`` / ``gyroscopic`` override the rig-level settings of the same name.
    """

    start: int = Field(ge=1, description="first station (1-based)")
    end: int = Field(ge=1, description="second station (1-based)")
    material: str
    outer_diameter: Length = Field(gt=0, le=100.0, description="m, at the start station")
    inner_diameter: Length = Field(default=0.0, ge=0, description="m, at the start station")
    outer_diameter_right: Length | None = Field(default=None, gt=0, description="m, at the end station (taper)")
    inner_diameter_right: Length | None = Field(default=None, ge=0, description="m, at the end station (taper)")
    refine: int = Field(default=1, ge=1, le=64, description="sub-elements")
    modulus_factor: Ratio = Field(default=1.0, gt=0, description="E multiplier (open crack)")
    axial_force: Force = Field(default=0.0, description="N, tension positive (geometric stiffness)")
    torque: Moment = Field(default=0.0, description="N m, about +z (geometric stiffness)")
    shear_method: ShearMethod | None = Field(default=None, description="shear coefficient formula")
    shear_coefficient: Ratio | None = Field(default=None, gt=0, le=2, description="kappa, overrides the formula")
    shear: bool | None = Field(default=None, description="shear deformation (False: Euler-Bernoulli)")
    rotary_inertia: bool | None = None
    gyroscopic: bool | None = None

    @model_validator(mode="after")
    def _geometry(self) -> ShaftElement:
        if self.end != self.start + 1:
            raise ValueError("end must be start + 1 (elements join neighbouring stations)")
        if self.inner_diameter >= self.outer_diameter:
            raise ValueError("inner_diameter must be < outer_diameter")
        if self.shear is False:
            for key in ("shear_method", "shear_coefficient"):
                if getattr(self, key) is not None:
                    raise ValueError(f"{key}: unused with shear: false (the element has no shear deformation)")
        if self.shear_method is not None and self.shear_coefficient is not None:
            raise ValueError("shear_coefficient: give shear_method or shear_coefficient, not both")
        if self.inner_diameter_right is not None and self.inner_diameter_right >= self.outer_right:
            raise ValueError("inner_diameter_right must be < outer_diameter_right")
        if self.inner_diameter_right is None and self.outer_diameter_right is not None \
                and self.inner_diameter >= self.outer_diameter_right:
            raise ValueError("inner_diameter_right: give it (the bore would exceed outer_diameter_right)")
        return self


class Disc(Strict):
    """A rigid disc at a station: mass and inertias, or its geometry and material.

    Geometry (a solid or bored cylinder of ``width`` along the shaft): ``m = rho pi w (D^2 - d^2) / 4``,
    ``Ip = m (D^2 + d^2) / 8``, ``Id = Ip / 2 + m w^2 / 12``.
    """

    name: str = "disc"
    station: int = Field(ge=1)
    mass: Mass | None = Field(default=None, gt=0, le=1e7, description="kg")
    polar_inertia: Inertia | None = Field(default=None, ge=0, le=1e9, description="kg m^2")
    transverse_inertia: Inertia | None = Field(default=None, ge=0, le=1e9, description="kg m^2")
    material: str | None = Field(default=None, description="by geometry: material name")
    width: Length | None = Field(default=None, gt=0, description="by geometry: axial width, m")
    outer_diameter: Length | None = Field(default=None, gt=0, description="by geometry: m")
    inner_diameter: Length | None = Field(default=None, ge=0, description="by geometry: bore, m")

    @model_validator(mode="after")
    def _form(self) -> Disc:
        inertial = [k for k in ("mass", "polar_inertia", "transverse_inertia") if getattr(self, k) is not None]
        geometric = [k for k in ("material", "width", "outer_diameter", "inner_diameter")
                     if getattr(self, k) is not None]
        if inertial and geometric:
            raise ValueError(f"{geometric[0]}: give mass and inertias or geometry (material, width, "
                             "outer_diameter, inner_diameter), not both")
        if geometric:
            for k in ("material", "width", "outer_diameter"):
                if getattr(self, k) is None:
                    raise ValueError(f"{k}: required for a disc given by its geometry")
            assert self.outer_diameter is not None
            if (self.inner_diameter or 0.0) >= self.outer_diameter:
                raise ValueError("inner_diameter: must be < outer_diameter")
            return self
        for k in ("mass", "polar_inertia", "transverse_inertia"):
            if getattr(self, k) is None:
                raise ValueError(f"{k}: required field is missing (or give the disc's material, width and diameters)")
        return self

    def inertias(self, materials: dict[str, Material]) -> tuple[float, float, float]:
        """(mass kg, polar inertia kg m^2, transverse inertia kg m^2)."""
        if self.material is None:
            assert self.mass is not None and self.polar_inertia is not None and self.transverse_inertia is not None
            return self.mass, self.polar_inertia, self.transverse_inertia
        assert self.width is not None and self.outer_diameter is not None
        rho = materials[self.material].density
        D, d, w = self.outer_diameter, self.inner_diameter or 0.0, self.width
        m = rho * math.pi * w * (D**2 - d**2) / 4.0
        ip = m * (D**2 + d**2) / 8.0
        return m, ip, ip / 2.0 + m * w**2 / 12.0


class PointMass(Strict):
    """A point mass (kg) at a shaft station or a support node: translation only, no inertia."""

    name: str = "point_mass"
    station: int = Field(ge=1, description="shaft station, or a support node numbered after the last station")
    mass: Mass | None = Field(default=None, gt=0, le=1e7, description="kg, both directions")
    mx: Mass | None = Field(default=None, gt=0, le=1e7, description="kg, x only (with my)")
    my: Mass | None = Field(default=None, gt=0, le=1e7, description="kg, y only (with mx)")

    @model_validator(mode="after")
    def _form(self) -> PointMass:
        if self.mass is not None and (self.mx is not None or self.my is not None):
            raise ValueError("mass: give mass, or mx and my, not both")
        if self.mass is None and (self.mx is None or self.my is None):
            raise ValueError("mass: required field is missing (or mx and my)")
        return self

    @property
    def masses(self) -> tuple[float, float]:
        """(m_x, m_y), kg."""
        if self.mass is not None:
            return self.mass, self.mass
        assert self.mx is not None and self.my is not None
        return self.mx, self.my


class SpeedTable(Strict):
    """A coefficient tabulated against speed, linearly interpolated; outside the table held constant
    (``hold``) or extrapolated linearly from the end segments (``linear``), as its bearing's ``extrapolate``
    says."""

    speed_rpm: list[SpeedRpm] = Field(min_length=1)
    values: list[float] = Field(min_length=1)

    @model_validator(mode="after")
    def _table(self) -> SpeedTable:
        if len(self.speed_rpm) != len(self.values):
            raise ValueError("speed_rpm and values must have the same length")
        if any(b <= a for a, b in zip(self.speed_rpm, self.speed_rpm[1:])):
            raise ValueError("speed_rpm must be strictly increasing")
        return self

    def at(self, speed_rpm: float, extrapolate: str = "hold") -> float:
        """The coefficient at ``speed_rpm``; ``extrapolate``: ``"hold"`` or ``"linear"`` outside the table."""
        import numpy as np

        x, y = self.speed_rpm, self.values
        if extrapolate == "linear" and len(x) > 1 and not (x[0] <= speed_rpm <= x[-1]):
            i = 0 if speed_rpm < x[0] else len(x) - 2
            return float(y[i] + (y[i + 1] - y[i]) * (speed_rpm - x[i]) / (x[i + 1] - x[i]))
        return float(np.interp(speed_rpm, x, y))


#: a bearing's lateral coefficients (stiffness, damping, mass; x, y and cross terms)
BEARING_TERMS = ("kxx", "kyy", "kxy", "kyx", "cxx", "cyy", "cxy", "cyx", "mxx", "myy", "mxy", "myx")


class Bearing(Strict):
    """Linear bearing, seal or support at a station: stiffness (N/m), damping (N s/m), mass (kg).

    To ground, or with ``n_link`` between the station and another node (a shaft station, or a support
    node numbered after the last station: a pedestal, which carries a point mass). The force is
    ``-(K + j w C - w^2 Mb)`` times the relative displacement. Direct stiffness may be zero or
    negative (a seal, a magnetic bearing's negative stiffness); the model then warns where the
    assembled static stiffness is not positive definite.
    """

    name: str = "bearing"
    station: int = Field(ge=1)
    n_link: int | None = Field(default=None, ge=1, description="the other node (station or support node)")
    kxx: Stiffness | SpeedTable
    kyy: Stiffness | SpeedTable
    kxy: Stiffness | SpeedTable = 0.0
    kyx: Stiffness | SpeedTable = 0.0
    cxx: Damping | SpeedTable = 0.0
    cyy: Damping | SpeedTable = 0.0
    cxy: Damping | SpeedTable = 0.0
    cyx: Damping | SpeedTable = 0.0
    mxx: Mass | SpeedTable = 0.0
    myy: Mass | SpeedTable = 0.0
    mxy: Mass | SpeedTable = 0.0
    myx: Mass | SpeedTable = 0.0
    extrapolate: Literal["hold", "linear"] = Field(
        default="hold", description="speed tables outside their speeds: hold the end value (default) or extrapolate "
        "the end segment linearly (as ROSS extrapolates its interpolants; damping and mass may then turn negative)")

    @model_validator(mode="after")
    def _signs(self) -> Bearing:
        for name in ("cxx", "cyy", "mxx", "myy"):
            v = getattr(self, name)
            vals = v.values if isinstance(v, SpeedTable) else [v]
            if any(x < 0 for x in vals):
                raise ValueError(f"{name}: must be >= 0")
        if self.n_link is not None and self.n_link == self.station:
            raise ValueError("n_link: must differ from station")
        return self

    def coefficients(self, speed_rpm: float) -> dict[str, float]:
        """All twelve coefficients at ``speed_rpm`` (SI)."""
        out = {}
        for name in BEARING_TERMS:
            v = getattr(self, name)
            out[name] = v.at(speed_rpm, self.extrapolate) if isinstance(v, SpeedTable) else float(v)
        return out


class StationSpring(Strict):
    """Extra linear spring/damper from a station to ground (e.g. a coupling)."""

    name: str = "spring"
    station: int = Field(ge=1)
    kxx: Stiffness = Field(default=0.0, ge=0)
    kyy: Stiffness = Field(default=0.0, ge=0)
    cxx: Damping = Field(default=0.0, ge=0)
    cyy: Damping = Field(default=0.0, ge=0)
    k_rot: Stiffness = Field(default=0.0, ge=0, description="rotational stiffness, N m/rad")


class ModalDamping(Strict):
    """Damping built from the undamped modes: C = M Phi diag(2 zeta_i w_i) Phi^T M."""

    kind: Literal["modal"] = "modal"
    ratios: list[Ratio] = Field(min_length=1, description="zeta per mode; the last value repeats")

    @model_validator(mode="after")
    def _ratios(self) -> ModalDamping:
        if any(not (0 <= z < 1) for z in self.ratios):
            raise ValueError("ratios: each must be in [0, 1)")
        return self


class RayleighDamping(Strict):
    """C = alpha M + beta K, with M and K of the ``scope``:

    * ``system`` (default): the assembled model at each speed: shaft elements (with their axial-force
      and torque stiffness), discs, point masses, station springs and bearings (bearing stiffness and
      mass coefficients at that speed); K by its symmetric part;
    * ``rotor``: the rotor without springs and bearings: M of the shaft elements, discs and point
      masses, K of the shaft elements (symmetric part); as ROSS's rotor-level ``alpha``, ``beta``;
    * ``shaft_elements``: the shaft elements only (every layer), ``alpha M_e + beta K_e`` summed over
      them, K_e with its axial-force and torque parts as they are: discs and point masses get no
      damping; as ROSS's per-element ``ShaftElement(alpha=, beta=)`` with the same values on every
      element.
    """

    kind: Literal["rayleigh"] = "rayleigh"
    alpha: float = Field(ge=0, description="1/s")
    beta: float = Field(ge=0, description="s")
    scope: Literal["system", "rotor", "shaft_elements"] = "system"


class NoDamping(Strict):
    kind: Literal["none"] = "none"


DampingModel = Annotated[ModalDamping | RayleighDamping | NoDamping, Field(discriminator="kind")]


# --------------------------------------------------------------------------------------------
# lumped parts


class LumpedMass(Strict):
    name: str
    mass: Mass = Field(gt=0, description="kg")


class LumpedSpring(Strict):
    """Spring and damper between two masses, or a mass and ``ground``."""

    name: str
    between: tuple[str, str]
    stiffness: Stiffness = Field(ge=0, description="N/m")
    damping: Damping = Field(default=0.0, ge=0, description="N s/m")


# --------------------------------------------------------------------------------------------
# ports, damage, uncertainty, faults, measurement


class Port(Strict):
    """A measurement or damage port: a rotor station and direction, or a lumped mass."""

    station: int | None = Field(default=None, ge=1)
    direction: Literal["x", "y"] = "x"
    mass: str | None = None


class Ports(Strict):
    actuator: Port
    sensor: Port


class DamagePort(Strict):
    port: Port
    element: int | None = Field(default=None, ge=1, description="suspected element (rotor)")


class Uncertainty(Strict):
    """Uncertainty structure for validation (method.md).

    ``parameter`` names a model parameter for the parametric structure, as a dotted path:
    ``masses.m1.mass``, ``discs.disc.mass``, ``bearings.nme.kxx``, ``shaft.4.youngs_modulus``.
    """

    structure: Literal["additive", "multiplicative", "parametric"] = "additive"
    parameter: str | None = None

    @model_validator(mode="after")
    def _param(self) -> Uncertainty:
        if self.structure == "parametric" and not self.parameter:
            raise ValueError("parameter: required for the parametric structure")
        return self


class Crack(Strict):
    """A crack in one shaft element (see rotorcheck.faults).

    ``model``: ``open`` (modulus factor), ``mayes_davies`` (cosine breathing, eq. 5.13/5.21),
    ``gasch`` (hinge, eq. 5.10-5.12), ``jun`` (series, eq. 5.14-5.16).

    ``mayes_davies``/``gasch`` take either ``depth_ratio`` (depth / radius, 0 < alpha <= 1: the
    compliances F_xi, F_eta of eq. 5.25 are computed by the strip method,
    :mod:`rotorcheck.faults.compliance`) or both ``compliance_xi`` and ``compliance_eta``, never
    both kinds (nothing given is silently replaced). Other models take no ``depth_ratio``.
    """

    kind: Literal["crack"] = "crack"
    element: int = Field(ge=1, description="cracked element (1-based, between stations e and e+1)")
    model: Literal["open", "mayes_davies", "gasch", "jun"]
    modulus_factor: Ratio | None = Field(default=None, gt=0, le=1, description="open crack E factor")
    depth_ratio: Ratio | None = Field(
        default=None, gt=0, lt=2, description="depth / radius (mayes_davies, gasch: <= 1, sets F_xi, F_eta)"
    )
    compliance_xi: float | None = Field(default=None, ge=0, description="F_xi(alpha), instead of depth_ratio")
    compliance_eta: float | None = Field(default=None, ge=0, description="F_eta(alpha), instead of depth_ratio")
    section_length: Length | None = Field(default=None, gt=0, description="l in eq. 5.25, m")
    poisson: Ratio | None = Field(default=None, ge=0, lt=0.5)
    angle: Angle = Field(default=0.0, description="crack direction at t = 0 (rad; 0 = closed)")
    jun_b_xi: list[float] = Field(default_factory=list, description="k_xixi cosine series / k0")
    jun_b_eta: list[float] = Field(default_factory=list, description="k_etaeta cosine series / k0")
    jun_a: list[float] = Field(default_factory=list, description="k_xieta sine series / k0")

    @model_validator(mode="after")
    def _inputs(self) -> Crack:
        if self.model == "open" and self.modulus_factor is None:
            raise ValueError("modulus_factor: required for an open crack")
        if self.model in ("mayes_davies", "gasch"):
            if self.section_length is None:
                raise ValueError(f"section_length: required for the {self.model} model")
            given = [f for f in ("compliance_xi", "compliance_eta") if getattr(self, f) is not None]
            if self.depth_ratio is not None:
                if given:
                    raise ValueError(
                        f"{given[0]}: give depth_ratio (compliances computed from the depth) or "
                        "compliance_xi and compliance_eta, not both"
                    )
                if self.depth_ratio > 1.0:  # rotorcheck.faults.compliance.MAX_DEPTH_RATIO
                    raise ValueError(
                        "depth_ratio: the strip relation holds up to depth/radius 1 (half the diameter); "
                        "give compliance_xi and compliance_eta for a deeper crack"
                    )
            else:
                for f in ("compliance_xi", "compliance_eta"):
                    if getattr(self, f) is None:
                        raise ValueError(f"{f}: required for the {self.model} model (or give depth_ratio alone)")
        elif self.depth_ratio is not None:
            hint = (
                "give modulus_factor (rotorcheck.faults.compliance.open_crack_modulus_factor derives it from a depth)"
                if self.model == "open"
                else "its stiffness is the jun_* series"
            )
            raise ValueError(f"depth_ratio: not used by the {self.model} model; {hint}")
        return self


class SpringChange(Strict):
    """A lumped spring whose stiffness changes (the three-mass damage k3 -> kd)."""

    kind: Literal["spring_change"] = "spring_change"
    spring: str
    stiffness: Stiffness = Field(ge=0, description="N/m")


Fault = Annotated[Crack | SpringChange, Field(discriminator="kind")]


class UnbalanceMass(Strict):
    station: int = Field(ge=1)
    amount: Unbalance = Field(ge=0, description="kg m")
    phase: Angle = Field(default=0.0, description="rad, from +x towards +y at t = 0")


class Misalignment(Strict):
    """A 2X synchronous force at a station (bearing misalignment)."""

    station: int = Field(ge=1)
    force_2x: Force = Field(ge=0, description="N, amplitude at 1000 rpm, scales with speed^2")
    phase: Angle = 0.0


class Measurement(Strict):
    """How the simulator plays a stepped-sine measurement on this rig (truth configs)."""

    force_amplitude: Force = Field(default=1.0, gt=0, description="N, actuator force amplitude")
    n_periods: int = Field(default=64, ge=1)
    settle_periods: int = Field(default=16, ge=0)
    output_noise_std: Length = Field(default=0.0, ge=0, description="m, per sample")
    input_noise_std: Force = Field(default=0.0, ge=0, description="N, per sample")
    samples_per_period: int = Field(default=64, ge=8)
    unbalance: list[UnbalanceMass] = Field(default_factory=list)
    misalignment: Misalignment | None = None


class Analysis(Strict):
    band_hz: tuple[FrequencyHz, FrequencyHz] = (30.0, 600.0)
    n_points: int | None = Field(default=None, ge=2, description="points of a simulated sweep, linear over band_hz")
    speeds_rpm: list[SpeedRpm] = Field(default_factory=lambda: [0.0])
    campbell_max_rpm: SpeedRpm = Field(default=10000.0, gt=0)
    n_modes: int = Field(default=6, ge=1)

    @model_validator(mode="after")
    def _band(self) -> Analysis:
        if not (0 <= self.band_hz[0] < self.band_hz[1]):
            raise ValueError("band_hz: must be [low, high] with 0 <= low < high")
        return self


# --------------------------------------------------------------------------------------------
# benign variability: operating and environmental changes the detector must not call damage

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
_BENIGN_KIND = {  # parameters that apply to one rig kind only
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


# --------------------------------------------------------------------------------------------
# the rig


class RigConfig(Strict):
    """A rig: nominal model or simulated truth."""

    schema_: Literal["rotorcheck.rig"] = Field(default="rotorcheck.rig", alias="schema")
    version: Literal[1] = 1
    rig_id: str = Field(min_length=1)
    kind: Literal["rotor", "lumped"] = "rotor"
    description: str = ""
    # rotor
    materials: dict[str, Material] = Field(default_factory=dict)
    stations: list[Length] = Field(default_factory=list, description="axial positions, m")
    shaft: list[ShaftElement] = Field(default_factory=list)
    discs: list[Disc] = Field(default_factory=list)
    point_masses: list[PointMass] = Field(default_factory=list)
    bearings: list[Bearing] = Field(default_factory=list)
    springs: list[StationSpring] = Field(default_factory=list)
    shear_method: ShearMethod = Field(default="hutchinson", description="shear coefficient formula (rotor)")
    shear_coefficient: Ratio | None = Field(default=None, gt=0, le=2, description="kappa for every element")
    shear: bool = Field(default=True, description="shear deformation in the shaft (False: Euler-Bernoulli)")
    rotary_inertia: bool = Field(default=True, description="rotary inertia of the shaft")
    gyroscopic: bool = Field(default=True, description="gyroscopic coupling of shaft and discs")
    tapered_element: Literal["exact", "greenhill"] = Field(
        default="exact", description="stiffness of tapered elements: exact (flexibility of the actual "
        "tapered beam) or greenhill (Greenhill et al. 1985, one mid-section shear parameter; ROSS's)")
    # lumped
    masses: list[LumpedMass] = Field(default_factory=list)
    lumped_springs: list[LumpedSpring] = Field(default_factory=list)
    # common
    damping: DampingModel = Field(default_factory=NoDamping)
    ports: Ports | None = Field(default=None, description="actuator and sensor; optional (modal analysis)")
    damage: DamagePort | None = None
    uncertainty: Uncertainty = Field(default_factory=Uncertainty)
    faults: dict[str, Fault] = Field(default_factory=dict)
    measurement: Measurement = Field(default_factory=Measurement)
    analysis: Analysis = Field(default_factory=Analysis)
    variability: list[BenignRange] = Field(
        default_factory=list, description="benign parameter ranges: changes the detector must not call damage"
    )

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)

    @model_validator(mode="after")
    def _consistency(self) -> RigConfig:
        if self.kind == "rotor":
            self._check_rotor()
        else:
            self._check_lumped()
        if self.variability:
            resolve_benign(self)
        if self.uncertainty.structure == "parametric" and self.uncertainty.parameter:
            self._check_uncertainty_parameter(self.uncertainty.parameter)
        if self.kind == "rotor" and any(abs(z) > 1e4 for z in self.stations):
            raise ValueError("stations: positions beyond 10 km: not a rotor (give metres, or units such as '160 mm')")
        return self

    # -- rotor checks ------------------------------------------------------------------------
    def _check_rotor(self) -> None:
        n = len(self.stations)
        if n < 2:
            raise ValueError("stations: a rotor needs at least 2 stations")
        if any(b <= a for a, b in zip(self.stations, self.stations[1:])):
            raise ValueError("stations: positions must be strictly increasing")
        if not self.shaft:
            raise ValueError("shaft: a rotor needs shaft elements")
        refine: dict[int, tuple[int, int]] = {}
        for i, e in enumerate(self.shaft):
            if e.end > n:
                raise ValueError(f"shaft[{i}].end: station {e.end} out of range 1..{n}")
            if e.material not in self.materials:
                raise ValueError(f"shaft[{i}].material: unknown material {e.material!r}")
            first = refine.setdefault(e.start, (i, e.refine))
            if first[1] != e.refine:
                raise ValueError(f"shaft[{i}].refine: {e.refine}, but shaft[{first[0]}] on the same stations "
                                 f"{e.start}-{e.end} (a concentric layer) has {first[1]}; layers share one mesh")
        missing = [k for k in range(1, n) if k not in refine]
        if missing:
            k = missing[0]
            raise ValueError(f"shaft: no element joins stations {k} and {k + 1} (the shaft must be continuous "
                             f"over stations 1..{n}; several elements on one pair are concentric layers)")
        for group in ("discs", "springs"):
            for i, part in enumerate(getattr(self, group)):
                if part.station > n:
                    raise ValueError(f"{group}[{i}].station: {part.station} out of range 1..{n}")
        for i, d in enumerate(self.discs):
            if d.material is not None and d.material not in self.materials:
                raise ValueError(f"discs[{i}].material: unknown material {d.material!r}")
        self._check_support_nodes(n)
        if {"shear_method", "shear_coefficient"} <= self.model_fields_set and self.shear_coefficient is not None:
            raise ValueError("shear_coefficient: give shear_method or shear_coefficient, not both (the "
                             "coefficient would override the method everywhere)")
        if not any(self.shear if e.shear is None else e.shear for e in self.shaft):
            for key in ("shear_method", "shear_coefficient"):
                if key in self.model_fields_set and getattr(self, key) is not None:
                    raise ValueError(f"{key}: unused: no shaft element has shear deformation (shear: false)")
        at: dict[int, int] = {}
        for i, b in enumerate(self.bearings):
            if b.n_link is not None:
                continue
            if b.station in at:
                raise ValueError(f"bearings[{i}].station: station {b.station} already has bearings[{at[b.station]}] "
                                 "to ground (one per station; give their sum, or a spring)")
            at[b.station] = i
        for group in ("masses", "lumped_springs"):
            if getattr(self, group):
                raise ValueError(f"{group}: applies to kind: lumped only (a rotor takes discs, bearings and "
                                 "springs); it would be ignored")
        for name in ("actuator", "sensor"):
            if self.ports is None:
                break
            p = getattr(self.ports, name)
            if p.mass is not None:
                raise ValueError(f"ports.{name}.mass: a rotor port is a station and direction")
            if p.station is None or p.station > n:
                raise ValueError(f"ports.{name}.station: must be a station in 1..{n}")
        if self.damage is not None:
            p = self.damage.port
            if p.station is None or p.station > n:
                raise ValueError(f"damage.port.station: must be a station in 1..{n}")
            de = self.damage.element
            if de is not None and de > n - 1:
                raise ValueError(f"damage.element: {de} out of range 1..{n - 1}")
            if de is not None and p.station is not None and p.station not in (de, de + 1):
                raise ValueError(f"damage.element: element {de} joins stations {de} and {de + 1}; the damage port "
                                 f"is at station {p.station}")
        for key, f in self.faults.items():
            if isinstance(f, Crack) and f.element > n - 1:
                raise ValueError(f"faults.{key}.element: {f.element} out of range 1..{n - 1}")
            if isinstance(f, SpringChange):
                raise ValueError(f"faults.{key}: spring_change applies to lumped models only")
        for i, u in enumerate(self.measurement.unbalance):
            if u.station > n:
                raise ValueError(f"measurement.unbalance[{i}].station: out of range 1..{n}")
        mis = self.measurement.misalignment
        if mis is not None and mis.station > n:
            raise ValueError(f"measurement.misalignment.station: out of range 1..{n}")

    def _check_support_nodes(self, n: int) -> None:
        """Support nodes (numbered n+1, n+2, ... after the shaft stations): linked by a bearing's
        ``n_link``, each with a point mass in x and y, numbered without gaps."""
        nodes = self.support_nodes
        for i, pm in enumerate(self.point_masses):
            if pm.station > n and pm.station not in nodes:
                raise ValueError(f"point_masses[{i}].station: {pm.station} is neither a station (1..{n}) nor a "
                                 "support node that a bearing links (n_link)")
        linked = {b.n_link for b in self.bearings if b.n_link is not None}
        for node in nodes:
            if node not in linked:
                raise ValueError(f"bearings: support node {node} (after the last station {n}) is not linked to "
                                 f"the rotor: give a bearing with n_link: {node}")
            mx = sum(pm.masses[0] for pm in self.point_masses if pm.station == node)
            my = sum(pm.masses[1] for pm in self.point_masses if pm.station == node)
            if mx <= 0 or my <= 0:
                raise ValueError(f"point_masses: support node {node} has no mass in x and y (a massless pedestal "
                                 "is a series spring: fold it into the bearing, or give the pedestal's mass)")
        if nodes and list(nodes) != list(range(n + 1, n + 1 + len(nodes))):
            raise ValueError(f"bearings: support nodes must be numbered {n + 1}, {n + 2}, ... without gaps "
                             f"(got {list(nodes)})")

    @property
    def support_nodes(self) -> tuple[int, ...]:
        """Support (pedestal) nodes a bearing reaches after the shaft stations (rotor), ascending."""
        n = len(self.stations)
        ends = {b.station for b in self.bearings} | {b.n_link for b in self.bearings if b.n_link is not None}
        return tuple(sorted(k for k in ends if k > n))

    @property
    def n_support_nodes(self) -> int:
        """How many support nodes (see :attr:`support_nodes`)."""
        return len(self.support_nodes)

    def io_ports(self, purpose: str) -> Ports:
        """The actuator and sensor; a :class:`ConfigError` naming ``purpose`` when the rig has none."""
        if self.ports is None:
            raise ConfigError(f"rig {self.rig_id}", "ports", f"{purpose} needs ports.actuator and ports.sensor; "
                              "this rig has none (a rig without ports serves modal analysis only)")
        return self.ports

    def _check_uncertainty_parameter(self, name: str) -> None:
        """The parametric structure's parameter exists (checked at load, not when the model is built)."""
        parts = name.split(".")
        known: dict[tuple[str, str], list[str]] = {
            ("masses", "mass"): [m.name for m in self.masses],
            ("lumped_springs", "stiffness"): [k.name for k in self.lumped_springs],
            ("bearings", "kxx"): [b.name for b in self.bearings if b.n_link is None],
            ("bearings", "kyy"): [b.name for b in self.bearings if b.n_link is None],
        }
        names = known.get((parts[0], parts[2])) if len(parts) == 3 else None
        if names is None:
            raise ValueError(f"uncertainty.parameter: {name!r} is not a supported rank-one parameter "
                             "(masses.<m>.mass, lumped_springs.<k>.stiffness, bearings.<b>.kxx|kyy)")
        if parts[1] not in names:
            raise ValueError(f"uncertainty.parameter: no {parts[0]} entry named {parts[1]!r} "
                             f"(known: {', '.join(names) or 'none'})")

    def notes(self) -> list[str]:
        """What the loader accepted but a user should know (inconsistent material constants; bearing speed
        tables that do not cover the analysed speeds, and how they are extended; more modes asked than
        the model has degrees of freedom: clamped)."""
        out = [n for k, m in self.materials.items() if (n := m.consistency_note(k)) is not None]
        top = max(self.analysis.campbell_max_rpm, *self.analysis.speeds_rpm)
        for i, b in enumerate(self.bearings):
            tables = [t for t in (getattr(b, k) for k in BEARING_TERMS) if isinstance(t, SpeedTable)]
            if not tables:
                continue
            lo, hi = max(t.speed_rpm[0] for t in tables), min(t.speed_rpm[-1] for t in tables)  # all cover
            if lo > 0.0 or hi < top:
                how = ("held at their end values (extrapolate: hold)" if b.extrapolate == "hold" else
                       "extrapolated linearly from their end segments (extrapolate: linear)")
                out.append(f"bearings[{i}] ({b.name}): speed tables cover {lo:g}-{hi:g} rpm, the analysis "
                           f"0-{top:g} rpm; outside their speeds the coefficients are {how}")
        if "n_modes" in self.analysis.model_fields_set and self.analysis.n_modes > self.n_dof:
            out.append(f"analysis.n_modes: {self.analysis.n_modes} modes asked, but the model has {self.n_dof} degrees "
                       f"of freedom: at most {self.n_dof} modes are reported")
        return out

    @property
    def n_dof(self) -> int:
        """Degrees of freedom of the assembled model (rotor: 4 per mesh node plus 2 per support node)."""
        if self.kind == "lumped":
            return len(self.masses)
        per_span: dict[int, int] = {}
        for e in self.shaft:
            per_span.setdefault(e.start, e.refine)
        return 4 * (1 + sum(per_span.values())) + 2 * self.n_support_nodes

    # -- lumped checks -----------------------------------------------------------------------
    def _check_lumped(self) -> None:
        names = [m.name for m in self.masses]
        rotor_only = ["point_masses", "stations", "shaft", "discs", "bearings", "springs", "materials"]
        rotor_only += [k for k in ("shear_method", "shear_coefficient", "shear", "rotary_inertia", "gyroscopic",
                                   "tapered_element") if k in self.model_fields_set]
        for group in rotor_only:
            value = getattr(self, group)
            if value or (not isinstance(value, (list, dict)) and group in self.model_fields_set):
                raise ValueError(f"{group}: applies to kind: rotor only (a lumped model takes masses and "
                                 "lumped_springs); it would be ignored")
        if not names:
            raise ValueError("masses: a lumped model needs masses")
        if len(set(names)) != len(names):
            raise ValueError("masses: names must be unique")
        known = {*names, "ground"}
        for i, s in enumerate(self.lumped_springs):
            for end in s.between:
                if end not in known:
                    raise ValueError(f"lumped_springs[{i}].between: unknown mass {end!r}")
            if s.between[0] == s.between[1]:
                raise ValueError(f"lumped_springs[{i}].between: a spring needs two ends")
        for name in ("actuator", "sensor"):
            if self.ports is None:
                break
            p = getattr(self.ports, name)
            if p.mass not in names:
                raise ValueError(f"ports.{name}.mass: must name a mass ({', '.join(names)})")
        if self.damage is not None and self.damage.port.mass not in names:
            raise ValueError("damage.port.mass: must name a mass")
        springs = {s.name for s in self.lumped_springs}
        for key, f in self.faults.items():
            if isinstance(f, SpringChange) and f.spring not in springs:
                raise ValueError(f"faults.{key}.spring: unknown spring {f.spring!r}")
            if isinstance(f, Crack):
                raise ValueError(f"faults.{key}: a crack applies to rotor models only")

    # -- derived -----------------------------------------------------------------------------
    def sha256(self) -> str:
        """Hash of the validated content (insensitive to comments, layout and unit spelling)."""
        data = self.model_dump(mode="json", by_alias=True)
        if not data.get("variability"):  # absent and empty hash alike (hashes from before the section)
            data.pop("variability", None)
        if data.get("analysis", {}).get("n_points") is None:  # likewise the simulation grid's point count
            data.get("analysis", {}).pop("n_points", None)
        _prune_defaults(data, _LATER_KEYS)  # keys added later hash as if absent while at their defaults
        doc = json.dumps(data, sort_keys=True)
        return hashlib.sha256(doc.encode()).hexdigest()


#: keys added after rig hashes were first recorded, with their defaults (issue 20), by section
_LATER_KEYS: dict[str, dict[str, Any]] = {
    "": {"point_masses": [], "shear_method": "hutchinson", "shear_coefficient": None, "shear": True,
         "rotary_inertia": True, "gyroscopic": True, "tapered_element": "exact", "ports": None},
    "shaft": {"outer_diameter_right": None, "inner_diameter_right": None, "axial_force": 0.0, "torque": 0.0,
              "shear_method": None, "shear_coefficient": None, "shear": None, "rotary_inertia": None,
              "gyroscopic": None},
    "discs": {"material": None, "width": None, "outer_diameter": None, "inner_diameter": None},
    "bearings": {"n_link": None, "mxx": 0.0, "myy": 0.0, "mxy": 0.0, "myx": 0.0, "extrapolate": "hold"},
    "damping": {"scope": "system"},
}


def _prune_defaults(data: dict[str, Any], later: dict[str, dict[str, Any]]) -> None:
    """Drop, in place, the keys of ``later`` that hold their default value."""
    for section, defaults in later.items():
        target = data if section == "" else data.get(section)
        items = target if isinstance(target, list) else [target] if isinstance(target, dict) else []
        for item in items:
            for key, default in defaults.items():
                if key in item and item[key] == default:
                    del item[key]


# --------------------------------------------------------------------------------------------
# benign variability: resolution against the rig (validation; rotorcheck.variability builds on it)

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
    return _loc(leaf)


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
        where = _loc(tuple(leaf)) or "the rig"
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
        field, msg = _first_error(exc)
        raise ValueError(f"{r.form}: {r.path} = {value:g} is not a valid rig ({field}: {msg})") from None


def _resolve_one(cfg: RigConfig, r: BenignRange) -> ResolvedBenign:
    p = r.parameter
    need = _BENIGN_KIND.get(p)
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


# --------------------------------------------------------------------------------------------
# loading


class ConfigError(InputError):
    """An unusable rig file. ``str()`` names the file and the field."""


def _loc(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif str(part).startswith("function-") or part in ("SpeedTable", "float"):
            continue
        else:
            out += ("." if out else "") + str(part)
    return out


def _message(err: Any) -> str:
    t, ctx = err.get("type", ""), err.get("ctx") or {}
    if t == "greater_than":
        return f"must be > {ctx.get('gt')}"
    if t == "greater_than_equal":
        return f"must be >= {ctx.get('ge')}"
    if t == "less_than":
        return f"must be < {ctx.get('lt')}"
    if t == "less_than_equal":
        return f"must be <= {ctx.get('le')}"
    if t == "missing":
        return "required field is missing"
    if t == "extra_forbidden":
        return "unknown key"
    msg = str(err.get("msg", "invalid"))
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix) :]
    return msg


def _first_error(exc: ValidationError) -> tuple[str, str]:
    """The most specific error: prefer the deepest location (unions report every branch)."""
    errs = exc.errors()
    # for unions of float | SpeedTable, a unit error shows on the float branch: prefer that
    best = max(errs, key=lambda e: (e.get("type") != "model_type", len(e.get("loc", ()))))
    field = _loc(tuple(best.get("loc", ())))
    msg = _message(best)
    # a model-level validator message "name: text" refines the field path
    if ":" in msg and best.get("type") == "value_error":
        head, tail = msg.split(":", 1)
        if " " not in head.strip():
            field = f"{field}.{head.strip()}" if field else head.strip()
            msg = tail.strip()
    return field, msg


def parse_config(data: Any, source: str | Path = "<config>") -> RigConfig:
    """Validate a mapping (already parsed YAML) into a :class:`RigConfig`."""
    if not isinstance(data, dict):
        raise ConfigError(source, "", "the top level must be a mapping of keys")
    try:
        return RigConfig.model_validate(data)
    except ValidationError as exc:
        field, msg = _first_error(exc)
        raise ConfigError(source, field, msg) from None


#: a rig file larger than this is refused before it is parsed (bytes)
MAX_RIG_BYTES = 2_000_000


class _StrictLoader(yaml.SafeLoader):
    """Safe YAML with two YAML 1.1 surprises refused: a key given twice in one mapping (the later one
    silently won) and an integer with a leading zero (``010`` was read as octal 8)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key {key!r} given twice (first on line {seen[key] + 1})", key_node.start_mark)
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node: yaml.ScalarNode) -> int:
        text = str(node.value).replace("_", "")
        if re.fullmatch(r"[-+]?0[0-7]+", text):
            raise yaml.constructor.ConstructorError(
                None, None, f"{node.value!r}: a leading zero (YAML 1.1 reads it as octal "
                f"{int(text, 8)}); write {int(text, 10)} or quote it", node.start_mark)
        return int(super().construct_yaml_int(node))


_StrictLoader.add_constructor("tag:yaml.org,2002:int", _StrictLoader.construct_yaml_int)


def _non_finite(data: Any, path: str = "") -> str | None:
    """The path of the first NaN or infinite number in parsed YAML (``1e400`` reads as inf), else None."""
    if isinstance(data, float) and not math.isfinite(data):
        return path or "(top level)"
    if isinstance(data, dict):
        for k, v in data.items():
            hit = _non_finite(v, f"{path}.{k}" if path else str(k))
            if hit:
                return hit
    elif isinstance(data, list):
        for i, v in enumerate(data):
            hit = _non_finite(v, f"{path}[{i}]")
            if hit:
                return hit
    return None


def load_config(path: str | Path) -> RigConfig:
    """Read and validate a rig YAML file; raises :class:`ConfigError` naming file and field. Refused
    before validation: files over :data:`MAX_RIG_BYTES`, text that is not UTF-8, duplicate keys,
    integers with a leading zero, nesting too deep to parse, NaN or infinite numbers (by field)."""
    p = Path(path)
    text = read_bounded_text(p, MAX_RIG_BYTES, "rig file", ConfigError)
    try:
        data = yaml.load(text, Loader=_StrictLoader)  # a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError(p, "", f"malformed YAML: {where}{problem}") from None
    except RecursionError:
        raise ConfigError(p, "", "nested too deeply to be a rig file") from None
    bad = _non_finite(data)
    if bad is not None:
        raise ConfigError(p, bad, "not a finite number (NaN, inf, or beyond the float range such as 1e400)")
    return parse_config(data, p)


def json_schema() -> dict[str, Any]:
    """JSON Schema of the rig file, for editors."""
    schema = RigConfig.model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "rotorcheck rig"
    return schema
