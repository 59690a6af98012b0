"""Ports (actuator, sensor), the damage port and the uncertainty structure."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from rotorcheck.config.base import Strict


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

