"""The detectors by name (``detect --rule``) and the choice of one for a rig and baseline.

Adding a detector: a module in this package with a class that meets
:class:`~rotorcheck.workflow.detectors.base.Detector`, and its class in :data:`DETECTORS` below.
"""

from __future__ import annotations

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError, check_choice
from rotorcheck.workflow.detectors.base import Detector, DetectorSettings
from rotorcheck.workflow.detectors.certified import CertifiedDetector
from rotorcheck.workflow.detectors.enclosure import DataEnclosure, SystemEnclosure
from rotorcheck.workflow.detectors.joint import JointDetector
from rotorcheck.workflow.detectors.sideband import SidebandDetector

#: every detector by its ``--rule`` name
DETECTORS: dict[str, type[Detector]] = {d.name: d for d in (JointDetector, CertifiedDetector, SystemEnclosure,
                                                            DataEnclosure, SidebandDetector)}
#: the ``--rule`` choices
RULES = tuple(DETECTORS)


def default_rule(rig: RigConfig, baseline: Baseline) -> str:
    """The joint test on a rotor with a measured baseline; the per-point certified test on a lumped rig; the
    model-centred test of a baseline validated with ``--enclose system|data``."""
    if baseline.enclose == "measured":
        return "joint" if rig.kind == "rotor" else "certified"
    return baseline.enclose


def make_detector(rig: RigConfig, baseline: Baseline, rule: str | None = None,
                  settings: DetectorSettings | None = None) -> Detector:
    """The detector ``rule`` (None: :func:`default_rule`), prepared for ``rig`` and ``baseline``; a rule that
    does not fit them is an InputError naming ``--rule``. ``certified`` on a model-centred baseline is that
    baseline's certified test."""
    settings = settings if settings is not None else DetectorSettings()
    if not 0.0 < settings.false_alarm < 1.0:
        raise InputError(None, "--false-alarm", f"must be in (0, 1), got {settings.false_alarm}")
    if rule is None:
        name = default_rule(rig, baseline)
    else:
        name = check_choice(rule, DETECTORS, "--rule")
        if name == "certified" and baseline.enclose in ("system", "data"):
            name = baseline.enclose
    cls = DETECTORS[name]
    if baseline.enclose not in cls.encloses:
        what = getattr(cls, "title", f"{name} rule")
        raise InputError(None, "--rule", f"the {what} needs a baseline validated with --enclose "
                         f"{' or '.join(cls.encloses)} (this one: {baseline.enclose!r})")
    if cls.rotor_only and rig.kind != "rotor":
        raise InputError(None, "--rule", f"the {getattr(cls, 'title', name)} needs a rotor's shaft elements (crack "
                         "signatures); this rig is lumped: use --rule certified")
    detector = cls(settings)
    detector.prepare(rig, baseline)
    return detector
