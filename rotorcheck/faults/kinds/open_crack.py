"""An open crack: the cracked element's Young's modulus scaled by ``modulus_factor`` (chapter IV: element 4
at 46 % of E), time-invariant, the same in every direction."""

from __future__ import annotations

from typing import ClassVar

from rotorcheck.config import Crack
from rotorcheck.faults.kinds.base import SystemChange


class OpenCrackModel:
    """``kind: crack, model: open``."""

    schema: ClassVar[type] = Crack
    name: ClassVar[str] = "open crack"

    def applies(self, spec: object) -> bool:
        return isinstance(spec, Crack) and spec.model == "open"

    def built_in(self, spec: Crack) -> SystemChange:
        assert spec.modulus_factor is not None, "the schema requires it for an open crack"
        return SystemChange(modulus_factors={spec.element: spec.modulus_factor})

    def time_varying(self, spec: Crack) -> Crack | None:
        return None

    def elements(self, spec: Crack) -> tuple[int, ...]:
        return (spec.element,)
