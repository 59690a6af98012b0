"""Detectors: one module per detection rule behind the :class:`Detector` protocol, chosen by name.

- :mod:`~rotorcheck.workflow.detectors.base`: the protocol, :class:`DetectorSettings`, :class:`Detection`.
- :mod:`~rotorcheck.workflow.detectors.certified`: per-point certified test against the measured healthy FRF.
- :mod:`~rotorcheck.workflow.detectors.joint`: the joint GLR with benign change as bounded nuisance.
- :mod:`~rotorcheck.workflow.detectors.enclosure`: the model-centred tests (``system``, ``data``).
- :mod:`~rotorcheck.workflow.detectors.sideband`: a breathing crack's sidebands f + k x speed against noise.
- :mod:`~rotorcheck.workflow.detectors.registry`: :data:`DETECTORS` by ``--rule`` name, :func:`make_detector`.
"""

from rotorcheck.workflow.detectors.base import Detection, Detector, DetectorSettings
from rotorcheck.workflow.detectors.registry import DETECTORS, RULES, default_rule, make_detector

__all__ = ["DETECTORS", "RULES", "Detection", "Detector", "DetectorSettings", "default_rule", "make_detector"]
