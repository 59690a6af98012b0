"""The :class:`FaultModel` protocol: what the simulator, the drawings and the reports need of a fault kind.

A fault in a rig file is a schema object (:mod:`rotorcheck.config.faults`); its model says how it changes the
mechanical system: a time-invariant part built into the system (:class:`SystemChange`: element modulus
factors on a rotor, spring stiffness overrides on a lumped rig) and a time-varying part for the harmonic
balance (a breathing crack), and which shaft elements it sits in.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

from rotorcheck.config import Crack


@dataclass(frozen=True)
class SystemChange:
    """The time-invariant part of a fault: ``modulus_factors`` (rotor: 1-based element -> factor on E) and
    ``stiffness_overrides`` (lumped: spring name -> stiffness, N/m), as
    :func:`rotorcheck.fe.assembly.build_system` takes them."""

    modulus_factors: dict[int, float] = field(default_factory=dict)
    stiffness_overrides: dict[str, float] = field(default_factory=dict)


class FaultModel(Protocol):
    """One fault kind. ``schema``: its rig-file class; ``name``: how reports call it."""

    schema: ClassVar[type]
    name: ClassVar[str]

    def applies(self, spec: Any) -> bool:
        """Whether this model describes ``spec`` (a schema object)."""

    def built_in(self, spec: Any) -> SystemChange:
        """The time-invariant change of the system."""

    def time_varying(self, spec: Any) -> Crack | None:
        """The part the harmonic balance solves (a breathing crack), or None."""

    def elements(self, spec: Any) -> tuple[int, ...]:
        """The shaft elements the fault sits in (1-based; none for a lumped rig's fault)."""
