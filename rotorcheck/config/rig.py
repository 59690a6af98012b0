"""The rig description :class:`RigConfig`: a rotor or lumped model with its ports, faults and ranges."""

from __future__ import annotations

import hashlib
import json
from typing import Any, Literal

from pydantic import ConfigDict, Field, model_validator

from rotorcheck.config.analysis import Analysis, Measurement
from rotorcheck.config.base import ConfigError, Strict
from rotorcheck.config.benign import BenignRange
from rotorcheck.config.damping import DampingModel, NoDamping
from rotorcheck.config.faults import Crack, Fault, SpringChange
from rotorcheck.config.lumped import LumpedMass, LumpedSpring
from rotorcheck.config.ports import DamagePort, Ports, Uncertainty
from rotorcheck.config.quantities import Length, Ratio
from rotorcheck.config.shaft import Disc, Material, PointMass, ShaftElement, ShearMethod
from rotorcheck.config.supports import BEARING_TERMS, Bearing, SpeedTable, StationSpring


class RigConfig(Strict):
    """A rig: nominal model or simulated truth."""

    schema_: Literal["rotorcheck.rig"] = Field(default="rotorcheck.rig", alias="schema")
    version: Literal[1] = 1
    rig_id: str = Field(min_length=1)
    kind: Literal["rotor", "lumped"] = "rotor"
    description: str = ""
    # rotor
    materials: dict[str, Material] = Field(default_factory=dict)
    stations: list[Length] = Field(default_factory=list, description="axial positions, m")
    shaft: list[ShaftElement] = Field(default_factory=list)
    discs: list[Disc] = Field(default_factory=list)
    point_masses: list[PointMass] = Field(default_factory=list)
    bearings: list[Bearing] = Field(default_factory=list)
    springs: list[StationSpring] = Field(default_factory=list)
    shear_method: ShearMethod = Field(default="hutchinson", description="shear coefficient formula (rotor)")
    shear_coefficient: Ratio | None = Field(default=None, gt=0, le=2, description="kappa for every element")
    shear: bool = Field(default=True, description="shear deformation in the shaft (False: Euler-Bernoulli)")
    rotary_inertia: bool = Field(default=True, description="rotary inertia of the shaft")
    gyroscopic: bool = Field(default=True, description="gyroscopic coupling of shaft and discs")
    tapered_element: Literal["exact", "greenhill"] = Field(
        default="exact", description="stiffness of tapered elements: exact (flexibility of the actual "
        "tapered beam) or greenhill (Greenhill et al. 1985, one mid-section shear parameter; ROSS's)")
    # lumped
    masses: list[LumpedMass] = Field(default_factory=list)
    lumped_springs: list[LumpedSpring] = Field(default_factory=list)
    # common
    damping: DampingModel = Field(default_factory=NoDamping)
    ports: Ports | None = Field(default=None, description="actuator and sensor; optional (modal analysis)")
    damage: DamagePort | None = None
    uncertainty: Uncertainty = Field(default_factory=Uncertainty)
    faults: dict[str, Fault] = Field(default_factory=dict)
    measurement: Measurement = Field(default_factory=Measurement)
    analysis: Analysis = Field(default_factory=Analysis)
    variability: list[BenignRange] = Field(
        default_factory=list, description="benign parameter ranges: changes the detector must not call damage"
    )

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)

    @model_validator(mode="after")
    def _consistency(self) -> RigConfig:
        if self.kind == "rotor":
            self._check_rotor()
        else:
            self._check_lumped()
        if self.uncertainty.structure == "parametric" and self.uncertainty.parameter:
            self._check_uncertainty_parameter(self.uncertainty.parameter)
        if self.kind == "rotor" and any(abs(z) > 1e4 for z in self.stations):
            raise ValueError("stations: positions beyond 10 km: not a rotor (give metres, or units such as '160 mm')")
        return self

    # -- rotor checks ------------------------------------------------------------------------
    def _check_rotor(self) -> None:
        n = len(self.stations)
        if n < 2:
            raise ValueError("stations: a rotor needs at least 2 stations")
        if any(b <= a for a, b in zip(self.stations, self.stations[1:])):
            raise ValueError("stations: positions must be strictly increasing")
        if not self.shaft:
            raise ValueError("shaft: a rotor needs shaft elements")
        refine: dict[int, tuple[int, int]] = {}
        for i, e in enumerate(self.shaft):
            if e.end > n:
                raise ValueError(f"shaft[{i}].end: station {e.end} out of range 1..{n}")
            if e.material not in self.materials:
                raise ValueError(f"shaft[{i}].material: unknown material {e.material!r}")
            first = refine.setdefault(e.start, (i, e.refine))
            if first[1] != e.refine:
                raise ValueError(f"shaft[{i}].refine: {e.refine}, but shaft[{first[0]}] on the same stations "
                                 f"{e.start}-{e.end} (a concentric layer) has {first[1]}; layers share one mesh")
        missing = [k for k in range(1, n) if k not in refine]
        if missing:
            k = missing[0]
            raise ValueError(f"shaft: no element joins stations {k} and {k + 1} (the shaft must be continuous "
                             f"over stations 1..{n}; several elements on one pair are concentric layers)")
        for group in ("discs", "springs"):
            for i, part in enumerate(getattr(self, group)):
                if part.station > n:
                    raise ValueError(f"{group}[{i}].station: {part.station} out of range 1..{n}")
        for i, d in enumerate(self.discs):
            if d.material is not None and d.material not in self.materials:
                raise ValueError(f"discs[{i}].material: unknown material {d.material!r}")
        self._check_support_nodes(n)
        if {"shear_method", "shear_coefficient"} <= self.model_fields_set and self.shear_coefficient is not None:
            raise ValueError("shear_coefficient: give shear_method or shear_coefficient, not both (the "
                             "coefficient would override the method everywhere)")
        if not any(self.shear if e.shear is None else e.shear for e in self.shaft):
            for key in ("shear_method", "shear_coefficient"):
                if key in self.model_fields_set and getattr(self, key) is not None:
                    raise ValueError(f"{key}: unused: no shaft element has shear deformation (shear: false)")
        at: dict[int, int] = {}
        for i, b in enumerate(self.bearings):
            if b.n_link is not None:
                continue
            if b.station in at:
                raise ValueError(f"bearings[{i}].station: station {b.station} already has bearings[{at[b.station]}] "
                                 "to ground (one per station; give their sum, or a spring)")
            at[b.station] = i
        for group in ("masses", "lumped_springs"):
            if getattr(self, group):
                raise ValueError(f"{group}: applies to kind: lumped only (a rotor takes discs, bearings and "
                                 "springs); it would be ignored")
        for name in ("actuator", "sensor"):
            if self.ports is None:
                break
            p = getattr(self.ports, name)
            if p.mass is not None:
                raise ValueError(f"ports.{name}.mass: a rotor port is a station and direction")
            if p.station is None or p.station > n:
                raise ValueError(f"ports.{name}.station: must be a station in 1..{n}")
        if self.damage is not None:
            p = self.damage.port
            if p.station is None or p.station > n:
                raise ValueError(f"damage.port.station: must be a station in 1..{n}")
            de = self.damage.element
            if de is not None and de > n - 1:
                raise ValueError(f"damage.element: {de} out of range 1..{n - 1}")
            if de is not None and p.station is not None and p.station not in (de, de + 1):
                raise ValueError(f"damage.element: element {de} joins stations {de} and {de + 1}; the damage port "
                                 f"is at station {p.station}")
        for key, f in self.faults.items():
            if isinstance(f, Crack) and f.element > n - 1:
                raise ValueError(f"faults.{key}.element: {f.element} out of range 1..{n - 1}")
            if isinstance(f, SpringChange):
                raise ValueError(f"faults.{key}: spring_change applies to lumped models only")
        for i, u in enumerate(self.measurement.unbalance):
            if u.station > n:
                raise ValueError(f"measurement.unbalance[{i}].station: out of range 1..{n}")
        mis = self.measurement.misalignment
        if mis is not None and mis.station > n:
            raise ValueError(f"measurement.misalignment.station: out of range 1..{n}")

    def _check_support_nodes(self, n: int) -> None:
        """Support nodes (numbered n+1, n+2, ... after the shaft stations): linked by a bearing's
        ``n_link``, each with a point mass in x and y, numbered without gaps."""
        nodes = self.support_nodes
        for i, pm in enumerate(self.point_masses):
            if pm.station > n and pm.station not in nodes:
                raise ValueError(f"point_masses[{i}].station: {pm.station} is neither a station (1..{n}) nor a "
                                 "support node that a bearing links (n_link)")
        linked = {b.n_link for b in self.bearings if b.n_link is not None}
        for node in nodes:
            if node not in linked:
                raise ValueError(f"bearings: support node {node} (after the last station {n}) is not linked to "
                                 f"the rotor: give a bearing with n_link: {node}")
            mx = sum(pm.masses[0] for pm in self.point_masses if pm.station == node)
            my = sum(pm.masses[1] for pm in self.point_masses if pm.station == node)
            if mx <= 0 or my <= 0:
                raise ValueError(f"point_masses: support node {node} has no mass in x and y (a massless pedestal "
                                 "is a series spring: fold it into the bearing, or give the pedestal's mass)")
        if nodes and list(nodes) != list(range(n + 1, n + 1 + len(nodes))):
            raise ValueError(f"bearings: support nodes must be numbered {n + 1}, {n + 2}, ... without gaps "
                             f"(got {list(nodes)})")

    @property
    def support_nodes(self) -> tuple[int, ...]:
        """Support (pedestal) nodes a bearing reaches after the shaft stations (rotor), ascending."""
        n = len(self.stations)
        ends = {b.station for b in self.bearings} | {b.n_link for b in self.bearings if b.n_link is not None}
        return tuple(sorted(k for k in ends if k > n))

    @property
    def n_support_nodes(self) -> int:
        """How many support nodes (see :attr:`support_nodes`)."""
        return len(self.support_nodes)

    def io_ports(self, purpose: str) -> Ports:
        """The actuator and sensor; a :class:`ConfigError` naming ``purpose`` when the rig has none."""
        if self.ports is None:
            raise ConfigError(f"rig {self.rig_id}", "ports", f"{purpose} needs ports.actuator and ports.sensor; "
                              "this rig has none (a rig without ports serves modal analysis only)")
        return self.ports

    def _check_uncertainty_parameter(self, name: str) -> None:
        """The parametric structure's parameter exists (checked at load, not when the model is built)."""
        parts = name.split(".")
        known: dict[tuple[str, str], list[str]] = {
            ("masses", "mass"): [m.name for m in self.masses],
            ("lumped_springs", "stiffness"): [k.name for k in self.lumped_springs],
            ("bearings", "kxx"): [b.name for b in self.bearings if b.n_link is None],
            ("bearings", "kyy"): [b.name for b in self.bearings if b.n_link is None],
        }
        names = known.get((parts[0], parts[2])) if len(parts) == 3 else None
        if names is None:
            raise ValueError(f"uncertainty.parameter: {name!r} is not a supported rank-one parameter "
                             "(masses.<m>.mass, lumped_springs.<k>.stiffness, bearings.<b>.kxx|kyy)")
        if parts[1] not in names:
            raise ValueError(f"uncertainty.parameter: no {parts[0]} entry named {parts[1]!r} "
                             f"(known: {', '.join(names) or 'none'})")

    def notes(self) -> list[str]:
        """What the loader accepted but a user should know (inconsistent material constants; bearing speed
        tables that do not cover the analysed speeds, and how they are extended; more modes asked than
        the model has degrees of freedom: clamped)."""
        out = [n for k, m in self.materials.items() if (n := m.consistency_note(k)) is not None]
        out += [n for k, f in self.faults.items() if isinstance(f, Crack) and (n := f.note(k)) is not None]
        top = max(self.analysis.campbell_max_rpm, *self.analysis.speeds_rpm)
        for i, b in enumerate(self.bearings):
            tables = [t for t in (getattr(b, k) for k in BEARING_TERMS) if isinstance(t, SpeedTable)]
            if not tables:
                continue
            lo, hi = max(t.speed_rpm[0] for t in tables), min(t.speed_rpm[-1] for t in tables)  # all cover
            if lo > 0.0 or hi < top:
                how = ("held at their end values (extrapolate: hold)" if b.extrapolate == "hold" else
                       "extrapolated linearly from their end segments (extrapolate: linear)")
                out.append(f"bearings[{i}] ({b.name}): speed tables cover {lo:g}-{hi:g} rpm, the analysis "
                           f"0-{top:g} rpm; outside their speeds the coefficients are {how}")
        if "n_modes" in self.analysis.model_fields_set and self.analysis.n_modes > self.n_dof:
            out.append(f"analysis.n_modes: {self.analysis.n_modes} modes asked, but the model has {self.n_dof} degrees "
                       f"of freedom: at most {self.n_dof} modes are reported")
        return out

    @property
    def n_dof(self) -> int:
        """Degrees of freedom of the assembled model (rotor: 4 per mesh node plus 2 per support node)."""
        if self.kind == "lumped":
            return len(self.masses)
        per_span: dict[int, int] = {}
        for e in self.shaft:
            per_span.setdefault(e.start, e.refine)
        return 4 * (1 + sum(per_span.values())) + 2 * self.n_support_nodes

    # -- lumped checks -----------------------------------------------------------------------
    def _check_lumped(self) -> None:
        names = [m.name for m in self.masses]
        rotor_only = ["point_masses", "stations", "shaft", "discs", "bearings", "springs", "materials"]
        rotor_only += [k for k in ("shear_method", "shear_coefficient", "shear", "rotary_inertia", "gyroscopic",
                                   "tapered_element") if k in self.model_fields_set]
        for group in rotor_only:
            value = getattr(self, group)
            if value or (not isinstance(value, (list, dict)) and group in self.model_fields_set):
                raise ValueError(f"{group}: applies to kind: rotor only (a lumped model takes masses and "
                                 "lumped_springs); it would be ignored")
        if not names:
            raise ValueError("masses: a lumped model needs masses")
        if len(set(names)) != len(names):
            raise ValueError("masses: names must be unique")
        known = {*names, "ground"}
        for i, s in enumerate(self.lumped_springs):
            for end in s.between:
                if end not in known:
                    raise ValueError(f"lumped_springs[{i}].between: unknown mass {end!r}")
            if s.between[0] == s.between[1]:
                raise ValueError(f"lumped_springs[{i}].between: a spring needs two ends")
        for name in ("actuator", "sensor"):
            if self.ports is None:
                break
            p = getattr(self.ports, name)
            if p.mass not in names:
                raise ValueError(f"ports.{name}.mass: must name a mass ({', '.join(names)})")
        if self.damage is not None and self.damage.port.mass not in names:
            raise ValueError("damage.port.mass: must name a mass")
        springs = {s.name for s in self.lumped_springs}
        for key, f in self.faults.items():
            if isinstance(f, SpringChange) and f.spring not in springs:
                raise ValueError(f"faults.{key}.spring: unknown spring {f.spring!r}")
            if isinstance(f, Crack):
                raise ValueError(f"faults.{key}: a crack applies to rotor models only")

    # -- derived -----------------------------------------------------------------------------
    def sha256(self) -> str:
        """Hash of the validated content (insensitive to comments, layout and unit spelling)."""
        data = self.model_dump(mode="json", by_alias=True)
        if not data.get("variability"):  # absent and empty hash alike (hashes from before the section)
            data.pop("variability", None)
        if data.get("analysis", {}).get("n_points") is None:  # likewise the simulation grid's point count
            data.get("analysis", {}).pop("n_points", None)
        _prune_defaults(data, _LATER_KEYS)  # keys added later hash as if absent while at their defaults
        for fault in (data.get("faults") or {}).values():  # a crack's depth hashes as the older depth_ratio
            if isinstance(fault, dict) and "depth" in fault:
                depth = fault.pop("depth")
                if depth is not None:
                    fault["depth_ratio"] = 2.0 * depth
        doc = json.dumps(data, sort_keys=True)
        return hashlib.sha256(doc.encode()).hexdigest()


#: keys added after rig hashes were first recorded, with their defaults (issue 20), by section
_LATER_KEYS: dict[str, dict[str, Any]] = {
    "": {"point_masses": [], "shear_method": "hutchinson", "shear_coefficient": None, "shear": True,
         "rotary_inertia": True, "gyroscopic": True, "tapered_element": "exact", "ports": None},
    "shaft": {"outer_diameter_right": None, "inner_diameter_right": None, "axial_force": 0.0, "torque": 0.0,
              "shear_method": None, "shear_coefficient": None, "shear": None, "rotary_inertia": None,
              "gyroscopic": None},
    "discs": {"material": None, "width": None, "outer_diameter": None, "inner_diameter": None},
    "bearings": {"n_link": None, "mxx": 0.0, "myy": 0.0, "mxy": 0.0, "myx": 0.0, "extrapolate": "hold"},
    "damping": {"scope": "system"},
    "measurement": {"sideband_orders": []},
}


def _prune_defaults(data: dict[str, Any], later: dict[str, dict[str, Any]]) -> None:
    """Drop, in place, the keys of ``later`` that hold their default value."""
    for section, defaults in later.items():
        target = data if section == "" else data.get(section)
        items = target if isinstance(target, list) else [target] if isinstance(target, dict) else []
        for item in items:
            for key, default in defaults.items():
                if key in item and item[key] == default:
                    del item[key]

