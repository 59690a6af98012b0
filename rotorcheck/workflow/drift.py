"""Learning where the machine drifts from several healthy sweeps (``validate --learn-drift``), on the modal anchor.

Healthy sweeps taken over days sit at different states inside the ``variability`` ranges. Their mean is no state of
the machine, so the healthy FRF stays one sweep, the most central
(:func:`rotorcheck.workflow.measured.healthy_reference`), tested through its modal anchor and model-form prior exactly
as a single sweep is. What the other sweeps teach is where that reference sits among the machine's states:

1. each other sweep's benign parameters are fitted against the reference by the joint test's H0 fit, inside a box of
   twice the ranges (the change between two states inside them): ``theta_k``, the reference's own row zero;
2. the centre of the machine's drift as seen from the reference lies among the centres the declared ranges allow:
   those ``c`` with every ``theta_k - c`` inside ``[lo, hi]`` (each state's fit widened by 1.96 standard errors),
   ``[c_lo, c_hi]``, which narrows as the sweeps reach the ranges' ends. Where no centre allows every state (the
   sweeps spread beyond the declared width) the 95 % Student-t interval of the mean of the K states stands
   instead (the sweeps taken as independent draws of the drift) and the output says so. The t interval is not
   intersected with the first set: with 3 sweeps that happen to agree it is too narrow (measured: with it,
   6-7 of 100 healthy sweeps were called damage on the damper truths, a sensor gain's three training states within
   0.2 % of each other);
3. new sweeps are tested with the declared ranges moved to ``[lo + c_lo, hi + c_hi]`` (:func:`recentred_rig`);
   a parameter the sweeps do not determine (a fit at the edge of the box of step 1, or without a finite standard
   error) keeps its declared range about the reference (giving it the change between two states instead,
   ``[lo - hi, hi - lo]``, was measured: the bearings of the crack rig at rest, flat alone, then hid 5 % losses
   beside Young's modulus, found in 0-3 of 20 sweeps instead of 11-16, false alarms 0-1 of 20 either way);
4. the model-error factor kappa is the smallest of :data:`KAPPA_STEPS` under which the other sweeps, each tested
   against the reference with the ranges learned without it, raise no more alarms than noise would at the stated
   false-alarm rate (binomial, 1 %).

With one sweep the ranges are read about that sweep's state; with several, about the centre of the sweeps. More sweeps
narrow the centre's set (as the sweeps reach the ranges' ends), so the test's power grows with K (measured per truth
variant: bench/results_independent_physics.md, round eight).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import bdtrc, stdtrit

from rotorcheck.config import RigConfig
from rotorcheck.variability import benign_at, benign_parameters, pair_ranges, recentred_rig
from rotorcheck.workflow.benign import KAPPA_MODAL, anchored_pairs, joint_detection
from rotorcheck.workflow.measured import MeasuredRun, frf_estimate

#: model-error factors tried, smallest first, when the training sweeps test the anchor (the first is the default)
KAPPA_STEPS = (KAPPA_MODAL, 0.25, 0.5, 1.0, 2.0)
#: confidence of the interval of the drift's centre the ranges are widened by
CENTRE_CONFIDENCE = 0.95
#: the level at which the training sweeps' alarms are more than noise (binomial upper tail)
ALARM_LEVEL = 0.01
#: the rule, in words, for reports
DRIFT_RULE = ("ranges moved over the centres that allow every healthy sweep's fitted state (the mean's "
              f"{100 * CENTRE_CONFIDENCE:g} % Student-t interval where none does); kappa the smallest of {KAPPA_STEPS} "
              f"under which the sweeps, each left out, raise no more alarms than noise at {ALARM_LEVEL:g} (binomial)")


@dataclass
class DriftLearning:
    """What :func:`learn_drift_ranges` learned: per benign parameter (``names``, the rig's order at the sweeps'
    speed) the training sweeps' fitted states relative to the reference ``theta`` (K, p) (relative change for
    factors, the unit for offsets; the reference's row zero), the ranges' shift ``shift`` (p,) and widening ``widen``
    (p,) each side, the model-error factor ``kappa`` and the leave-one-out alarms at each factor tried."""

    names: tuple[str, ...]
    theta: np.ndarray
    theta_se: np.ndarray
    shift: np.ndarray
    widen: np.ndarray
    kappa: float
    reference: int
    alarms: dict[float, int] = field(default_factory=dict)
    allowed: int = 0  # alarms of the K - 1 left-out sweeps that noise alone explains (binomial, ALARM_LEVEL)
    determined: np.ndarray | None = None  # (p,) bool: the sweeps determine the parameter (else its range stays)
    beyond: np.ndarray | None = None  # (p,) bool: the sweeps spread beyond the declared width (no centre fits)
    alarmed: tuple[int, ...] = ()  # the sweeps called damage, left out, at the default kappa (is each healthy?)

    @property
    def shift_by_name(self) -> dict[str, float]:
        """``{parameter: shift}``, the form stored in a baseline."""
        return {n: float(x) for n, x in zip(self.names, self.shift)}

    @property
    def widen_by_name(self) -> dict[str, float]:
        """``{parameter: widening each side}``, the form stored in a baseline."""
        return {n: float(x) for n, x in zip(self.names, self.widen)}

    def as_dict(self, rig: RigConfig) -> dict[str, object]:
        """``validate --json``'s ``learned_drift``: the kept sweep (1-based), kappa, the rule, and per parameter the
        range the joint test will allow, in %, relative to the kept sweep (``rig``: the rig as validated)."""
        declared = {p.name: p for p in benign_parameters(rig)}
        det = np.ones(len(self.names), dtype=bool) if self.determined is None else self.determined
        rows = []
        for n, c, w, d in zip(self.names, self.shift, self.widen, det):
            p = declared[n]
            rows.append({"name": n, "range": [100.0 * (p.lo + c - w), 100.0 * (p.hi + c + w)], "determined": bool(d)})
        return {"kept_sweep": self.reference + 1, "kappa": self.kappa, "rule": DRIFT_RULE, "parameters": rows}

    def summary(self) -> str:
        """Lines for ``validate``'s output: the learned centre and widening per parameter, kappa and its check."""
        k = self.theta.shape[0]
        lines = [f"benign drift learned from {k} healthy sweeps on the modal anchor of sweep {self.reference + 1}: "
                 f"kappa = {self.kappa:g} (left-out alarms {self.alarms}; noise explains up to {self.allowed})"]
        if self.alarmed:
            which = ", ".join(str(k + 1) for k in self.alarmed)
            lines.append(f"  warning: sweep(s) {which}, tested against the others at kappa {KAPPA_STEPS[0]:g}, read as "
                         "damage: if one of them is not a healthy state, validate without it (a damaged sweep among "
                         "the healthy ones makes the detector blinder)")
        p = len(self.names)
        det = np.ones(p, dtype=bool) if self.determined is None else self.determined
        out = np.zeros(p, dtype=bool) if self.beyond is None else self.beyond
        for n, c, w, d, b in zip(self.names, self.shift, self.widen, det, out):
            if not d:
                lines.append(f"  {n}: not determined by the sweeps (a fit at the edge, or flat): its declared range "
                             "about the reference")
                continue
            lines.append(f"  {n}: ranges moved by {_show(n, c)}, widened by {_show(n, w)} each side"
                         + (" (the sweeps spread beyond the declared width: the mean's interval alone)" if b else ""))
        return "\n".join(lines)


def _show(name: str, x: float) -> str:
    return f"{x:+.4g} rpm" if name == "speed" else f"{100 * x:+.3g} %"


def allowed_alarms(n: int, false_alarm: float, level: float = ALARM_LEVEL) -> int:
    """The most alarms of ``n`` healthy sweeps tested at ``false_alarm`` that noise explains: the largest m with
    ``P(Binomial(n, false_alarm) >= m) > level`` (0 when n is 0)."""
    m = 0
    while m < n and float(bdtrc(m, n, false_alarm)) > level * (1.0 + 1e-9):  # bdtrc(m) = P(X >= m + 1)
        m += 1
    return m


def _mean_interval(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)`` of the mean of the rows: its ``CENTRE_CONFIDENCE`` interval (Student t; the mean alone for one
    row)."""
    k = theta.shape[0]
    c = theta.mean(axis=0)
    if k < 2:
        return c, c
    half = float(stdtrit(k - 1, 0.5 + CENTRE_CONFIDENCE / 2.0)) * theta.std(axis=0, ddof=1) / np.sqrt(k)
    return c - half, c + half


def drift_centre(theta: np.ndarray, theta_se: np.ndarray, lo: np.ndarray, hi: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(c_lo, c_hi, beyond)`` per parameter: where the centre of the states ``theta`` (K, p) lies (see the module
    docstring, step 2) given the declared ranges ``[lo, hi]`` (p,) and each state's standard error (K, p);
    ``beyond``: no centre allows every state (the mean's t interval is returned there)."""
    m_lo, m_hi = _mean_interval(theta)
    margin = 1.96 * np.where(np.isfinite(theta_se), theta_se, 0.0)
    c_lo = np.max(theta - margin, axis=0) - hi
    c_hi = np.min(theta + margin, axis=0) - lo
    beyond = c_lo > c_hi
    return np.where(beyond, m_lo, c_lo), np.where(beyond, m_hi, c_hi), beyond


def learn_drift_ranges(rig: RigConfig, runs: list[MeasuredRun], reference: int, false_alarm: float = 0.01,
                       exclude: np.ndarray | None = None) -> DriftLearning:
    """Where the reference sweep ``runs[reference]`` sits among the machine's drifted states, from the other sweeps
    (see the module docstring). ``exclude`` (f,) bool: points on a shaft harmonic (no weight). The sweeps share the
    grid and the channel pairs, and their speeds lie within twice the speed range (``validate`` checks it); each
    sweep's measured speed offset from the reference enters its fit as a new sweep's does in ``detect``."""
    ref = runs[reference]
    speed = ref.speed_rpm
    est = frf_estimate(ref)
    params = [p for p in benign_at(rig, speed) if not p.is_speed]
    names = tuple(p.name for p in params)
    wide = pair_ranges(rig, speed)
    lo, hi = np.array([p.lo for p in params]), np.array([p.hi for p in params])
    theta = np.zeros((len(runs), len(names)))
    se = np.zeros_like(theta)
    determined = np.ones(len(names), dtype=bool)
    others = [k for k in range(len(runs)) if k != reference]
    for k in others:
        run, th, var, _ = anchored_pairs(wide, runs[k], est.frf, est.var, speed)
        j = joint_detection(wide, th, var, run, None, false_alarm=false_alarm, speed_rpm=speed, exclude=exclude)
        fitted = dict(zip(j.theta_names, zip(j.theta, j.theta_se, j.theta_at_bound)))
        theta[k] = [fitted[n][0] for n in names]
        se[k] = [fitted[n][1] for n in names]
        determined &= np.array([not fitted[n][2] and np.isfinite(fitted[n][1]) for n in names])

    def moved_ranges(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(shift, widen, beyond)`` from the states of ``rows``; parameters not determined keep their declared
        ranges about the reference."""
        c_lo, c_hi, out = drift_centre(theta[rows], se[rows], lo, hi)
        return (np.where(determined, (c_lo + c_hi) / 2.0, 0.0), np.where(determined, (c_hi - c_lo) / 2.0, 0.0),
                out & determined)

    shift, widen, beyond = moved_ranges(np.arange(len(runs)))

    def left_out_alarm(k: int, kappa: float) -> bool:
        c, w, _ = moved_ranges(np.delete(np.arange(len(runs)), k))
        moved = recentred_rig(rig, dict(zip(names, c)), dict(zip(names, w)))
        run, th, var, _ = anchored_pairs(moved, runs[k], est.frf, est.var, speed)
        return bool(joint_detection(moved, th, var, run, kappa, false_alarm=false_alarm, speed_rpm=speed,
                                    exclude=exclude).damage)

    allowed = allowed_alarms(len(others), false_alarm)
    alarms: dict[float, int] = {}
    alarmed: tuple[int, ...] = ()
    kappa = KAPPA_STEPS[-1]
    for step in KAPPA_STEPS:
        called = tuple(k for k in others if left_out_alarm(k, step))
        alarms[step] = len(called)
        alarmed = alarmed or called
        if alarms[step] <= allowed:
            kappa = step
            break
    return DriftLearning(names, theta, se, shift, widen, kappa, reference, alarms, allowed, determined, beyond,
                         alarmed)
