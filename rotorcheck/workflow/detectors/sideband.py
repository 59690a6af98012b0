"""The sideband test: a breathing crack's response at ``f + k x speed``, which benign change cannot make.

A rotor whose stiffness does not turn with the shaft (no crack; E, bearings, gain and speed drifting as they
like) is time-invariant: driven at ``f`` it responds at ``f`` only. A breathing crack opens and closes once a
turn and makes the rotor time-periodic, so the response also holds tones at ``f + k Omega`` (``Omega`` the shaft
frequency). A sweep of version 3 stores them (:mod:`rotorcheck.signal.sidebands`). Their test needs no model,
no drift model and no healthy sweep; only the noise: per point ``T_j = sum of 2 |S|^2 / var(S)`` over its
separable tones (order k, channel pair) divided by the tones' correlation scale, at most ``chi2(2 n_j)`` in
distribution without a crack (:func:`rotorcheck.signal.sidebands.sideband_points`); the sums over windows of 2, 8 and 32
adjacent points and over every point (:func:`rotorcheck.signal.sidebands.sideband_scan`), each window's p-value
times the number of windows (Bonferroni). Verdict: damage when that p-value is below the false-alarm rate.
Per point: ``T_j`` at the family-wise ``confidence`` over the points (Bonferroni) certifies the point.

Assumptions, stated with the verdict: a healthy rotor is time-invariant (an axisymmetric shaft and supports; a
shaft with different bending stiffness in two directions, or a crack already in the healthy machine, also makes
sidebands, at 2 x speed); the variances are the noise's (estimated with many degrees of freedom: treated as
known); the tones of one point are nearly independent (a tone closer than the resolution to another is left
out).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError
from rotorcheck.lazy import lazy_module
from rotorcheck.robust.validation import STATUS_EXCLUDED, STATUS_FAULT, STATUS_OK, DetectionResult, Verdict
from rotorcheck.signal.sidebands import sideband_scan
from rotorcheck.workflow.detectors.base import Detection, DetectorSettings
from rotorcheck.workflow.measured import MeasuredRun

special = lazy_module("scipy.special")  # the chi-square tails

#: the rule in words (the report's ``rule``)
SIDEBAND_RULE = ("sidebands f + k x speed against a time-invariant rotor: in windows of 2, 8 and 32 adjacent points "
                 "and over every point, T = sum of 2|S|^2/var(S) over the separable tones ~ chi2(2n) without a crack; "
                 "damage when the smallest window p-value times the number of windows (Bonferroni) is below the "
                 "false-alarm rate")


class SidebandDetector:
    """A breathing crack's sidebands against the noise of a time-invariant rotor (no model, no drift model)."""

    name: ClassVar[str] = "sideband"
    title: ClassVar[str] = "sideband test"
    encloses: ClassVar[tuple[str, ...]] = ("measured", "system", "data")
    rotor_only: ClassVar[bool] = False

    def __init__(self, settings: DetectorSettings) -> None:
        if not 0.0 < settings.confidence < 1.0:
            raise InputError(None, "--confidence", f"must be in (0, 1), got {settings.confidence}")
        self.settings = settings

    def prepare(self, rig: RigConfig, baseline: Baseline) -> None:
        """Nothing to hold: the test uses the new sweep alone."""

    def detect(self, run: MeasuredRun) -> Detection:
        """:meth:`test` as the sweep's detection (``--rule sideband``): its per-point evidence is the run's, so a run
        resampled onto another grid is refused (its sidebands stay on the sweep's own grid)."""
        sb = run.sidebands
        if sb is not None and sb.frequency_hz.shape != run.frequency_hz.shape:
            raise InputError(run.path, f"/runs/{run.run_id}/frequency", "--rule sideband reads the sweep on its own "
                             "grid: the sidebands cannot be interpolated (run without --resample, or use the default "
                             "rule, which tests them beside the joint test)")
        return self.test(run)

    def test(self, run: MeasuredRun) -> Detection:
        """The verdict of :data:`SIDEBAND_RULE` for ``run`` and its points certified at the family-wise confidence, on
        the sidebands' own grid (``Detection.frequency_hz``)."""
        sb = run.sidebands
        if sb is None:
            raise InputError(run.path, f"/runs/{run.run_id}/sideband_phasor",
                             "the sweep holds no sidebands (sweep version 3, a rotating run): --rule sideband needs "
                             "them (simulate with measurement.sideband_orders, ingest with sideband_orders)")
        alpha = self.settings.false_alarm
        t_point, n_point = sb.statistic()
        f = sb.frequency_hz
        scan = sideband_scan(t_point, n_point)
        if scan.n_tones == 0:
            verdict = Verdict("inconclusive", "no sideband could be separated at any point", f.size, 0, f.size, 0, 0)
            points = DetectionResult(np.full(f.size, np.nan), np.full(f.size, np.nan), np.zeros(f.size),
                                     np.zeros(f.size, bool), np.full(f.size, STATUS_EXCLUDED, dtype="<U13"), 0.0)
            return Detection(self.name, f, verdict, SIDEBAND_RULE, points, np.zeros(f.size), "no sideband",
                             false_alarm=alpha)
        thr = scan.threshold(alpha)
        tested = n_point > 0
        n_tested = int(tested.sum())
        a_point = (1.0 - self.settings.confidence) / max(n_tested, 1)
        thr_point = np.where(tested, special.chdtri(2 * np.maximum(n_point, 1), a_point), np.inf)
        fault = tested & (t_point > thr_point)
        status = np.where(~tested, STATUS_EXCLUDED, np.where(fault, STATUS_FAULT, STATUS_OK)).astype("<U13")
        ratio = np.where(tested, t_point / thr_point, 0.0)
        orders = ", ".join(f"{int(k):+d}" for k in sb.order)
        lo, hi = scan.points
        where = f"{f[lo]:.4g}-{f[hi - 1]:.4g} Hz ({hi - lo} points)"
        stat = (f"T = {scan.statistic:.4g} on {scan.dof} dof over {where}, p = {scan.p_value:.3g} after "
                f"{scan.n_windows} windows (Bonferroni)")
        if scan.p_value < alpha:
            reason = (f"sidebands (orders {orders}) beyond noise: {stat} < {alpha:g}; a time-invariant rotor (benign "
                      "drift included) makes none")
            verdict = Verdict("damage", reason, f.size, int(fault.sum()), 0, 0, 0)
        else:
            reason = f"sidebands (orders {orders}) within noise: the strongest window {stat} >= {alpha:g}"
            verdict = Verdict("healthy", reason, f.size, int(fault.sum()), 0, 0, 0)
        notes = [f"{scan.n_tones} separable sideband tones over {n_tested} of {f.size} points (orders {orders}); a "
                 "tone closer than the lock-in's resolution to the excitation, a shaft harmonic or another sideband "
                 "is left out",
                 "assumes the healthy rotor is time-invariant (axisymmetric shaft and supports, no crack in the "
                 "healthy machine) and the stated variances are the noise's"]
        dist = np.where(tested, t_point, np.nan)
        points = DetectionResult(dist, dist, np.where(tested, thr_point, np.nan), fault, status, 0.0)
        return Detection(self.name, f, verdict, SIDEBAND_RULE, points, ratio,
                         "sideband statistic T_j / its family-wise threshold", statistic=scan.statistic, threshold=thr,
                         p_value=scan.p_value, notes=notes, false_alarm=alpha)
