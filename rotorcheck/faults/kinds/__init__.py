"""Fault kinds behind one registry: each module holds a kind's model (what it changes in the system, what the
harmonic balance solves, where it sits); its rig-file schema class is in :mod:`rotorcheck.config.faults`.

Adding a fault kind: its schema class in :mod:`rotorcheck.config.faults` (and in the ``Fault`` union there), a
module here with a class meeting :class:`~rotorcheck.faults.kinds.base.FaultModel`, and that class in
:data:`FAULT_MODELS`.
"""

from __future__ import annotations

from typing import Any

from rotorcheck.config import RigConfig
from rotorcheck.faults.kinds.base import FaultModel, SystemChange
from rotorcheck.faults.kinds.breathing_crack import BreathingCrackModel
from rotorcheck.faults.kinds.open_crack import OpenCrackModel
from rotorcheck.faults.kinds.spring_change import SpringChangeModel

#: every fault model, the first that applies to a schema object describes it
FAULT_MODELS: tuple[FaultModel, ...] = (OpenCrackModel(), BreathingCrackModel(), SpringChangeModel())


def fault_model(spec: Any) -> FaultModel:
    """The model of the fault ``spec`` (a schema object of a rig's ``faults``)."""
    for m in FAULT_MODELS:
        if m.applies(spec):
            return m
    raise ValueError(f"no fault model for {type(spec).__name__} {spec!r}: add one to rotorcheck.faults.kinds")


def fault_elements(config: RigConfig) -> list[int]:
    """The shaft elements of every fault of the rig (1-based, sorted)."""
    return sorted({e for f in config.faults.values() for e in fault_model(f).elements(f)})


__all__ = ["FAULT_MODELS", "FaultModel", "SystemChange", "fault_elements", "fault_model"]
