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

    ``mayes_davies``/``gasch`` take either ``depth`` (depth as a fraction of the shaft diameter,
    0 < d <= 0.5, the convention of ``--crack-depth`` and of every report: the compliances F_xi, F_eta
    of eq. 5.25 are computed by the strip method, :mod:`rotorcheck.faults.compliance`) or both
    ``compliance_xi`` and ``compliance_eta``, never both kinds (nothing given is silently replaced).
    The older key ``depth_ratio`` (depth / radius = 2 x depth) is still read; ``model`` notes it.
    Other models take no depth.
    """

    kind: Literal["crack"] = "crack"
    element: int = Field(ge=1, description="cracked element (1-based, between stations e and e+1)")
    model: Literal["open", "mayes_davies", "gasch", "jun"]
    modulus_factor: Ratio | None = Field(default=None, gt=0, le=1, description="open crack E factor")
    depth: Ratio | None = Field(
        default=None, gt=0, lt=1, description="depth / diameter (mayes_davies, gasch: <= 0.5, sets F_xi, F_eta)"
    )
    depth_ratio: Ratio | None = Field(
        default=None, gt=0, lt=2, description="older key: depth / radius (= 2 x depth); give depth instead"
    )
    compliance_xi: float | None = Field(default=None, ge=0, description="F_xi(alpha), instead of depth_ratio")
    compliance_eta: float | None = Field(default=None, ge=0, description="F_eta(alpha), instead of depth_ratio")
    section_length: Length | None = Field(default=None, gt=0, description="l in eq. 5.25, m")
    poisson: Ratio | None = Field(default=None, ge=0, lt=0.5)
    angle: Angle = Field(default=0.0, description="crack direction at t = 0 (rad; 0 = closed)")
    jun_b_xi: list[float] = Field(default_factory=list, description="k_xixi cosine series / k0")
    jun_b_eta: list[float] = Field(default_factory=list, description="k_etaeta cosine series / k0")
    jun_a: list[float] = Field(default_factory=list, description="k_xieta sine series / k0")

    @property
    def depth_over_radius(self) -> float | None:
        """alpha = depth / radius of eq. 5.25 (the strip method's variable), from ``depth`` or ``depth_ratio``."""
        return 2.0 * self.depth if self.depth is not None else self.depth_ratio

    def note(self, key: str) -> str | None:
        """What ``model`` says about this crack's input: the older depth key and its value in today's convention."""
        if self.depth_ratio is None:
            return None
        return (f"faults.{key}.depth_ratio: the older key (depth / radius = {self.depth_ratio:g}); read as depth "
                f"{0.5 * self.depth_ratio:g} of the diameter, the convention of --crack-depth and every report: "
                f"write 'depth: {0.5 * self.depth_ratio:g}' instead")

    @model_validator(mode="after")
    def _inputs(self) -> Crack:
        if self.depth is not None and self.depth_ratio is not None:
            raise ValueError("depth_ratio: give depth (fraction of the diameter) or the older depth_ratio "
                             "(depth / radius), not both")
        alpha = self.depth_over_radius
        key = "depth" if self.depth is not None else "depth_ratio"
        if self.model == "open" and self.modulus_factor is None:
            raise ValueError("modulus_factor: required for an open crack")
        if self.model in ("mayes_davies", "gasch"):
            if self.section_length is None:
                raise ValueError(f"section_length: required for the {self.model} model")
            given = [f for f in ("compliance_xi", "compliance_eta") if getattr(self, f) is not None]
            if alpha is not None:
                if given:
                    raise ValueError(
                        f"{given[0]}: give {key} (compliances computed from the depth) or "
                        "compliance_xi and compliance_eta, not both"
                    )
                if alpha > 1.0:  # rotorcheck.faults.compliance.MAX_DEPTH_RATIO
                    raise ValueError(
                        f"{key}: the strip relation holds up to half the diameter (depth 0.5, depth_ratio 1); "
                        "give compliance_xi and compliance_eta for a deeper crack"
                    )
            else:
                for f in ("compliance_xi", "compliance_eta"):
                    if getattr(self, f) is None:
                        raise ValueError(f"{f}: required for the {self.model} model (or give depth alone)")
        elif alpha is not None:
            hint = (
                "give modulus_factor (rotorcheck.faults.compliance.open_crack_modulus_factor derives it from a depth)"
                if self.model == "open"
                else "its stiffness is the jun_* series"
            )
            raise ValueError(f"{key}: not used by the {self.model} model; {hint}")
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

