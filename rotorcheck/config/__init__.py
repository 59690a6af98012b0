"""The rig description (YAML), validated on load: one module per part of the schema.

Two model kinds share one config family: ``kind: rotor`` (a Timoshenko finite element rotor: stations, shaft
elements, discs, bearings) and ``kind: lumped`` (masses, springs and dampers; the three-mass example). Bare
numbers are SI; strings such as ``"16 mm"`` or ``"224.08 GPa"`` are converted (:mod:`rotorcheck.units`).
Unknown keys are rejected. Errors name the file and the field by path, e.g.
``configs/x.yaml: bearings[1].kxx: must be > 0``.

- :mod:`~rotorcheck.config.quantities`: quantity types; :mod:`~rotorcheck.config.base`: the strict base model,
  :class:`ConfigError`; :mod:`~rotorcheck.config.errors`: validation errors as field paths.
- :mod:`~rotorcheck.config.shaft`, :mod:`~rotorcheck.config.supports`, :mod:`~rotorcheck.config.damping`,
  :mod:`~rotorcheck.config.lumped`, :mod:`~rotorcheck.config.ports`, :mod:`~rotorcheck.config.faults`,
  :mod:`~rotorcheck.config.analysis`, :mod:`~rotorcheck.config.benign`: the sections.
- :mod:`~rotorcheck.config.rig`: :class:`RigConfig`.
- :mod:`~rotorcheck.config.resolve`: benign ranges resolved against the rig; :mod:`~rotorcheck.config.loading`:
  reading a file (bounded strict YAML), validation, resolution, JSON Schema.
"""

from rotorcheck.config.analysis import Analysis, Measurement
from rotorcheck.config.base import ConfigError, Strict
from rotorcheck.config.benign import (
    BENIGN_FORMS,
    BENIGN_KIND,
    BENIGN_PARAMETERS,
    BENIGN_PATH_ROOTS,
    BenignName,
    BenignRange,
)
from rotorcheck.config.damping import DampingModel, ModalDamping, NoDamping, RayleighDamping
from rotorcheck.config.errors import field_path, first_error
from rotorcheck.config.faults import Crack, Fault, Misalignment, SpringChange, UnbalanceMass
from rotorcheck.config.loading import MAX_RIG_BYTES, StrictLoader, json_schema, load_config, parse_config
from rotorcheck.config.lumped import LumpedMass, LumpedSpring
from rotorcheck.config.ports import DamagePort, Port, Ports, Uncertainty
from rotorcheck.config.quantities import (
    Angle,
    Damping,
    Density,
    Force,
    FrequencyHz,
    Inertia,
    Length,
    Mass,
    Moment,
    Pressure,
    Ratio,
    SpeedRpm,
    Stiffness,
    Unbalance,
)
from rotorcheck.config.resolve import Leaf, ResolvedBenign, leaf_text, resolve_benign
from rotorcheck.config.rig import RigConfig
from rotorcheck.config.shaft import Disc, Material, PointMass, ShaftElement, ShearMethod, TaperedSection
from rotorcheck.config.supports import BEARING_TERMS, Bearing, SpeedTable, StationSpring

__all__ = [
    "BEARING_TERMS",
    "BENIGN_FORMS",
    "BENIGN_KIND",
    "BENIGN_PARAMETERS",
    "BENIGN_PATH_ROOTS",
    "MAX_RIG_BYTES",
    "Analysis",
    "Angle",
    "Bearing",
    "BenignName",
    "BenignRange",
    "ConfigError",
    "Crack",
    "DamagePort",
    "Damping",
    "DampingModel",
    "Density",
    "Disc",
    "Fault",
    "Force",
    "FrequencyHz",
    "Inertia",
    "Leaf",
    "Length",
    "LumpedMass",
    "LumpedSpring",
    "Mass",
    "Material",
    "Measurement",
    "Misalignment",
    "ModalDamping",
    "Moment",
    "NoDamping",
    "PointMass",
    "Port",
    "Ports",
    "Pressure",
    "Ratio",
    "RayleighDamping",
    "ResolvedBenign",
    "RigConfig",
    "ShaftElement",
    "ShearMethod",
    "SpeedRpm",
    "SpeedTable",
    "SpringChange",
    "StationSpring",
    "Stiffness",
    "Strict",
    "StrictLoader",
    "TaperedSection",
    "Unbalance",
    "UnbalanceMass",
    "Uncertainty",
    "field_path",
    "first_error",
    "json_schema",
    "leaf_text",
    "load_config",
    "parse_config",
    "resolve_benign",
]
