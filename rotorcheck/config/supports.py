"""Bearings (coefficients, speed tables) and station springs."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from rotorcheck.config.base import Strict
from rotorcheck.config.quantities import Damping, Mass, SpeedRpm, Stiffness


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
        import numpy as np  # lazy: numpy only to interpolate a table (rotorcheck.config loads without numpy)

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

