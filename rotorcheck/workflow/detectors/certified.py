"""The per-point certified test against the measured healthy FRF (baseline ``--enclose measured``).

At each point the new FRF's distance from the healthy one against the noise of both sweeps, at the
family-wise ``confidence`` over every point and channel pair (:mod:`rotorcheck.robust.measured`); with
several pairs also along the damage direction. The verdict: :data:`rotorcheck.robust.measured.MEASURED_RULE`.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError
from rotorcheck.nominal import damage_direction
from rotorcheck.robust.measured import MEASURED_RULE, FrfEstimate, measured_detect, measured_verdict
from rotorcheck.robust.validation import DetectionResult
from rotorcheck.workflow.detectors.base import Detection, DetectorSettings, detection_harmonics, harmonics_notes
from rotorcheck.workflow.measured import MeasuredRun, frf_estimate, per_pair
from rotorcheck.workflow.rigs import nominal_for

HARMONICS_NOTE = ("the sweep stores no per-period phasors: shaft-speed harmonics (1X, 2X, ...) could not be "
                  "removed; with a free-running start angle they may show as differences near kX")


def ratio_meaning(n_pairs: int) -> str:
    """What the per-point ratio of the measured test is, for the decision figure."""
    return ("|T_new - T_healthy| / its noise allowance" if n_pairs == 1 else
            f"largest over the {n_pairs} channel pairs\nand the damage direction of |T_new - T_h| / allowance")


class CertifiedDetector:
    """Fault points certified against the measured healthy FRF; they alone decide the verdict."""

    name: ClassVar[str] = "certified"
    encloses: ClassVar[tuple[str, ...]] = ("measured",)
    rotor_only: ClassVar[bool] = False

    def __init__(self, settings: DetectorSettings) -> None:
        if not 0.0 < settings.confidence < 1.0:
            raise InputError(None, "--confidence", f"must be in (0, 1), got {settings.confidence}")
        self.settings = settings
        self.rig: RigConfig | None = None
        self.healthy: FrfEstimate | None = None
        self.baseline_rpm = 0.0

    def prepare(self, rig: RigConfig, baseline: Baseline) -> None:
        """The measured healthy FRF with its variance and dof."""
        if baseline.healthy_frf is None or baseline.healthy_frf_var is None or baseline.healthy_frf_dof is None:
            raise InputError(None, "healthy_frf", "the baseline holds no measured healthy FRF "
                             "(validate with --enclose measured)")
        self.rig = rig
        self.healthy = FrfEstimate(baseline.healthy_frf, baseline.healthy_frf_var, baseline.healthy_frf_dof)
        self.baseline_rpm = float(baseline.speed_rpm)

    def detect(self, run: MeasuredRun) -> Detection:
        """Fault points of ``run`` and the verdict of :data:`MEASURED_RULE`."""
        rig, healthy = self.rig, self.healthy
        if rig is None or healthy is None:
            raise RuntimeError("prepare() the detector first")
        new = frf_estimate(run)
        per_pair(healthy.frf, run.frequency_hz, new.frf.shape[1], run)
        e21 = nominal_for(rig, run.frequency_hz, run.speed_rpm).E[:, 1:, 0]
        if run.n_pairs > 1 and rig.damage is not None:
            e21 = damage_direction(rig, run.frequency_hz, run.speed_rpm, run.pairs)
        harmonics = detection_harmonics(run, self.baseline_rpm)
        m = measured_detect(new, healthy, self.settings.confidence, e21=e21, exclude=harmonics.flagged)
        fault = m.fault.copy()
        status = m.status.astype("<U13")
        dist = m.distance[:, 0].copy()
        for i in self.settings.fail_at:  # testing hook: the point could not be decided
            fault[i], status[i], dist[i] = False, "solver_failed", np.nan
        points = DetectionResult(dist, dist, m.radius[:, 0], fault, status, 0.0)
        notes = [HARMONICS_NOTE] if run.harmonics_removed == 0 and run.speed_rpm != 0.0 else []
        return Detection(self.name, run.frequency_hz, measured_verdict(fault, status, m.confidence, m.n_tests),
                         MEASURED_RULE, points, np.sqrt(np.asarray(m.statistic, dtype=float)),
                         ratio_meaning(run.n_pairs), p_value=m.family_p_value,
                         notes=notes + harmonics_notes(harmonics), measured=m, harmonics=harmonics)
