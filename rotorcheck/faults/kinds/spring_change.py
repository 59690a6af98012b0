"""A lumped spring whose stiffness changes (the three-mass rig's damage, k3 -> kd): time-invariant."""

from __future__ import annotations

from typing import ClassVar

from rotorcheck.config import Crack, SpringChange
from rotorcheck.faults.kinds.base import SystemChange


class SpringChangeModel:
    """``kind: spring_change``."""

    schema: ClassVar[type] = SpringChange
    name: ClassVar[str] = "spring change"

    def applies(self, spec: object) -> bool:
        return isinstance(spec, SpringChange)

    def built_in(self, spec: SpringChange) -> SystemChange:
        return SystemChange(stiffness_overrides={spec.spring: spec.stiffness})

    def time_varying(self, spec: SpringChange) -> Crack | None:
        return None

    def elements(self, spec: SpringChange) -> tuple[int, ...]:
        return ()
