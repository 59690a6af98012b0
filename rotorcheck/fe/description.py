"""What the FE engine reads of a rig: the mechanical description only (issue 28).

A rig file (:class:`rotorcheck.config.RigConfig`) also holds ports, uncertainty, faults, the benign ranges,
measurement and analysis settings; the assembly (:func:`rotorcheck.fe.assembly.build_system`) reads none of
them. :class:`MechanicalDescription` names what it does read, so any object with these attributes (a
``RigConfig``, a variant of one, a test's own) can be assembled, and the assembly caches by these fields
alone (:data:`MECHANICAL_FIELDS`): two rigs that differ only in ports or faults share one assembled shaft.
SI units throughout (m, kg, N/m, N s/m, Pa).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Literal, Protocol

from rotorcheck.config import (
    Bearing,
    Disc,
    LumpedMass,
    LumpedSpring,
    Material,
    PointMass,
    ShaftElement,
    StationSpring,
)
from rotorcheck.config.damping import DampingModel

#: the fields of a rig the assembly reads (its cache key is their content)
MECHANICAL_FIELDS: frozenset[str] = frozenset({
    "kind", "materials", "stations", "shaft", "discs", "point_masses", "bearings", "springs", "shear_method",
    "shear_coefficient", "shear", "rotary_inertia", "gyroscopic", "tapered_element", "masses", "lumped_springs",
    "damping"})


class MechanicalDescription(Protocol):
    """A rig's mechanics: a rotor (stations m, shaft elements, discs, point masses, bearings, station springs,
    shear and inertia switches) or a lumped model (masses kg, springs N/m), and its damping."""

    @property
    def kind(self) -> Literal["rotor", "lumped"]: ...
    @property
    def materials(self) -> Mapping[str, Material]: ...
    @property
    def stations(self) -> Sequence[float]: ...
    @property
    def shaft(self) -> Sequence[ShaftElement]: ...
    @property
    def discs(self) -> Sequence[Disc]: ...
    @property
    def point_masses(self) -> Sequence[PointMass]: ...
    @property
    def bearings(self) -> Sequence[Bearing]: ...
    @property
    def springs(self) -> Sequence[StationSpring]: ...
    @property
    def shear_method(self) -> str: ...
    @property
    def shear_coefficient(self) -> float | None: ...
    @property
    def shear(self) -> bool: ...
    @property
    def rotary_inertia(self) -> bool: ...
    @property
    def gyroscopic(self) -> bool: ...
    @property
    def tapered_element(self) -> Literal["exact", "greenhill"]: ...
    @property
    def masses(self) -> Sequence[LumpedMass]: ...
    @property
    def lumped_springs(self) -> Sequence[LumpedSpring]: ...
    @property
    def damping(self) -> DampingModel: ...
    @property
    def n_support_nodes(self) -> int:
        """Support (pedestal) nodes a bearing reaches after the shaft stations (rotor)."""
        ...
