"""The model-centred tests (baselines ``--enclose system`` and ``--enclose data``, the dissertation's FDMVOP):
the new run against the nominal model with the model-error bound gamma_h(w) of validation; a point is a
fault where no model error within gamma_h and noise within V explains it (the LMI per frequency,
:func:`rotorcheck.robust.validation.detect`). With several channel pairs, one experiment per input over the
additive full block. The verdict: :data:`VERDICT_RULE`.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.robust import validation
from rotorcheck.robust.validation import DetectionResult
from rotorcheck.workflow.detectors.base import (
    Detection,
    DetectorSettings,
    detection_harmonics,
    exclude_points,
    harmonics_notes,
)
from rotorcheck.workflow.measured import MeasuredRun, pair_experiments
from rotorcheck.workflow.noise import baseline_noise_values
from rotorcheck.workflow.rigs import nominal_for
from rotorcheck.workflow.validation import parameter_structure

VERDICT_RULE = (
    "damage if the number of fault points is at least max(3, 2 % of the points) or at least 2 "
    "adjacent points are faults; otherwise inconclusive if any point could not be decided (solver "
    "failure) or the healthy data could not be enclosed somewhere; otherwise healthy"
)


def worst_detection(dets: list[DetectionResult]) -> DetectionResult:
    """One per-point detection from several experiments': a point is a fault when any experiment's is;
    the required gamma is the largest."""
    if len(dets) == 1:
        return dets[0]
    fault = np.any([d.fault for d in dets], axis=0)
    lo = np.max([d.gamma_required for d in dets], axis=0)
    up = np.max([d.gamma_required_upper for d in dets], axis=0)
    status = np.where(fault, "fault", dets[0].status).astype("<U13")
    for d in dets:
        status = np.where(~fault & (d.status != "ok"), d.status, status)
    return DetectionResult(lo, up, dets[0].gamma_healthy, fault, status, dets[0].rtol,
                           sum(d.n_solver_calls for d in dets), dets[0].reason)


class SystemEnclosure:
    """The new run against the nominal model and gamma_h (validated with ``--enclose system``)."""

    name: ClassVar[str] = "system"
    title: ClassVar[str] = "model-centred test"
    encloses: ClassVar[tuple[str, ...]] = ("system",)
    rotor_only: ClassVar[bool] = False

    def __init__(self, settings: DetectorSettings) -> None:
        self.settings = settings
        self.rig: RigConfig | None = None
        self.baseline: Baseline | None = None

    def prepare(self, rig: RigConfig, baseline: Baseline) -> None:
        """The rig and the baseline's gamma_h."""
        self.rig, self.baseline = rig, baseline

    def detect(self, run: MeasuredRun) -> Detection:
        """Fault points where the run leaves the healthy uncertain model, and :data:`VERDICT_RULE`."""
        rig, b = self.rig, self.baseline
        if rig is None or b is None or b.gamma is None:
            raise RuntimeError("prepare() the detector with a validated baseline first")
        fail_at = self.settings.fail_at
        if run.n_pairs > 1:
            me, Ws, Zs, Vp = pair_experiments(rig, run)
            det = worst_detection([validation.detect(me, w, z, Vp, b.gamma, fail_at=fail_at) for w, z in zip(Ws, Zs)])
        else:
            model = nominal_for(rig, run.frequency_hz, run.speed_rpm)
            det = validation.detect(model.me, run.W, run.Zt, baseline_noise_values(b, run), b.gamma,
                                    parameter_structure(model, b.enclose), fail_at=fail_at)
        harmonics = detection_harmonics(run, b.speed_rpm)
        det = exclude_points(det, harmonics)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.asarray(det.gamma_required, dtype=float) / np.asarray(det.gamma_healthy, dtype=float)
        ratio = np.where(harmonics.flagged, np.nan, ratio)
        return Detection(self.name, run.frequency_hz, validation.verdict(det.fault, det.status, b.gamma_status),
                         VERDICT_RULE, det, ratio, "gamma_required / gamma_healthy",
                         notes=harmonics_notes(harmonics), harmonics=harmonics)


class DataEnclosure(SystemEnclosure):
    """As :class:`SystemEnclosure`, the baseline validated with ``--enclose data`` (the dissertation's FDMVOP)."""

    name: ClassVar[str] = "data"
    encloses: ClassVar[tuple[str, ...]] = ("data",)
