"""The :class:`Detector` protocol, its settings and the typed :class:`Detection` every detector returns.

A detector is made with :class:`DetectorSettings`, then ``prepare(rig, baseline)`` once per baseline and
``detect(run)`` once per measured run. Registering a new one: a module in this package with a class that
meets the protocol, and one ``@register`` line (see :mod:`rotorcheck.workflow.detectors.registry`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.robust.joint import JointResult
from rotorcheck.robust.measured import MeasuredDetection
from rotorcheck.robust.real_box import BoxCertificate
from rotorcheck.robust.validation import STATUS_EXCLUDED, DetectionResult, Verdict
from rotorcheck.signal.harmonics import ShaftHarmonics
from rotorcheck.workflow.measured import MeasuredRun, run_harmonics

if TYPE_CHECKING:  # matplotlib only for .plot()
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class DetectorSettings:
    """What the user sets for a detection: the per-point test's family-wise ``confidence`` (over every point
    and channel pair), the joint test's per-sweep ``false_alarm`` rate, ``fail_at`` (a testing hook: these
    point indices are reported as a solver failure) and ``verdict_only`` (the verdict and its evidence without
    the certificates that follow it, e.g. the joint detector's points beyond every benign change: what a
    caller that needs the verdict alone asks for)."""

    confidence: float = 0.99
    false_alarm: float = 0.01
    fail_at: tuple[int, ...] = ()
    verdict_only: bool = False


@dataclass
class Detection:
    """One detector's answer for one run.

    ``verdict`` ('damage' | 'healthy' | 'inconclusive' with its reason); ``rule``: the rule that made it,
    in words; ``statistic``, ``threshold``, ``p_value``: the sweep-level test where there is one (None for a
    per-point rule without a sweep statistic); ``points``: the per-point evidence over the f points
    (``gamma_required``, ``gamma_healthy``, ``fault``, ``status``); ``ratio`` (f,): the statistic that decided
    per point, against a threshold of 1; ``notes``: what the reader must know. The detector's own results
    stay typed beside it (``measured``, ``joint``, ``beyond_benign``; ``sideband``: the sideband test's own detection
    where it ran beside the joint test).
    """

    detector: str
    frequency_hz: np.ndarray
    verdict: Verdict
    rule: str
    points: DetectionResult
    ratio: np.ndarray
    ratio_meaning: str
    statistic: float | None = None
    threshold: float | None = None
    p_value: float | None = None
    notes: list[str] = field(default_factory=list)
    false_alarm: float | None = None  # the per-sweep rate the sweep-level test was held to (where there is one)
    measured: MeasuredDetection | None = None
    joint: JointResult | None = None
    beyond_benign: BoxCertificate | None = None
    harmonics: ShaftHarmonics | None = None  # points on a shaft harmonic: status 'excluded', in no claim
    sideband: Detection | None = None  # the sideband test beside the joint test (a sweep with sidebands)

    @property
    def fault(self) -> np.ndarray:
        """(f,) bool: the certified fault points."""
        return np.asarray(self.points.fault, dtype=bool)

    @property
    def fault_beyond_benign(self) -> np.ndarray | None:
        """(f,) points unexplained after the joint test's fitted benign change in any channel pair (None: no
        joint test)."""
        if self.joint is None:
            return None
        f = self.frequency_hz
        return np.asarray(np.asarray(self.joint.remaining, dtype=bool).reshape(-1, f.size).any(axis=0))

    def plot(self, title: str = "") -> Figure:
        """The decision figure: the deciding ratio per frequency against 1, fault points, the sweep test."""
        from rotorcheck.report.plots import FigureContext, decision_figure  # lazy: matplotlib only when plotting

        joint = None if self.joint is None else {
            "statistic": self.joint.statistic, "threshold": self.joint.threshold, "p_value": self.joint.p_value,
            "false_alarm": self.joint.false_alarm}
        ctx = FigureContext(rig_id=title or self.detector)
        return decision_figure(self.frequency_hz, self.ratio, self.fault, np.asarray(self.points.status), ctx,
                               self.verdict.verdict, self.rule, self.ratio_meaning, joint, self.fault_beyond_benign)


#: what a detection keeps the points on a shaft harmonic out of (the warning's words)
HARMONICS_KEPT_OUT = ("the certified fault points, the joint statistic and its benign fit, and the certificate "
                      "beyond benign change")


def detection_harmonics(run: MeasuredRun, baseline_rpm: float) -> ShaftHarmonics:
    """The points of ``run`` on a shaft harmonic at its own speed or the baseline's (a healthy sweep at the
    baseline's speed holds that speed's unbalance response)."""
    return run_harmonics([run], (baseline_rpm,))


def exclude_points(points: DetectionResult, harmonics: ShaftHarmonics) -> DetectionResult:
    """``points`` with the flagged points no fault and of status 'excluded' (their numbers kept)."""
    out = harmonics.flagged
    if not np.any(out):
        return points
    points.fault = np.asarray(points.fault, dtype=bool) & ~out
    points.status = np.where(out, STATUS_EXCLUDED, np.asarray(points.status)).astype("<U13")
    return points


def harmonics_notes(harmonics: ShaftHarmonics) -> list[str]:
    """The warning for the notes ([] when no point is flagged)."""
    w = harmonics.warning(HARMONICS_KEPT_OUT)
    return [w] if w else []


class Detector(Protocol):
    """A detection rule: ``prepare`` once against a rig and baseline, then ``detect`` each run.

    ``name``: the registry key (``--rule``); ``encloses``: the baseline ``enclose`` modes it accepts;
    ``rotor_only``: needs a rotor's shaft elements.
    """

    name: ClassVar[str]
    encloses: ClassVar[tuple[str, ...]]
    rotor_only: ClassVar[bool]

    def __init__(self, settings: DetectorSettings) -> None: ...

    def prepare(self, rig: RigConfig, baseline: Baseline) -> None:
        """Hold what every run against this rig and baseline shares."""

    def detect(self, run: MeasuredRun) -> Detection:
        """The verdict for ``run`` with its rule, statistic and per-point evidence."""
