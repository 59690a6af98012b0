"""The documents other tools read, as typed classes: ``report.json`` (detect), ``location.json`` (locate)
and the ``--json`` outputs of ``fit-noise`` and ``validate``. Each key comes from one field here (cli.md's
contract keys plus context); ``to_dict`` (``to_json`` of a location) gives the JSON document (optional
groups left out when absent).

Units: frequencies Hz, receptances m/N, damage dynamics N/m, noise bounds m, angles deg.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

if TYPE_CHECKING:  # annotations only: the location model is not needed to build or render a report
    from rotorcheck.location import LocationResult

__all__ = ["CONTRACT_KEYS", "DetectionReport", "LocationReport", "NoiseReport", "ReportValue", "ValidationReport"]

#: report.json keys other tools rely on (../shared/spec/cli.md)
CONTRACT_KEYS = (
    "verdict", "n_points", "n_fault_points", "fault_frequencies_hz", "frequency_hz", "gamma_healthy",
    "gamma_required", "fault", "damage_dynamics_re", "damage_dynamics_im", "damage_bound_min_abs",
    "damage_bound_max_abs",
)

FloatArray = np.ndarray

#: a value of a report document as ``to_dict`` gives it, before :func:`rotorcheck.report.reports.render_json` writes
#: it: JSON's values (text, numbers, booleans, null, lists, objects), with numpy arrays and scalars where a field
#: holds them (written as lists and numbers)
ReportValue: TypeAlias = (str | int | float | bool | np.ndarray | np.generic | list["ReportValue"]
                          | dict[str, "ReportValue"] | None)


def _as_dict(obj: Any) -> dict[str, Any]:
    """Fields in order; an optional field (default None) left at None is left out."""
    out: dict[str, Any] = {}
    for f in fields(obj):
        value = getattr(obj, f.name)
        if value is None and f.default is None:
            continue
        out[f.name] = value
    return out


@dataclass
class DetectionReport:
    """``report.json`` of ``rotorcheck detect``: verdict, context, per-point arrays (f,)."""

    verdict: str  # "damage" | "healthy" | "inconclusive"
    verdict_reason: str
    verdict_rule: str
    n_points: int
    n_fault_points: int
    fault_frequencies_hz: list[float]
    rig_id: str
    rig_sha256: str
    sweep: str
    sweep_sha256: str
    run_id: str
    speed_rpm: float
    band_hz: list[float]
    noise_bound_m: float
    noise_method: str
    uncertainty: str
    parameter: str
    enclose: str  # detection mode: "measured" | "system" | "data"
    damage_port: str
    shaft_orders_removed: int
    notes: list[str]
    frequency_hz: FloatArray
    gamma_healthy: FloatArray  # measured: the noise allowance of |T_new - T_h| (m/N); else gamma_h
    gamma_required: FloatArray  # measured: |T_new - T_h| (m/N); else the certified lower bound
    gamma_required_upper: FloatArray
    fault: FloatArray
    status: list[str]
    damage_dynamics_re: FloatArray  # eq. 3.11 with the nominal E22 (N/m)
    damage_dynamics_im: FloatArray
    damage_bound_kind: list[str]
    damage_bound_min_abs: FloatArray
    damage_bound_max_abs: FloatArray
    damage_bound_phase_min_deg: FloatArray
    damage_bound_phase_max_deg: FloatArray
    # measured detection
    confidence: float | None = None  # family-wise
    n_tests: int | None = None
    point_miss_probability: float | None = None
    p_value: float | None = None  # the sweep's Sidak-adjusted p-value for "any change"
    gamma_meaning: str | None = None
    point_p_value: FloatArray | None = None
    variance_dof: FloatArray | None = None
    # anchored identification (E22 := the measured healthy FRF)
    damage_dynamics_anchored_re: FloatArray | None = None
    damage_dynamics_anchored_im: FloatArray | None = None
    damage_anchored_bound_kind: list[str] | None = None
    damage_anchored_bound_min_abs: FloatArray | None = None
    damage_anchored_bound_max_abs: FloatArray | None = None
    damage_anchored_bound_phase_min_deg: FloatArray | None = None
    damage_anchored_bound_phase_max_deg: FloatArray | None = None
    damage_anchored_bound_confidence: float | None = None
    damage_anchored_channel_error: FloatArray | None = None
    damage_anchored_noise_min_abs: FloatArray | None = None
    damage_anchored_noise_max_abs: FloatArray | None = None
    damage_dynamics_by_direction: dict[str, dict[str, Any]] | None = None  # {"x"|"y": {"re", "im"} (f,)} N/m
    location: LocationResult | None = None  # where and how big (detect --locate); JSON: its to_dict()
    detectability: dict[str, Any] | None = None  # what this sweep could have revealed (rotorcheck.detectability)
    channel_pairs: list[str] | None = None  # measured FRFs "output<-input" (port labels), the rig's io pair first
    baseline: str | None = None  # the baseline file the sweep was compared with
    stations_m: list[float] | None = None  # the rig's station positions (m): element k spans [k-1, k]
    conclusion: str | None = None  # the plain conclusion every rendering opens with (report.content.conclusion)
    # the joint test (verdict_rule names it when it decided)
    joint_statistic: float | None = None  # T = max_e T_e (chi-square units)
    joint_threshold: float | None = None  # T at which the GLR's own p = its share of false_alarm (robust.joint)
    joint_p_value: float | None = None  # the sweep's: min(GLR p / (1 - share), fit p / share, 1) (robust.joint)
    joint_glr_p_value: float | None = None  # the GLR's own P(max_e T_e >= T | H0)
    joint_fit_chi2: float | None = None  # H0's goodness of fit: chi2 of the best benign fit (chi-square units)
    joint_fit_dof: int | None = None  # its degrees of freedom
    joint_fit_p_value: float | None = None  # P(chi2 >= joint_fit_chi2 | H0)
    false_alarm: float | None = None  # per-sweep false-alarm rate the threshold gives
    candidate_elements: list[int] | None = None  # shaft elements tested (1-based)
    element_statistic: list[float] | None = None  # T_e per candidate
    joint_best_element: int | None = None  # the joint test's largest T_e (its linearized GLR; not the diagnosis)
    joint_stiffness_loss: float | None = None  # its linearized loss estimate (fraction)
    joint_stiffness_loss_interval: list[float] | None = None  # 95 %, linearized
    # the diagnosis (damage verdicts): the ranking's first element, as locate names it (rotorcheck.ranking)
    best_element: int | None = None
    best_element_likelihood: float | None = None  # its relative likelihood among the candidates
    stiffness_loss: float | None = None  # its best-fit loss (fraction)
    stiffness_loss_interval: list[float] | None = None  # certified (detect --locate), else None
    detectable_stiffness_loss: list[float] | None = None  # per candidate: 90 % power at false_alarm
    benign_parameters: list[dict[str, Any]] | None = None  # {name, estimate, interval, unit, at_range_edge, edge_chi2,
    # range}
    benign_model_error: float | None = None  # kappa: relative error of the model's benign prediction in H0
    learned_benign_directions: int | None = None
    # points the fitted benign change leaves unexplained (per point, Sidak at false_alarm over the points)
    fault_beyond_benign: FloatArray | None = None  # (f,) bool
    fault_beyond_benign_frequencies_hz: list[float] | None = None
    # per point, certified beyond every benign change in the ranges (real parameters, branch and bound)
    beyond_benign_rule: str | None = None
    beyond_benign_status: list[str] | None = None  # (f,) "explained" | "unexplained" | "undecided"
    certified_beyond_benign_frequencies_hz: list[float] | None = None
    n_certified_beyond_benign: int | None = None
    n_undecided_beyond_benign: int | None = None
    n_certified_beyond_benign_complex: int | None = None  # the same with each parameter a complex disc
    # points on a shaft harmonic (rotorcheck.signal.harmonics): {frequency_hz, order, harmonic_hz, offset_hz,
    # resolution_hz}; status 'excluded', kept out of every certified claim
    shaft_harmonic_points: list[dict[str, Any]] | None = None
    # the sideband test (a sweep with sidebands f + k x speed): {rule, orders, statistic, threshold, p_value,
    # false_alarm, n_tones, verdict, fault_frequencies_hz, assumes} (rotorcheck.workflow.detectors.sideband)
    sideband_test: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        """The report.json document (arrays as numpy; :func:`rotorcheck.report.reports.render_json`)."""
        out = _as_dict(self)
        if self.location is not None:
            out["location"] = self.location.to_dict()
        return out


@dataclass(frozen=True)
class LocationReport:
    """``location.json`` of ``rotorcheck locate`` (and of the fleet's locate stage): the sweep and its
    sha256, the baseline file, the rig, the sweep's speed (rpm) and where and how big the change is."""

    sweep: str
    sweep_sha256: str
    baseline: str
    rig_id: str
    speed_rpm: float
    result: LocationResult

    def to_json(self) -> dict[str, Any]:
        """The location.json document: the context keys, then :meth:`LocationResult.to_dict`'s."""
        return {"sweep": self.sweep, "sweep_sha256": self.sweep_sha256, "baseline": self.baseline,
                "rig_id": self.rig_id, "speed_rpm": self.speed_rpm, **self.result.to_dict()}


@dataclass
class NoiseReport:
    """``rotorcheck fit-noise --json``."""

    noise_bound_m: float
    method: str
    confidence: float | None
    sweep: str
    baseline: str
    details: dict[str, Any]

    def to_dict(self) -> dict[str, Any]:
        """The JSON document."""
        return _as_dict(self)


@dataclass
class ValidationReport:
    """``rotorcheck validate --json``: gamma_h per point and how it was made."""

    frequency_hz: FloatArray
    gamma: FloatArray
    gamma_lower: FloatArray
    status: list[str]
    noise_bound_m: float
    noise_method: str
    enclose: str
    uncertainty: str
    n_points: int
    n_not_enclosed: int  # points not 'ok' and not 'excluded'
    baseline: str
    # points on a shaft harmonic (status 'excluded': no part of the bound); see DetectionReport
    shaft_harmonic_points: list[dict[str, Any]] | None = None
    # drift learned from several healthy sweeps (validate --learn-drift): {kept_sweep (1-based), kappa, rule,
    # parameters: [{name, range (%, relative to the kept sweep, as the joint test will allow it), determined}]}
    learned_drift: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        """The JSON document."""
        return _as_dict(self)
