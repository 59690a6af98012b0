"""Damping models of a rig: modal, Rayleigh (with its scope), none."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from rotorcheck.config.base import Strict
from rotorcheck.config.quantities import Ratio


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

