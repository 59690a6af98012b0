"""Steps 4-5: fault points of a new run against a baseline, the sweep verdict and its rule, the damage
dynamics D_u (N/m) with its bound."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.detectability import Detectability, detectability, linearized
from rotorcheck.errors import InputError
from rotorcheck.location import LocationResult
from rotorcheck.nominal import NominalModel, primary_pair
from rotorcheck.progress import Progress
from rotorcheck.report.content import conclusion
from rotorcheck.report.schema import DetectionReport, ReportValue
from rotorcheck.robust import identify
from rotorcheck.robust.identify import DamageSet
from rotorcheck.robust.joint import JointResult
from rotorcheck.robust.measured import AnchoredDamageBound, MeasuredDetection, anchored_damage_bound, io_model_error
from rotorcheck.robust.real_box import BoxCertificate
from rotorcheck.robust.validation import DetectionResult, Verdict
from rotorcheck.workflow.benign import benign_table
from rotorcheck.workflow.detectors import Detection, DetectorSettings, make_detector
from rotorcheck.workflow.detectors.base import HARMONICS_KEPT_OUT
from rotorcheck.workflow.detectors.joint import joint_pairs
from rotorcheck.workflow.directional import DirectionalDamage, damage_per_direction
from rotorcheck.workflow.locating import locate_damage
from rotorcheck.workflow.measured import (
    MeasuredRun,
    _show_pairs,
    aligned_pairs,
    baseline_pairs,
    frf_estimate,
    grid_mismatch,
    healthy_frf_of,
    pair_keys,
    per_pair,
)
from rotorcheck.workflow.rigs import baseline_rig, damage_port_name, nominal_for, speed_tolerance

if TYPE_CHECKING:  # matplotlib only for .plot()
    from matplotlib.figure import Figure


@dataclass
class Diagnosis:
    """What follows a detector's answer: the damage dynamics at the damage port, N/m per frequency (f,).

    ``damage``: D_u with the nominal model's E22 (eq. 3.11), ``damage_set`` its exact set over the uncertainty
    inherited from gamma_h and V (eq. 3.12; it carries the model's error of E22: not the estimate to read);
    ``anchored``: D_u with E22 anchored at the measured healthy FRF, ``anchored_set`` its bound (assumption: the
    noise of both sweeps at the detector's family-wise confidence, and with a measured baseline the model's
    damage-port channels in error by up to ``anchored_set.channel_error``), ``anchored_noise_only`` the same
    over the noise alone; ``damage_xy``: D at the damage station in x and y (several channel pairs; 95 % Monte
    Carlo intervals and a certified bound); ``location``: where and how big (``detect --locate``);
    ``detectability``: what this sweep could have revealed; ``notes``: what each of these rests on.
    """

    frequency_hz: np.ndarray
    damage: np.ndarray
    damage_set: DamageSet
    anchored: np.ndarray | None = None
    anchored_set: AnchoredDamageBound | DamageSet | None = None
    anchored_noise_only: AnchoredDamageBound | None = None
    damage_xy: DirectionalDamage | None = None
    location: LocationResult | None = None
    detectability: Detectability | None = None
    notes: list[str] = field(default_factory=list)

    def plot(self, fault: np.ndarray | None = None, title: str = "Damage dynamics D_u") -> Figure:
        """D_u per frequency with its bound: the anchored estimate where there is one, else the nominal."""
        from rotorcheck.report.plots import damage_dynamics_figure  # lazy: matplotlib only when plotting

        if self.anchored is not None and self.anchored_set is not None:
            d, b = self.anchored, self.anchored_set
        else:
            d, b = self.damage, self.damage_set
        return damage_dynamics_figure(self.frequency_hz, d, b.min_abs, b.max_abs, np.degrees(b.phase_min),
                                      np.degrees(b.phase_max), fault=fault, title=title)


#: exit codes of the verdicts (cli.md)
EXIT_CODES = {"healthy": 0, "damage": 1, "inconclusive": 3}


@dataclass
class DetectionOutcome:
    """Per-point detection and identification (arrays (f,)) and the sweep-level verdict."""

    rig: RigConfig
    baseline: Baseline
    run: MeasuredRun
    model: NominalModel
    found: Detection  # the detector's verdict, rule, statistic and per-point evidence
    diagnosis: Diagnosis  # the damage dynamics with their bounds, location, what the sweep could reveal

    @property
    def notes(self) -> list[str]:
        """The detector's notes, then the diagnosis's."""
        return [*self.found.notes, *self.diagnosis.notes]

    @property
    def damage(self) -> np.ndarray:
        """D_u with the nominal E22, N/m (f,)."""
        return self.diagnosis.damage

    @property
    def damage_set(self) -> DamageSet:
        """The exact set of :attr:`damage` (eq. 3.12)."""
        return self.diagnosis.damage_set

    @property
    def anchored(self) -> np.ndarray | None:
        """D_u anchored at the measured healthy FRF, N/m (f,)."""
        return self.diagnosis.anchored

    @property
    def anchored_set(self) -> AnchoredDamageBound | DamageSet | None:
        """The bound of :attr:`anchored`."""
        return self.diagnosis.anchored_set

    @property
    def anchored_noise_only(self) -> AnchoredDamageBound | None:
        """The anchored bound over the noise alone."""
        return self.diagnosis.anchored_noise_only

    @property
    def damage_xy(self) -> DirectionalDamage | None:
        """D at the damage station in x and y (several channel pairs)."""
        return self.diagnosis.damage_xy

    @property
    def location(self) -> LocationResult | None:
        """Where and how big (``detect --locate``)."""
        return self.diagnosis.location

    @location.setter
    def location(self, value: LocationResult | None) -> None:
        self.diagnosis.location = value

    @property
    def detectability(self) -> Detectability | None:
        """What this sweep could have revealed."""
        return self.diagnosis.detectability

    @property
    def detection(self) -> DetectionResult:
        """The per-point evidence (f,): gamma_required, gamma_healthy, fault, status."""
        return self.found.points

    @property
    def verdict(self) -> Verdict:
        """The sweep verdict and its reason."""
        return self.found.verdict

    @property
    def measured(self) -> MeasuredDetection | None:
        """The per-point test against the measured healthy FRF (baseline ``--enclose measured``)."""
        return self.found.measured

    @property
    def joint(self) -> JointResult | None:
        """The joint test, when it decided."""
        return self.found.joint

    @property
    def beyond_benign(self) -> BoxCertificate | None:
        """Per-point certificate beyond every benign change in the ranges (joint test)."""
        return self.found.beyond_benign

    @property
    def harmonics_warning(self) -> str:
        """Which points sit on a shaft harmonic and what they were kept out of ('' when none)."""
        h = self.found.harmonics
        return "" if h is None else h.warning(HARMONICS_KEPT_OUT)

    @property
    def exit_code(self) -> int:
        return EXIT_CODES[self.verdict.verdict]

    @property
    def verdict_rule(self) -> str:
        """The rule that made the verdict (the detector's)."""
        return self.found.rule

    @property
    def fault_beyond_benign(self) -> np.ndarray | None:
        """(f,) points unexplained after the joint test's fitted benign change in any channel pair (None: no
        joint test)."""
        return self.found.fault_beyond_benign

    def report(self) -> dict[str, ReportValue]:
        """The report.json document (cli.md keys plus context): :meth:`typed_report` as a dict."""
        return self.typed_report().to_dict()

    def typed_report(self) -> DetectionReport:
        """The report as a :class:`rotorcheck.report.schema.DetectionReport`."""
        f = self.run.frequency_hz
        fault = np.asarray(self.detection.fault, dtype=bool)
        ds = self.damage_set
        m = self.measured
        rep = DetectionReport(
            verdict=self.verdict.verdict, verdict_reason=self.verdict.reason,
            verdict_rule=self.verdict_rule,
            n_points=int(f.size), n_fault_points=int(np.count_nonzero(fault)),
            fault_frequencies_hz=[float(x) for x in f[fault]], rig_id=self.rig.rig_id,
            rig_sha256=self.rig.sha256(), sweep=str(self.run.path), sweep_sha256=self.run.sha256,
            run_id=self.run.run_id, speed_rpm=self.run.speed_rpm, band_hz=list(self.run.band_hz),
            noise_bound_m=self.baseline.noise_bound_m, noise_method=self.baseline.noise_method,
            uncertainty=self.baseline.uncertainty, parameter=self.baseline.parameter,
            enclose=self.baseline.enclose, damage_port=damage_port_name(self.rig),
            shaft_orders_removed=self.run.harmonics_removed, notes=self.notes, frequency_hz=f,
            gamma_healthy=self.detection.gamma_healthy, gamma_required=self.detection.gamma_required,
            gamma_required_upper=self.detection.gamma_required_upper, fault=fault,
            status=[str(s) for s in self.detection.status],
            damage_dynamics_re=self.damage.real, damage_dynamics_im=self.damage.imag,
            damage_bound_kind=[str(k) for k in ds.kind], damage_bound_min_abs=ds.min_abs,
            damage_bound_max_abs=ds.max_abs, damage_bound_phase_min_deg=np.degrees(ds.phase_min),
            damage_bound_phase_max_deg=np.degrees(ds.phase_max),
        )
        rep.channel_pairs = [f"{o}<-{i}" for o, i in pair_keys(self.run)] or None
        rep.stations_m = [float(z) for z in self.rig.stations] or None
        h = self.found.harmonics
        if h is not None and h.n_flagged:
            rep.shaft_harmonic_points = h.points()
        if m is not None:
            rep.confidence, rep.n_tests, rep.point_miss_probability = m.confidence, m.n_tests, m.point_miss
            rep.p_value, rep.point_p_value, rep.variance_dof = m.family_p_value, m.p_value, m.dof[:, 0]
            rep.gamma_meaning = ("measured detection: gamma_required = |T_new - T_healthy| (m/N), gamma_healthy = "
                                 "the noise allowance of that difference at the per-point level (m/N)")
        if self.anchored is not None and self.anchored_set is not None:
            a = self.anchored_set
            rep.damage_dynamics_anchored_re, rep.damage_dynamics_anchored_im = self.anchored.real, self.anchored.imag
            rep.damage_anchored_bound_kind = [str(k) for k in a.kind]
            rep.damage_anchored_bound_min_abs, rep.damage_anchored_bound_max_abs = a.min_abs, a.max_abs
            rep.damage_anchored_bound_phase_min_deg = np.degrees(a.phase_min)
            rep.damage_anchored_bound_phase_max_deg = np.degrees(a.phase_max)
            rep.damage_anchored_bound_confidence = m.confidence if m is not None else None
            if self.anchored_noise_only is not None:
                rep.damage_anchored_channel_error = getattr(a, "channel_error", None)
                rep.damage_anchored_noise_min_abs = self.anchored_noise_only.min_abs
                rep.damage_anchored_noise_max_abs = self.anchored_noise_only.max_abs
        j = self.joint
        if j is not None:
            rep.joint_statistic, rep.joint_threshold, rep.joint_p_value = j.statistic, j.threshold, j.p_value
            rep.joint_glr_p_value, rep.joint_fit_chi2 = j.glr_p_value, j.chi2_h0
            rep.joint_fit_dof, rep.joint_fit_p_value = j.fit_dof, j.fit_p_value
            rep.false_alarm, rep.candidate_elements = j.false_alarm, list(j.elements)
            rep.element_statistic = [float(x) for x in j.t_element]
            if j.elements:
                rep.joint_best_element = j.elements[j.best]
                rep.joint_stiffness_loss = float(j.severity[j.best])
                rep.joint_stiffness_loss_interval = list(j.severity_interval)
            rep.detectable_stiffness_loss = [float(x) for x in j.detectable]
            rep.benign_parameters = benign_table(j, self.rig)
            rep.benign_model_error, rep.learned_benign_directions = j.kappa, j.learned
            rem = self.fault_beyond_benign
            assert rem is not None
            rep.fault_beyond_benign = rem
            rep.fault_beyond_benign_frequencies_hz = [float(x) for x in f[rem]]
        loc = self.location
        if loc is not None:
            rep.location = loc
            b = loc.best
            if b is not None:  # the diagnosis's element: the ranking's first (detect and locate name the same)
                rep.best_element, rep.stiffness_loss = b.element, b.loss_estimate
                rep.best_element_likelihood = b.likelihood
                if loc.certified and b.status == "consistent":
                    rep.stiffness_loss_interval = [float(x) for x in b.loss_interval]
        if self.detectability is not None:
            rep.detectability = self.detectability.to_dict()
        dxy = self.damage_xy
        if dxy is not None:
            rep.damage_dynamics_by_direction = {
                d: {"re": dxy.estimate[:, k, k].real, "im": dxy.estimate[:, k, k].imag,
                    "re_interval": [dxy.re_interval[0][:, k], dxy.re_interval[1][:, k]],
                    "im_interval": [dxy.im_interval[0][:, k], dxy.im_interval[1][:, k]],
                    "interval_confidence": 0.95, "interval_draws": dxy.draws,
                    **({} if dxy.bound is None else {
                        "bound_kind": [str(x) for x in dxy.bound.kind],
                        "bound_re": [dxy.bound.re_outer[:, k, 0], dxy.bound.re_outer[:, k, 1]],
                        "bound_im": [dxy.bound.im_outer[:, k, 0], dxy.bound.im_outer[:, k, 1]],
                        "witness_re": [dxy.bound.re_inner[:, k, 0], dxy.bound.re_inner[:, k, 1]],
                        "witness_im": [dxy.bound.im_inner[:, k, 0], dxy.bound.im_inner[:, k, 1]],
                        "bound_confidence": m.confidence if m is not None else None})}
                for k, d in enumerate("xy")}
        sb = self.found.sideband if self.found.detector != "sideband" else self.found
        sbf = self.run.sidebands
        if sb is not None and sb.statistic is not None and sb.threshold is not None and sbf is not None:
            n_tones = int(np.sum(np.isfinite(sbf.frf) & np.isfinite(sbf.var)))
            rep.sideband_test = {
                "rule": sb.rule, "orders": [int(k) for k in sbf.order], "statistic": sb.statistic,
                "threshold": sb.threshold, "p_value": sb.p_value, "n_tones": n_tones,
                "false_alarm": sb.false_alarm,
                "verdict": sb.verdict.verdict, "fault_frequencies_hz": [float(x) for x in sb.frequency_hz[sb.fault]],
                "assumes": "; ".join(n for n in sb.notes if "assume" in n)}
        c = self.beyond_benign
        if c is not None:
            rep.beyond_benign_rule, rep.beyond_benign_status = c.rule, [str(x) for x in c.status]
            rep.certified_beyond_benign_frequencies_hz = [float(x) for x in f[c.unexplained]]
            rep.n_certified_beyond_benign = int(np.count_nonzero(c.unexplained))
            rep.n_undecided_beyond_benign = int(np.count_nonzero(c.undecided))
            rep.n_certified_beyond_benign_complex = int(np.count_nonzero(c.complex_unexplained))
        rep.conclusion = conclusion(rep)
        return rep


def check_baseline(baseline: Baseline, rig: RigConfig, run: MeasuredRun, baseline_path: str | Path) -> MeasuredRun:
    """Refuse a baseline made for another rig, speed or grid (InputError naming the field); returns ``run``
    with its channel pairs in the baseline's order (:func:`aligned_pairs`)."""
    if not baseline.validated or baseline.frequency_hz is None:
        raise InputError(baseline_path, "/@stage", "baseline holds only a noise fit; run 'rotorcheck validate'")
    if baseline.rig_sha256 != rig.sha256():
        raise InputError(baseline_path, "/@rig_sha256",
                         f"baseline was made for another rig description (rig_id {baseline.rig_id!r}, "
                         f"sha256 {baseline.rig_sha256[:12]}; this rig {rig.sha256()[:12]})")
    d_rpm = run.speed_rpm - baseline.speed_rpm
    tol = speed_tolerance(rig)
    why = ""
    if abs(d_rpm) <= 1e-9:
        pass
    elif baseline.speed_rpm == 0.0:
        why = "a baseline at standstill is not compared with a spinning run"
    elif tol == 0.0:
        why = "the rig's variability section sets no speed tolerance"
    elif abs(d_rpm) > tol:
        why = f"outside the rig's speed tolerance (variability: speed +-{tol:g} rpm)"
    if why:
        raise InputError(run.path, f"/runs/{run.run_id}/@speed_rpm",
                         f"{run.speed_rpm:g} rpm, the baseline is at {baseline.speed_rpm:g} rpm: {why}")
    grid = grid_mismatch(run.frequency_hz, baseline.frequency_hz)
    if grid is not None:
        raise InputError(run.path, f"/runs/{run.run_id}/frequency",
                         f"grid differs from the baseline's: {grid}; detection compares point by point "
                         "(--resample interpolates the new sweep onto the baseline's grid)")
    want = baseline_pairs(baseline)
    run = aligned_pairs(run, want)
    have = pair_keys(run)
    if want is not None and have != want:
        raise InputError(run.path, "/channels", f"channel pairs {_show_pairs(have)} differ from the baseline's "
                         f"({_show_pairs(want)}); detection compares the same channels")
    return run


def baseline_for_speed(bases: list[Baseline], rig: RigConfig, run: MeasuredRun, baseline_path: str | Path
                       ) -> Baseline:
    """The validated set of a several-run baseline at ``run``'s speed (the closest within the rig's speed
    tolerance; exact at standstill), refused naming the speeds it holds."""
    tol = speed_tolerance(rig)
    ok = [b for b in bases if abs(b.speed_rpm - run.speed_rpm) <= (tol if b.speed_rpm and run.speed_rpm else 1e-9)]
    if not ok:
        raise InputError(run.path, f"/runs/{run.run_id}/@speed_rpm", f"{run.speed_rpm:g} rpm: the baseline "
                         f"{baseline_path} holds " + ", ".join(f"{b.run_id} ({b.speed_rpm:g} rpm)" for b in bases)
                         + f" (speed tolerance +-{tol:g} rpm)")
    return min(ok, key=lambda b: abs(b.speed_rpm - run.speed_rpm))


def detect(
    rig: RigConfig, baseline: Baseline, run: MeasuredRun, fail_at: tuple[int, ...] = (), confidence: float = 0.99,
    rule: str | None = None, false_alarm: float = 0.01, progress: Progress | None = None,
) -> DetectionOutcome:
    """Steps 4-5: fault points of ``run`` against the healthy ``baseline`` and the verdict (the detector
    ``rule`` of :mod:`rotorcheck.workflow.detectors`; None: the default for the rig and baseline), then the
    damage dynamics D_u with its bound (:func:`diagnose`).

    Detectors: 'joint' (default with a measured baseline on a rotor: one GLR over every point, benign
    change inside the rig's ``variability`` ranges as bounded nuisance, ``false_alarm`` per sweep),
    'certified' (the per-point fault points against the measured healthy FRF decide, ``confidence``
    family-wise), 'system' / 'data' (against the nominal model with gamma_h; the baseline's ``enclose``).
    """
    settings = DetectorSettings(confidence, false_alarm, tuple(fail_at))
    return diagnose(rig, baseline, run, make_detector(rig, baseline, rule, settings).detect(run), progress)


def locatable_with(rig: RigConfig, baseline: Baseline) -> bool:
    """A damage can be located on ``rig`` against ``baseline``: a rotor and a measured healthy FRF."""
    return rig.kind == "rotor" and baseline.enclose == "measured" and healthy_frf_of(baseline) is not None


def diagnose(rig: RigConfig, baseline: Baseline, run: MeasuredRun, found: Detection,
             progress: Progress | None = None) -> DetectionOutcome:
    """What follows a detector's answer ``found``: the damage dynamics D_u at the damage port (eq. 3.11) with
    its bound (eq. 3.12), anchored at the measured healthy FRF where the baseline holds it, per direction
    with several channel pairs, what the sweep could have revealed (joint test), and on a damage verdict
    where (:func:`rotorcheck.workflow.locating.locate_damage` without certificates: the candidate elements
    ranked by the one machinery ``locate`` uses; ``progress`` hears each element done)."""
    if baseline.gamma is None:
        raise InputError(None, "gamma", "baseline holds only a noise fit; run 'rotorcheck validate'")
    model = nominal_for(rig, run.frequency_hz, run.speed_rpm)
    E = model.E
    T = run.frf
    notes: list[str] = []
    measured = found.measured
    identifiable = rig.damage is not None
    damage = identify.damage_dynamics(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], E[:, 1, 1], T) if identifiable else (
        np.full(T.size, np.nan + 0j))
    if not identifiable:
        dset = identify.undecided_set(T.size)
        notes.append("the rig has no damage port: no damage dynamics are identified (detection needs none)")
    elif model.structure in ("additive", "multiplicative"):
        dset = identify.damage_set_io(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], E[:, 1, 1], T, baseline.gamma,
                                      baseline.noise_bound_m, run.W, kind=model.structure)
    else:
        dset = identify.damage_set(model.P, T, baseline.gamma)
    if run.resampled_from:
        notes.append(f"the sweep was resampled from its {run.resampled_from} points onto the baseline's grid "
                     "(linear interpolation of the FRF; variances combined as for independent neighbours)")
    if run.noise_source:
        notes.append(f"FRF-only sweep: its noise is {run.noise_source}")
    if run.n_pairs > 1:
        notes.append(f"{run.n_pairs} channel pairs: detection and the joint test use all of them; the damage dynamics "
                     "D_u are identified from the rig's actuator -> sensor pair alone")
    if identifiable:
        notes.append("damage_dynamics_* (eq. 3.11 with the nominal E22) carries the nominal model's error of E22 "
                     "(its size on a healthy shaft is the model error, not damage); damage_dynamics_anchored_* "
                     "anchors E22 at the measured healthy FRF and is the estimate to read")
    anchored: np.ndarray | None = None
    anchored_set: AnchoredDamageBound | DamageSet | None = None
    noise_only: AnchoredDamageBound | None = None
    Th = healthy_frf_of(baseline)
    if Th is not None and identifiable:
        # the member of the inherited set that the healthy data selects: E22 := measured healthy FRF;
        # its bound: the difference allowance of both sweeps' noise (measured) or the uniform V
        anchored = identify.damage_dynamics(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], Th, T)
        if measured is not None:
            radius = measured.radius[:, 0]
            rho = io_model_error(model.frf, Th)
            anchored_set = anchored_damage_bound(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], Th, T, radius, rho)
            noise_only = anchored_damage_bound(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], Th, T, radius, 0.0)
            notes.append("damage_anchored_bound_*: every D consistent with both sweeps' noise (at the stated "
                         "family-wise confidence) and with the model's damage-port channels E11, E12 E21 in error "
                         "relatively by up to damage_anchored_channel_error (assumed: no more than the model's "
                         "io channel errs on the healthy data there); damage_anchored_noise_*: noise only")
        elif baseline.input_phasor is not None:
            Wh = baseline.input_phasor[:, 0]
            anchored_set = identify.damage_set_io(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], Th, T,
                                                  baseline.noise_bound_m / np.abs(Wh), baseline.noise_bound_m,
                                                  run.W)
    if identifiable and baseline.noise_bound_m > 0 and model.structure == "parametric":
        notes.append("parametric structure: the nominal damage bound covers the parameter uncertainty only, "
                     "not the noise (a second uncertainty makes the set non-circular)")
    sweep_det = None
    joint = found.joint
    if joint is not None and joint.elements:
        sweep_det = sweep_detectability(baseline_rig(rig, baseline), baseline, run, joint)
    damage_xy = None
    if identifiable and baseline.enclose == "measured" and run.n_pairs > 1:
        damage_xy = damage_per_direction(rig, run, np.asarray(baseline.healthy_frf),
                                         np.asarray(baseline.healthy_frf_var),
                                         radius=None if measured is None else measured.radius, progress=progress)
        if damage_xy is not None:
            notes.append("damage_dynamics_by_direction: D at the damage station in x and y from every channel "
                         "pair (eq. 3.11 in matrix form: the weighted least-squares member, anchored at the "
                         "measured healthy FRF); bound_re/bound_im: the certified outer intervals of every D "
                         "consistent with both sweeps' noise (each pair's difference within its allowance at the "
                         "stated family-wise confidence; the set of W is convex, D its Moebius image: SOCP support "
                         "functions plus an exact remainder bound), witness_re/witness_im the range attained inside "
                         "it; the model's receptances to and from the damage station taken as exact; "
                         "re_interval/im_interval: 95 % by Monte Carlo over the noise")
    location = None
    if found.verdict.verdict == "damage" and locatable_with(rig, baseline):
        # where: the one ranking of candidate elements that locate reports too (locate adds the certificates)
        location = locate_damage(rig, baseline, run, certify=False, damage=True, progress=progress, certify_best=True)
    diagnosis = Diagnosis(run.frequency_hz, damage, dset, anchored, anchored_set, noise_only, damage_xy,
                          location=location, detectability=sweep_det, notes=notes)
    return DetectionOutcome(rig, baseline, run, model, found, diagnosis)


def sweep_detectability(rig: RigConfig, baseline: Baseline, run: MeasuredRun, joint: JointResult) -> Detectability:
    """What this sweep could have revealed (:mod:`rotorcheck.detectability` with this sweep's and the
    baseline's variances): the element easiest to watch and the best candidate. The benign model the joint
    test allowed is linearized at the healthy state (on the crack rig within 3 % of the re-solved model's
    figures, 15 % on element 6); learned benign directions are not included."""
    f = run.frequency_hz
    run, th_all, vh_all, _ = joint_pairs(rig, baseline, run)  # the pairs the joint test read
    est = frf_estimate(run)
    P = est.frf.shape[1]
    th = per_pair(th_all, f, P, run)
    vh = per_pair(vh_all, f, P, run)
    bm = None if joint.benign is None else linearized(joint.benign)
    easiest = joint.elements[int(np.argmin(joint.detectable))]
    els = sorted({easiest, joint.elements[joint.best]})
    run_pairs = list(run.pairs) if run.pairs else [primary_pair(rig)]
    return detectability(rig, f, baseline.speed_rpm, est.var, vh, run_pairs, th, joint.false_alarm, bm, els,
                         noise_source="this sweep's and the baseline's variances", workers=1)


#: verdict rules of ``detect``: 'joint' (one GLR over all points, benign change as bounded nuisance)
#: or 'certified' (the per-point certified fault points decide, as before)


def joint_summary(outcome: DetectionOutcome) -> str:
    """Lines for the terminal: the fitted benign parameters and the smallest detectable loss."""
    j = outcome.joint
    if j is None:
        return ""
    lines = []
    if j.theta_names:
        parts = []
        for b in benign_table(j, outcome.rig):
            lo, hi = b["interval"]
            iv = (" (at its range end, the data pushing beyond it)" if b["at_range_edge"] else
                  f" [{lo:+.3g}, {hi:+.3g}]" if np.isfinite(lo) and np.isfinite(hi) else " (not fixed by the data)")
            parts.append(f"{b['name']} {b['estimate']:+.3g}{' ' if b['unit'] != '%' else ''}{b['unit']}{iv}")
        lines.append("benign change fitted: " + ", ".join(parts))
    c = outcome.beyond_benign
    if c is not None:
        lines.append(f"points certified beyond every benign change in the ranges: {int(c.unexplained.sum())} of "
                     f"{c.status.size} ({int(c.undecided.sum())} undecided; parameters as complex discs: "
                     f"{int(c.complex_unexplained.sum())})")
    d = outcome.detectability
    if d is not None:
        def pct(x: float | None) -> str:
            return "none up to 50 %" if x is None else f"{100 * x:.3g} %"
        for e in d.elements:
            lines.append(f"this sweep could have revealed a breathing crack of at least {pct(e.breathing_depth_min)} "
                         f"depth in element {e.element} (open-crack loss {pct(e.open_loss_min)}; noise alone: "
                         f"{pct(e.breathing_depth_min_noise_only)}), 90 % power at {d.false_alarm:g}")
    return "\n".join(lines)


def anchored_summary(outcome: DetectionOutcome) -> str:
    """One line: the anchored damage dynamics (median over the fault points, else the band) and its bound."""
    if outcome.anchored is None or outcome.anchored_set is None:
        return ""
    fault = np.asarray(outcome.detection.fault, dtype=bool)
    sel = fault if np.any(fault) else np.ones_like(fault)
    a = outcome.anchored[sel]
    lo = outcome.anchored_set.min_abs[sel]
    hi = outcome.anchored_set.max_abs[sel]
    where = "the fault points" if np.any(fault) else "all points"
    return (f"damage dynamics at {damage_port_name(outcome.rig)} (anchored at the healthy data, median over {where}): "
            f"Re D_u = {np.median(a.real) / 1e3:.4g} kN/m, |D_u| within [{np.median(lo) / 1e3:.4g}, "
            f"{np.median(hi) / 1e3:.4g}] kN/m (positive: stiffness loss)")
