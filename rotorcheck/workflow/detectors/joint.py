"""The joint test (default with a measured baseline on a rotor): one generalized likelihood ratio over every
point and channel pair, benign change inside the rig's ``variability`` ranges as bounded nuisance (the model
re-solved at the parameters, with a model-error allowance), a crack signature per shaft element as the
alternative (:mod:`rotorcheck.robust.joint`). The per-point certified test runs first and stays as where in
frequency the data depart; each point is also certified beyond every benign change where it can be
(:func:`rotorcheck.workflow.benign.certify_beyond_benign`).

A rotating sweep that holds sidebands (version 3) is also tested for them
(:mod:`rotorcheck.workflow.detectors.sideband`: a breathing crack's tones at f + k x speed, which no benign
change makes): the false-alarm rate is split in half between the two tests (Bonferroni: together at most the
stated rate) and either one's damage verdict is the sweep's; not when the baseline's healthy sweeps held
sidebands beyond noise (the healthy rotor is then not time-invariant: said in the notes).
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.robust.joint import JOINT_RULE, JointResult, LearnedDirections
from rotorcheck.robust.validation import Verdict
from rotorcheck.signal.sidebands import HEALTHY_SIDEBAND_ALPHA
from rotorcheck.variability import benign_parameters
from rotorcheck.workflow.benign import anchored_pairs, certify_beyond_benign, joint_detection
from rotorcheck.workflow.detectors.base import Detection, DetectorSettings
from rotorcheck.workflow.detectors.certified import CertifiedDetector
from rotorcheck.workflow.detectors.sideband import SidebandDetector
from rotorcheck.workflow.measured import MeasuredRun
from rotorcheck.workflow.rigs import baseline_rig


def learned_directions(baseline: Baseline) -> LearnedDirections | None:
    """The benign directions a baseline learned from several healthy sweeps (None: none stored)."""
    if baseline.benign_directions is None:
        return None
    U = np.asarray(baseline.benign_directions)
    return LearnedDirections(U, np.asarray(baseline.benign_direction_bound), np.zeros(0), int(baseline.n_healthy))


def joint_pairs(rig: RigConfig, baseline: Baseline, run: MeasuredRun
                ) -> tuple[MeasuredRun, np.ndarray, np.ndarray, str]:
    """What the joint test reads of ``run`` and ``baseline``: ``(run, healthy FRF, its variance, note)``, the channel
    pairs restricted to those the healthy sweep's modal fit describes where the baseline predicts benign change on
    it (:func:`rotorcheck.workflow.benign.anchored_pairs`; a baseline whose drift was learned on the model re-solved
    keeps every pair, as learned); ``rig`` the rig as the baseline reads it."""
    th, var = np.asarray(baseline.healthy_frf), np.asarray(baseline.healthy_frf_var)
    if baseline.drift.on_anchor:
        return anchored_pairs(rig, run, th, var, baseline.speed_rpm)
    return run, th, var, ""


def learned_ranges_note(rig: RigConfig, baseline: Baseline) -> str:
    """What the joint test allowed when the baseline learned drift (``validate --learn-drift``): the ranges as moved,
    relative to the kept healthy sweep."""
    moved = baseline.drift.range_shift or {}
    parts = [f"{p.name} [{100 * p.lo:+.3g}, {100 * p.hi:+.3g}] %" for p in benign_parameters(rig)
             if p.name in moved and p.kind == "factor"]
    return (f"benign ranges as learned from {len(baseline.sweep_sha256 or [])} healthy sweeps, relative to the kept "
            f"one (moved over the centres that allow every sweep's fitted state): {', '.join(parts)}")


def joint_verdict(joint: JointResult, certified: Verdict) -> Verdict:
    """The sweep verdict of the joint test (its rule: :data:`rotorcheck.robust.joint.JOINT_RULE`); the
    certified fault points stay as where in frequency the data depart."""
    benign = "noise" if not joint.theta_names else "benign change inside the configured ranges and noise"
    glr = f"T = {joint.statistic:.4g} {'>' if joint.statistic > joint.threshold else '<='} {joint.threshold:.4g}"
    fit = f"H0's fit chi2 = {joint.chi2_h0:.5g} on {joint.fit_dof} dof (p = {joint.fit_p_value:.2g})"
    if joint.damage:
        # where the damage is, is the diagnosis's (rotorcheck.ranking: the one ranking detect and locate report);
        # the test's own linearized best element stays in report.json as joint_best_element
        if joint.decided_by_fit:
            why = (f"joint test: {fit} (sweep p = {joint.p_value:.2g} < {joint.false_alarm:g}); the change is not "
                   f"explained by {benign}, and no small loss of one element explains the rest ({glr}): a change "
                   "larger than the first-order crack signatures, or of another kind")
        else:
            why = (f"joint test: {glr} (p = {joint.p_value:.2g} < {joint.false_alarm:g}); the change is not explained "
                   f"by {benign}")
        return Verdict("damage", why, certified.n_points, certified.n_fault, certified.n_undecided,
                       certified.longest_run, certified.threshold)
    why = (f"joint test: {glr}, {fit} (sweep p = {joint.p_value:.2g}); the change is explained by {benign} at "
           f"false-alarm rate {joint.false_alarm:g}")
    return Verdict("healthy", why, certified.n_points, certified.n_fault, certified.n_undecided,
                   certified.longest_run, certified.threshold)


class JointDetector:
    """The joint GLR decides; the per-point certified test says where."""

    name: ClassVar[str] = "joint"
    title: ClassVar[str] = "joint test"
    encloses: ClassVar[tuple[str, ...]] = ("measured",)
    rotor_only: ClassVar[bool] = True

    def __init__(self, settings: DetectorSettings) -> None:
        self.settings = settings
        self.points = CertifiedDetector(settings)
        self.model_rig: RigConfig | None = None
        self.baseline: Baseline | None = None

    def prepare(self, rig: RigConfig, baseline: Baseline) -> None:
        """The rig as updated by the baseline (``validate --update``) and the per-point test."""
        self.points.prepare(rig, baseline)
        self.model_rig = baseline_rig(rig, baseline)
        self.baseline = baseline

    def detect(self, run: MeasuredRun) -> Detection:
        """The per-point evidence, then the joint verdict and the per-point certificate beyond benign change."""
        rig, b = self.model_rig, self.baseline
        if rig is None or b is None:
            raise RuntimeError("prepare() the detector first")
        found = self.points.detect(run)
        kappa = None if b.benign_kappa is None else float(b.benign_kappa)
        out = None if found.harmonics is None else found.harmonics.flagged
        run, th, var, note = joint_pairs(rig, b, run)
        if note:
            found.notes.append(note)
        if b.drift.range_shift is not None:
            found.notes.append(learned_ranges_note(rig, b))
        with_sidebands = run.sidebands is not None and run.speed_rpm != 0.0
        p_healthy = b.healthy.sideband_p_value
        if with_sidebands and p_healthy is not None and p_healthy < HEALTHY_SIDEBAND_ALPHA:
            with_sidebands = False
            found.notes.append(f"the sidebands were not tested: the healthy sweeps' own were beyond noise (scan p = "
                               f"{p_healthy:.3g}), so the healthy rotor is not time-invariant")
        alpha = self.settings.false_alarm / (2.0 if with_sidebands else 1.0)
        # a baseline of an earlier version that learned drift on the model re-solved is tested so
        joint = joint_detection(rig, th, var, run, kappa, learned_directions(b), alpha,
                                b.speed_rpm, b.benign_correction, exclude=out, modal=b.drift.on_anchor)
        found.detector, found.rule, found.joint = self.name, JOINT_RULE, joint
        found.verdict = joint_verdict(joint, found.verdict)
        found.statistic, found.threshold, found.p_value = joint.statistic, joint.threshold, joint.p_value
        found.notes.extend(joint.notes)
        if with_sidebands:
            # on the sidebands' own grid: a run resampled onto the baseline's keeps them as measured
            sb = SidebandDetector(dataclasses.replace(self.settings, false_alarm=alpha)).test(run)
            if p_healthy is None:
                sb.notes.append("the healthy sweeps held no sidebands: that the healthy rotor makes none is assumed, "
                                "not checked")
            found.sideband = sb
            found.rule = (f"{JOINT_RULE}; or {sb.rule} (each at half the false-alarm rate "
                          f"{self.settings.false_alarm:g}: Bonferroni)")
            if sb.verdict.verdict == "damage" and found.verdict.verdict != "damage":
                v = found.verdict
                found.verdict = Verdict("damage", f"sideband test: {sb.verdict.reason}; {v.reason}", v.n_points,
                                        v.n_fault, v.n_undecided, v.longest_run, v.threshold)
            else:
                found.notes.append(f"sideband test: {sb.verdict.reason}")
        if self.settings.verdict_only:
            return found
        certified = certify_beyond_benign(rig, th, var, run, joint, b.speed_rpm, exclude=out)
        if certified is not None:
            found.beyond_benign = certified[0]
            found.notes.extend(certified[1])
        return found
