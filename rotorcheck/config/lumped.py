"""Masses and springs of a lumped rig."""

from __future__ import annotations

from pydantic import Field

from rotorcheck.config.base import Strict
from rotorcheck.config.quantities import Damping, Mass, Stiffness


class LumpedMass(Strict):
    name: str
    mass: Mass = Field(gt=0, description="kg")


class LumpedSpring(Strict):
    """Spring and damper between two masses, or a mass and ``ground``."""

    name: str
    between: tuple[str, str]
    stiffness: Stiffness = Field(ge=0, description="N/m")
    damping: Damping = Field(default=0.0, ge=0, description="N s/m")

