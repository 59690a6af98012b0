"""A breathing crack (Mayes-Davies, Gasch, Jun et al.): the element's stiffness opens and closes with the shaft
angle, a time-periodic change solved by the harmonic balance (:mod:`rotorcheck.faults.harmonic_balance`);
nothing is built into the time-invariant system."""

from __future__ import annotations

from typing import ClassVar

from rotorcheck.config import Crack
from rotorcheck.faults.kinds.base import SystemChange


class BreathingCrackModel:
    """``kind: crack, model: mayes_davies | gasch | jun``."""

    schema: ClassVar[type] = Crack
    name: ClassVar[str] = "breathing crack"

    def applies(self, spec: object) -> bool:
        return isinstance(spec, Crack) and spec.model != "open"

    def built_in(self, spec: Crack) -> SystemChange:
        return SystemChange()

    def time_varying(self, spec: Crack) -> Crack | None:
        return spec

    def elements(self, spec: Crack) -> tuple[int, ...]:
        return (spec.element,)
