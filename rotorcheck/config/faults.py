"""Fault descriptions of a rig file (cracks, spring changes, unbalance, misalignment)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from rotorcheck.config.base import Strict
from rotorcheck.config.quantities import Angle, Force, Length, Ratio, Stiffness, Unbalance


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

