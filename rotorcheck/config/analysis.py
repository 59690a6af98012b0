"""The measurement (noise, periods, force) and analysis (band, points, speeds, modes) sections."""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import Field, model_validator

from rotorcheck.config.base import Strict
from rotorcheck.config.faults import Misalignment, UnbalanceMass
from rotorcheck.config.quantities import Force, FrequencyHz, Length, SpeedRpm


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
    sideband_orders: list[int] = Field(default_factory=list, description="sidebands f + k speed measured at each "
                                       "point of a rotating sweep (orders k, nonzero; sweep contract version 3)")

    @model_validator(mode="after")
    def _orders(self) -> Measurement:
        why = sideband_order_problem(self.sideband_orders)
        if why:
            raise ValueError(f"sideband_orders: {why}")
        return self


def sideband_order_problem(orders: Sequence[int]) -> str | None:
    """Why ``orders`` are not sideband orders k of ``f + k speed`` (None when they are: distinct and nonzero)."""
    k = [int(x) for x in orders]
    if 0 in k:
        return f"order 0 is the excitation itself, not a sideband (got {k})"
    if len(set(k)) != len(k):
        return f"an order given twice (got {k}): give distinct orders"
    return None


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

