"""The Detector protocol and registry (issue 28): a new detector is one class plus a registry entry, and
``detect`` then runs it; rules that do not fit the rig or baseline are refused naming ``--rule``."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import numpy as np
import pytest
from scipy import stats

from rotorcheck import workflow
from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError
from rotorcheck.resources import configs_dir, samples_dir
from rotorcheck.robust.validation import DetectionResult, Verdict
from rotorcheck.workflow.detectors import DETECTORS, Detection, DetectorSettings, default_rule, make_detector

TOY_RULE = "damage iff the largest |T_new - T_h|^2 / (var_new + var_h) over the points exceeds its Sidak quantile"


class LargestPointDetector:
    """A detector a newcomer might add: the largest whitened difference over the points (chi2 with 2 dof)."""

    name: ClassVar[str] = "largest-point"
    encloses: ClassVar[tuple[str, ...]] = ("measured",)
    rotor_only: ClassVar[bool] = False

    def __init__(self, settings: DetectorSettings) -> None:
        self.settings = settings

    def prepare(self, rig: RigConfig, baseline: Baseline) -> None:
        self.th = np.asarray(baseline.healthy_frf)[:, 0]
        self.vh = np.asarray(baseline.healthy_frf_var)[:, 0]

    def detect(self, run: workflow.MeasuredRun) -> Detection:
        est = workflow.frf_estimate(run)
        z = np.abs(est.frf[:, 0] - self.th) ** 2 / ((est.var[:, 0] + self.vh) / 2.0)  # chi2_2 under H0
        n = z.size
        thr = float(stats.chi2.isf(1.0 - (1.0 - self.settings.false_alarm) ** (1.0 / n), 2))
        fault = z > thr
        verdict = Verdict("damage" if fault.any() else "healthy", f"max {z.max():.4g} vs {thr:.4g}", n,
                          int(fault.sum()), 0, 0, 1)
        points = DetectionResult(np.sqrt(z), np.sqrt(z), np.full(n, np.sqrt(thr)), fault,
                                 np.where(fault, "fault", "ok"), 0.0)
        return Detection(self.name, run.frequency_hz, verdict, TOY_RULE, points, np.sqrt(z / thr),
                         "sqrt(z / threshold)", statistic=float(z.max()), threshold=thr)


@pytest.fixture(scope="module")
def open_crack() -> tuple[RigConfig, Baseline, workflow.MeasuredRun]:
    rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
    healthy = workflow.load_run(samples_dir() / "crack_rig" / "healthy_0rpm.h5", rig)
    base = workflow.validate(rig, [healthy], workflow.fit_noise(healthy)).baseline
    new = workflow.load_run(samples_dir() / "crack_rig" / "open_crack_0rpm.h5", rig)
    return rig, base, new


def test_a_registered_detector_runs_through_detect_and_its_report(open_crack, monkeypatch) -> None:
    rig, base, new = open_crack
    monkeypatch.setitem(DETECTORS, LargestPointDetector.name, LargestPointDetector)
    out = workflow.detect(rig, base, new, rule="largest-point", false_alarm=0.01)
    # the statistic computed here, independently of the detector's code path
    th, vh = base.healthy_frf[:, 0], base.healthy_frf_var[:, 0]
    z = np.abs(new.frf - th) ** 2 / ((new.output_var / np.abs(new.W) ** 2 + vh) / 2.0)
    n = z.size
    thr = stats.chi2.isf(1.0 - 0.99 ** (1.0 / n), 2)
    assert out.found.statistic == pytest.approx(float(z.max()), rel=1e-9)
    assert out.found.threshold == pytest.approx(float(thr), rel=1e-12)
    assert out.verdict.verdict == "damage" and out.exit_code == 1
    rep = out.report()
    assert rep["verdict_rule"] == TOY_RULE
    assert rep["n_fault_points"] == int(np.count_nonzero(z > thr))
    # the diagnosis after it is the same as after any detector: D_u anchored at the healthy data
    assert rep["damage_dynamics_anchored_re"] is not None


def test_default_rules_and_refusals(open_crack) -> None:
    rig, base, _ = open_crack
    assert default_rule(rig, base) == "joint"
    with pytest.raises(InputError, match="--rule"):
        make_detector(rig, base, "no-such-rule")
    assert base.bound is not None
    system = dataclasses.replace(base, bound=dataclasses.replace(base.bound, enclose="system"))
    assert default_rule(rig, system) == "system"
    with pytest.raises(InputError, match="needs a baseline validated with --enclose measured"):
        make_detector(rig, system, "joint")
    assert make_detector(rig, system, "certified").name == "system"  # that baseline's certified test
    lumped = workflow.load_rig(configs_dir() / "three_mass_trial3.yaml")
    assert default_rule(lumped, base) == "certified"
    with pytest.raises(InputError, match="lumped: use --rule certified"):
        make_detector(lumped, base, "joint")
    with pytest.raises(InputError, match="--false-alarm"):
        make_detector(rig, base, None, DetectorSettings(false_alarm=1.5))


def test_detection_and_diagnosis_plot_what_they_hold(open_crack) -> None:
    rig, base, new = open_crack
    out = workflow.detect(rig, base, new)
    fig = out.found.plot("open crack sample")
    ax = fig.axes[0]
    # the deciding ratio, point for point, is on the decision figure (a line or markers carry its values)
    drawn = np.concatenate([np.asarray(a.get_ydata(), dtype=float) for a in ax.get_lines()])
    finite = out.found.ratio[np.isfinite(out.found.ratio)]
    assert np.all(np.isin(np.round(finite, 12), np.round(drawn, 12)))
    # the measured per-point ratio is |T_new - T_h| / allowance (an independent recomputation)
    th = base.healthy_frf[:, 0]
    np.testing.assert_allclose(out.found.points.gamma_required, np.abs(new.frf - th), rtol=1e-9)
    dfig = out.diagnosis.plot(out.found.fault)
    mag = dfig.axes[0]
    ys = [np.asarray(line.get_ydata(), dtype=float) for line in mag.get_lines()]
    full = [y for y in ys if y.shape == out.diagnosis.anchored.shape]
    # the estimate is drawn exactly where its bound excludes 0 (issue 31: not read where it is not significant)
    significant = np.asarray(out.diagnosis.anchored_set.min_abs) > 0
    assert np.any(significant)
    drawn = [y for y in full if np.any(np.isfinite(y))]
    hit = [y for y in drawn if np.allclose(y[significant], np.abs(out.diagnosis.anchored)[significant], rtol=1e-9)]
    assert hit, "no line carries |D_u| at the points where its bound excludes 0"
    assert not np.any(np.isfinite(hit[0][~significant]))  # and nothing elsewhere


def test_verdict_only_gives_the_full_runs_verdict_without_the_certificates(open_crack) -> None:
    """``DetectorSettings.verdict_only`` (what locate asks before it locates): the same verdict, statistic and
    threshold as the full joint detection, without the per-point certificate beyond benign change."""
    rig, base, new = open_crack
    full = make_detector(rig, base, None, DetectorSettings()).detect(new)
    quick = make_detector(rig, base, None, DetectorSettings(verdict_only=True)).detect(new)
    assert full.beyond_benign is not None and quick.beyond_benign is None
    assert quick.verdict.verdict == full.verdict.verdict == "damage"
    assert (quick.statistic, quick.threshold, quick.p_value) == (full.statistic, full.threshold, full.p_value)
