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
    """C = alpha M + beta K; ``scope: rotor`` takes M and K of the rotor alone (shaft, discs, point
    masses; as ROSS's global ``alpha``, ``beta``), ``system`` (default) with bearings and springs."""

    kind: Literal["rayleigh"] = "rayleigh"
    alpha: float = Field(ge=0, description="1/s")
    beta: float = Field(ge=0, description="s")
    scope: Literal["system", "rotor"] = "system"


class NoDamping(Strict):
    kind: Literal["none"] = "none"


DampingModel = Annotated[ModalDamping | RayleighDamping | NoDamping, Field(discriminator="kind")]

