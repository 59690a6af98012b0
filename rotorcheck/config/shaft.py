"""Shaft sections (materials, tapered and layered elements), discs and point masses of a rotor rig."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Literal

from pydantic import Field, model_validator

from rotorcheck.config.base import Strict
from rotorcheck.config.quantities import Density, Force, Inertia, Length, Mass, Moment, Pressure, Ratio


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

    def inertias(self, materials: Mapping[str, Material]) -> tuple[float, float, float]:
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

