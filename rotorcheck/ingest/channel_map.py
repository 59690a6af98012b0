"""The channel map (YAML, validated with pydantic): which recorded channel is what.

Example::

    rig_id: crack_rig            # or  rig: configs/crack_rig.yaml  (its rig_id is used)
    run_id: 1000rpm
    speed_rpm: 1000              # nominal; required when there is no keyphasor (0: not spinning)
    sample_rate_hz: 25600        # only for files that state none (CSV without a time column)
    force:                       # the input: a force (N) or an actuator current (A) times its gain
                                 # (several inputs driven in patterns: forces: [ {...}, {...} ])
      channel: F
      station: 8
      direction: x
      unit: A                    # N | A
      gain_n_per_a: 12.5         # with unit A
    probes:                      # the outputs: displacement probes
      - {channel: P6x, station: 6, direction: x, unit: V, sensitivity_v_per_m: 7874.0}
      - {channel: P2x, station: 2, direction: x, unit: mm}     # m | mm | um | V
    keyphasor: {channel: KP}     # once-per-revolution pulses; threshold default mid-range
    steps:                       # optional step table (else steps are found from the force)
      - {frequency_hz: 30.0, start_s: 0.0, end_s: 2.67}
    analysis: {settle_periods: 16, min_periods: 8, shaft_orders: 4}
    # sidebands f + k speed of each step (a rotating run with a keyphasor; sweep format version 3):
    # analysis: {sideband_orders: [-2, -1, 1, 2]}

Errors name the map file and the field (:class:`~rotorcheck.errors.InputError`, exit 2).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, ClassVar, Literal

import yaml
from pydantic import Field, StrictInt, ValidationError, model_validator

from rotorcheck.config import MAX_RIG_BYTES, Strict, StrictLoader, first_error, load_config
from rotorcheck.config.analysis import sideband_order_problem
from rotorcheck.errors import InputError
from rotorcheck.fileio import read_bounded_text

__all__ = ["PROBE_UNITS", "AnalysisSettings", "ChannelMap", "ForceChannel", "Keyphasor", "Probe", "StepRow",
           "load_channel_map", "parse_channel_map"]

#: metres per unit of a probe channel recorded in length units
PROBE_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6}


class _Recorded(Strict):
    """A recorded channel at a model station (1-based) and direction; ``rails``: the recorder's range
    (recorded units), samples at or beyond it are clipped (default: found as flat tops)."""

    channel: str = Field(min_length=1)
    station: int = Field(ge=1)
    direction: Literal["x", "y"]
    rails: tuple[float, float] | None = None
    #: (unit, field, what): ``field`` is required when the channel is recorded in ``unit``
    _requires: ClassVar[tuple[str, str, str]] = ("", "", "")

    @model_validator(mode="after")
    def _required(self) -> _Recorded:
        unit, name, what = self._requires
        if unit and getattr(self, "unit", None) == unit and getattr(self, name) is None:
            raise ValueError(f"{name}: required when unit is {unit} ({what})")
        return self


class ForceChannel(_Recorded):
    """The input channel: a force in N, or an actuator current in A with its gain (N/A)."""

    unit: Literal["N", "A"] = "N"
    gain_n_per_a: float | None = Field(default=None, gt=0)

    _requires = ("A", "gain_n_per_a", "actuator gain, N/A")

    @property
    def scale(self) -> float:
        """Newtons per recorded unit."""
        return float(self.gain_n_per_a) if self.unit == "A" and self.gain_n_per_a is not None else 1.0


class Probe(_Recorded):
    """A displacement probe: recorded in V (with ``sensitivity_v_per_m``) or in m, mm or um."""

    unit: Literal["V", "m", "mm", "um"] = "m"
    sensitivity_v_per_m: float | None = Field(default=None, gt=0)

    _requires = ("V", "sensitivity_v_per_m", "probe sensitivity, V/m")

    @property
    def scale(self) -> float:
        """Metres per recorded unit."""
        if self.unit == "V":
            assert self.sensitivity_v_per_m is not None
            return 1.0 / float(self.sensitivity_v_per_m)
        return PROBE_UNITS[self.unit]


class Keyphasor(Strict):
    """Once-per-revolution pulse channel; ``threshold`` (recorded units) default: mid-range of the step."""

    channel: str = Field(min_length=1)
    threshold: float | None = None


class StepRow(Strict):
    """One row of a step table: the excitation frequency (Hz) from ``start_s`` to ``end_s`` (s)."""

    frequency_hz: float = Field(gt=0)
    start_s: float
    end_s: float

    @model_validator(mode="after")
    def _order(self) -> StepRow:
        if not self.end_s > self.start_s:
            raise ValueError("end_s: must be after start_s")
        return self


class AnalysisSettings(Strict):
    """How steps are analysed (see :mod:`rotorcheck.ingest.analysis`); ``sideband_orders``: the orders k
    of the sidebands ``f + k speed`` read at every step (distinct, nonzero; [] = none)."""

    settle_periods: int = Field(default=16, ge=0)
    settle_s: float = Field(default=0.0, ge=0)
    min_periods: int = Field(default=8, ge=3)
    shaft_orders: int = Field(default=4, ge=0, le=16)
    short_step: Literal["drop", "refuse"] = "drop"
    clipping: Literal["drop", "refuse"] = "drop"
    max_distortion: float = Field(default=0.1, gt=0, lt=1)
    step_rtol: float = Field(default=2e-3, gt=0, lt=0.5)
    keep_periods: bool = True
    sideband_orders: list[StrictInt] = Field(default_factory=list)

    @model_validator(mode="after")
    def _orders(self) -> AnalysisSettings:
        why = sideband_order_problem(self.sideband_orders)
        if why:
            raise ValueError(f"sideband_orders: {why}")
        return self


class ChannelMap(Strict):
    """The whole map (see the module docstring)."""

    rig_id: str | None = Field(default=None, min_length=1)
    rig: str | None = None
    run_id: str = Field(default="run1", min_length=1)
    speed_rpm: float | None = Field(default=None, ge=0)
    sample_rate_hz: float | None = Field(default=None, gt=0)
    group: str | None = None
    format: Literal["mat", "tdms", "wav", "csv", "parquet", "uff", "hdf5"] | None = None
    force: ForceChannel | None = None
    forces: list[ForceChannel] | None = Field(default=None, min_length=1)
    probes: list[Probe] = Field(min_length=1)
    keyphasor: Keyphasor | None = None
    steps: list[StepRow] | None = None
    analysis: AnalysisSettings = AnalysisSettings()
    source_path: str = Field(default="<map>", exclude=True)

    @model_validator(mode="after")
    def _check(self) -> ChannelMap:
        if self.rig_id is None and self.rig is None:
            raise ValueError("rig_id: required (or rig: the rig file)")
        if (self.force is None) == (self.forces is None):
            raise ValueError("force: give force (one input) or forces (several, driven in patterns), not both")
        if self.keyphasor is None and self.speed_rpm is None:
            raise ValueError("speed_rpm: required when there is no keyphasor (0 for a shaft at rest)")
        if self.analysis.sideband_orders and (self.keyphasor is None or self.speed_rpm == 0.0):
            why = "no keyphasor" if self.keyphasor is None else "speed_rpm is 0 (shaft at rest)"
            raise ValueError(f"analysis.sideband_orders: sidebands need a rotating shaft with a keyphasor (their "
                             f"phase is referenced to the shaft angle); here {why}")
        names = self.channel_names()
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"probes: channel(s) {', '.join(dup)} used twice")
        if self.steps:
            for a, b in zip(self.steps, self.steps[1:]):
                if b.start_s < a.end_s:
                    raise ValueError(f"steps: step at {b.frequency_hz:g} Hz starts before the previous one ends")
        return self

    @property
    def inputs(self) -> list[ForceChannel]:
        """The force channel(s), in the sweep's input order."""
        return list(self.forces) if self.forces is not None else [self.force] if self.force is not None else []

    def channel_names(self) -> list[str]:
        """Forces, probes, then the keyphasor: the channels the analysis reads."""
        names = [*(c.channel for c in self.inputs), *(p.channel for p in self.probes)]
        return names + ([self.keyphasor.channel] if self.keyphasor is not None else [])

    def resolved_rig_id(self) -> str:
        """``rig_id``, else the ``rig_id`` of the rig file (relative to the map's folder)."""
        if self.rig_id is not None:
            return self.rig_id
        assert self.rig is not None
        p = Path(self.rig)
        if not p.is_absolute():
            p = Path(self.source_path).parent / p
        return load_config(p).rig_id

    def to_json(self) -> str:
        """The map as JSON (stored in the sweep file's provenance)."""
        return json.dumps(self.model_dump(mode="json"), sort_keys=True)


def parse_channel_map(data: Any, source: str | os.PathLike[str] = "<map>") -> ChannelMap:
    """Validate a mapping into a :class:`ChannelMap`; errors name ``source`` and the field."""
    if not isinstance(data, dict):
        raise InputError(os.fspath(source), "", "the channel map must be a mapping of keys")
    try:
        cmap = ChannelMap.model_validate({**data, "source_path": os.fspath(source)})
    except ValidationError as exc:
        field, msg = first_error(exc)
        raise InputError(os.fspath(source), field, msg) from None
    return cmap


def load_channel_map(path: str | os.PathLike[str]) -> ChannelMap:
    """Read and validate a channel-map YAML file (errors name the file and the field)."""
    p = Path(path)
    if not p.exists():
        raise InputError(p, "", "no such channel map")
    text = read_bounded_text(p, MAX_RIG_BYTES, "channel map", InputError)
    try:
        data = yaml.load(text, Loader=StrictLoader)
    except yaml.YAMLError as exc:
        raise InputError(p, "", f"malformed YAML: {exc}") from None
    return parse_channel_map(data, p)
