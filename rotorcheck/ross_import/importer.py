"""The ``import_ross`` entry point: a ROSS rotor file's element tables sorted by kind, each kind turned
into its part of the rig document (stations, shaft, discs and point masses, bearings, damping), the
document validated, and :class:`RossImport`, which writes it as a commented rig YAML file."""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rotorcheck.config import ConfigError, parse_config
from rotorcheck.errors import InputError
from rotorcheck.ross_import.bearings import AXIAL, BEARING_KEYS, PLAIN_BEARINGS, Bearing, read_bearing, rig_bearings
from rotorcheck.ross_import.layout import layout
from rotorcheck.ross_import.masses import DISK_KEYS, POINT_MASS_KEYS, rig_masses
from rotorcheck.ross_import.parameters import rig_parameters
from rotorcheck.ross_import.shaft import SHAFT_KEYS, Shaft, read_shaft, rig_shaft
from rotorcheck.ross_import.tables import Table, kind_of, listing, load_ross_toml, slug, toml_key

#: the ROSS version whose file format and interpolation this package follows
ROSS_FORMAT_VERSION = "2.3.0"


@dataclass(frozen=True)
class RossImport:
    """A ROSS rotor as a rotorcheck rig.

    Attributes
    ----------
    rig : the rig document (a mapping; :func:`rotorcheck.config.parse_config` validates it).
    not_carried : one sentence each: what was dropped or approximated, and why.
    source : the ROSS file read.
    ross_version : the ROSS version that saved it (``"unknown"`` when the file does not say).
    """

    rig: dict[str, Any]
    not_carried: tuple[str, ...]
    source: str = ""
    ross_version: str = "unknown"

    def to_yaml(self) -> str:
        """The rig file: YAML text, headed by comments naming the source, the ROSS version and
        every item of :attr:`not_carried`."""
        lines = [
            f"# Imported from the ROSS rotor {self.source or '(unnamed)'} (saved by ROSS {self.ross_version})",
            "# by rotorcheck import-ross. Bare numbers are SI; ROSS node k is station k + 1; bearing",
            "# coefficient tables are against rotor speed (rpm).",
        ]
        if self.not_carried:
            lines.append(f"# Not carried over or approximated ({len(self.not_carried)}):")
            for item in self.not_carried:
                wrapped = textwrap.wrap(item, width=100, break_long_words=False, break_on_hyphens=False)
                lines.extend(("# - " if i == 0 else "#   ") + w for i, w in enumerate(wrapped))
        else:
            lines.append("# Everything was carried over.")
        body = yaml.dump(self.rig, Dumper=_Dumper, sort_keys=False, default_flow_style=None, width=120,
                         allow_unicode=True)
        return "\n".join(lines) + "\n" + body


class _Dumper(yaml.SafeDumper):
    """Safe YAML without anchors and aliases (the speed lists of one bearing are one object)."""

    def ignore_aliases(self, data: Any) -> bool:
        return True



@dataclass(frozen=True)
class _Elements:
    """The tables of a ROSS file by kind, each in file order (``discs``: ``(table, class, tag)``,
    ``point_masses``: ``(table, tag)``, ``span_like``: ``(table path, n)`` of elements left out that occupy
    a shaft span), and notes on what was left out."""

    shafts: list[Shaft]
    discs: list[tuple[Table, str, str]]
    point_masses: list[tuple[Table, str]]
    bearings: list[Bearing]
    span_like: list[tuple[str, int]]
    parameters: Table | None
    notes: list[str]


def _read_elements(data: dict[str, Any], source: str) -> _Elements:
    """The element tables of the parsed ROSS file ``data``, read and checked; refuses a file without a
    shaft element."""
    notes: list[str] = []
    shafts: list[Shaft] = []
    discs: list[tuple[Table, str, str]] = []  # table, class, tag
    point_masses: list[tuple[Table, str]] = []
    bearings: list[Bearing] = []
    span_like: list[tuple[str, int]] = []  # unsupported elements that occupy a shaft span (couplings)
    parameters: Table | None = None
    for name, value in data.items():
        if name == "ross_version" or name.startswith("_"):
            continue
        if name == "parameters":
            if not isinstance(value, dict):
                raise InputError(source, "parameters", f"must be a table, not {kind_of(value)}")
            parameters = Table(source, "parameters", value)
            continue
        cls, sep, tag = name.partition("_")
        if sep and not isinstance(value, dict):
            raise InputError(source, toml_key(name), f"must be a table (a ROSS element \"<ElementClass>_<tag>\" is "
                             f"one), not {kind_of(value)}: this import does not drop it unread")
        if not isinstance(value, dict) or not sep:
            notes.append(f"{toml_key(name)}: not a ROSS element table (expected \"<ElementClass>_<tag>\"); ignored.")
            continue
        table = Table(source, toml_key(name), value)
        if cls == "ShaftElement":
            shafts.append(read_shaft(table, len(shafts)))
            extra = table.unknown(SHAFT_KEYS)
        elif cls == "DiskElement" or (table.has("Id") and table.has("Ip") and table.has("m") and table.has("n")):
            discs.append((table, cls, tag))
            extra = table.unknown(DISK_KEYS)
            if cls != "DiskElement":
                notes.append(f"{table.path}: a ROSS {cls}, carried as a rigid disc (m, Id, Ip) only"
                             + (f"; its {', '.join(extra)} are not" if extra else "") + ".")
                extra = []
        elif cls == "PointMass":
            point_masses.append((table, tag))
            extra = table.unknown(POINT_MASS_KEYS)
        elif cls in PLAIN_BEARINGS or table.has("kxx"):
            bearings.append(read_bearing(table, cls, tag))
            extra = table.unknown(BEARING_KEYS)
            if cls not in PLAIN_BEARINGS:
                notes.append(f"{table.path}: a ROSS {cls}, carried as the linear coefficients saved with it (what "
                             "ROSS's modal and frequency response analyses use)"
                             + (f"; its own parameters ({', '.join(extra)}) and model are not" if extra else "") + ".")
                extra = []
        else:
            n_span = table.integer("n") if table.has("n") and table.has("L") else None
            if n_span is not None:
                span_like.append((table.path, n_span))
            notes.append(f"{table.path}: ROSS element class {cls} has no counterpart in a rotorcheck rig; left out.")
            continue
        if extra:
            notes.append(f"{table.path}: field{'s' if len(extra) > 1 else ''} {', '.join(extra)} not carried "
                         "(not used by this import).")
    if not shafts:
        raise InputError(source, "ShaftElement_*",
                         "no shaft element table: this is no rotor saved by ROSS (Rotor.save)")
    return _Elements(shafts, discs, point_masses, bearings, span_like, parameters, notes)


def _lateral_only_note(bearings: list[Bearing], mz_tables: list[str]) -> str:
    """The note that axial and torsional terms are not carried, naming the nonzero ones."""
    axial_terms = []
    for b in bearings:
        nonzero = [k for k in AXIAL if bool(np.any(b.raw[k] != 0))]
        if nonzero:
            axial_terms.append(f"{'/'.join(nonzero)} of {b.table.path}")
    if mz_tables:
        axial_terms.append(f"mz of {listing(mz_tables, 2)}")
    sentence = ("ROSS's model has 6 degrees of freedom per node, rotorcheck's is lateral only (x, y and the two "
                "tilts): the axial and torsional degrees of freedom and terms are not carried (kzz, czz, mzz of "
                "bearings and seals, mz of point masses, the axial and torsional part of shaft elements and discs)")
    if axial_terms:
        sentence += "; nonzero here: " + listing(axial_terms, 3)
    return sentence + "."


def import_ross(path: str | Path, rig_id: str | None = None, speed_points: int = 65) -> RossImport:
    """Read a rotor saved by ROSS (``Rotor.save``, TOML) as a rotorcheck rig.

    Parameters
    ----------
    path : the ROSS TOML file.
    rig_id : the rig's ``rig_id`` (default: from the file name).
    speed_points : evenly spaced speeds at which a speed-dependent bearing coefficient is sampled
        (besides the speeds saved with it); at least 2.

    Returns
    -------
    RossImport
        The rig document (validated) and what could not be carried over.

    Raises
    ------
    InputError
        Unreadable file, not TOML, not a ROSS rotor, a field of the wrong type or value; the field
        names the TOML table and key, e.g. ``"ShaftElement_Shaft Element 3".odl``.
    """
    if isinstance(speed_points, bool) or not isinstance(speed_points, int) or speed_points < 2:
        raise InputError(None, "speed_points", f"must be an integer >= 2, not {speed_points!r}")
    p = Path(path)
    source = str(path)
    data = load_ross_toml(p)
    version = data.get("ross_version", "unknown")
    if not isinstance(version, str):
        raise InputError(source, "ross_version", f"must be a string, not {kind_of(version)}")

    elements = _read_elements(data, source)
    notes = list(elements.notes)
    parameters = elements.parameters
    shafts = sorted(elements.shafts, key=lambda s: (s.n, s.order))  # ROSS sorts by n, stably (file order in a span)
    bearing_nodes = [k for b in elements.bearings for k in (b.n, b.n_link) if k is not None]
    lay = layout(source, shafts, elements.span_like, bearing_nodes, elements.point_masses)
    notes.extend(lay.notes)
    shaft = rig_shaft(shafts, lay.node_station)
    notes.extend(shaft.notes)
    names_taken: set[str] = set()  # disc, point mass and bearing names
    masses = rig_masses(elements.discs, elements.point_masses, lay, names_taken)
    notes.extend(masses.notes)
    bearing_entries, bearing_notes = rig_bearings(elements.bearings, lay, names_taken, speed_points)
    notes.extend(bearing_notes)
    params = rig_parameters(parameters, shafts)
    notes.extend(params.notes)
    notes.append(_lateral_only_note(elements.bearings, masses.mz_tables))
    if version != ROSS_FORMAT_VERSION:
        notes.append(f"The file says ROSS {version}; this import follows the file format and bearing interpolation "
                     f"of ROSS {ROSS_FORMAT_VERSION}, which may differ.")

    n_spans = lay.n_spans
    n_layers = len(shafts) - n_spans
    desc = (f"Imported from the ROSS rotor {p.name} (ROSS {version}): {n_spans} shaft spans"
            + (f" ({n_layers} further concentric layers)" if n_layers else "")
            + f", {len(masses.discs)} disc(s), {len(bearing_entries)} bearing/seal entries"
            + (f", {len(masses.point_masses)} point mass(es)" if masses.point_masses else "") + ".")
    if parameters is not None and parameters.has("tag"):
        desc += f" ROSS rotor tag: {parameters.text('tag', '')}."
    rig: dict[str, Any] = {
        "schema": "rotorcheck.rig",
        "version": 1,
        "rig_id": rig_id if rig_id is not None else slug(p.stem, "ross_rotor"),
        "kind": "rotor",
        "description": desc,
        "shear_method": "cowper",
    }
    if any("outer_diameter_right" in e or "inner_diameter_right" in e for e in shaft.entries):
        rig["tapered_element"] = "greenhill"  # ROSS's tapered element (one mid-section shear parameter)
        notes.append("tapered elements use ROSS's formulation (tapered_element: greenhill, Greenhill et al. 1985) "
                     "so the frequencies reproduce ROSS's; rotorcheck's default (exact) is the exact static "
                     "stiffness of the tapered beam, whose modes converge faster under refinement from 8 elements "
                     "per taper on (at 4 elements only its first mode is closer).")
    if not shaft.shear:
        rig["shear"] = False
        if not any(e.get("shear") for e in shaft.entries):
            del rig["shear_method"]  # no element has shear: the method would be unused (refused)
    if not shaft.rotary_inertia:
        rig["rotary_inertia"] = False
    rig["materials"] = shaft.materials
    rig["stations"] = lay.stations
    rig["shaft"] = shaft.entries
    if masses.discs:
        rig["discs"] = masses.discs
    if masses.point_masses:
        rig["point_masses"] = masses.point_masses
    if bearing_entries:
        rig["bearings"] = bearing_entries
    rig["damping"] = params.damping
    if params.analysis:
        rig["analysis"] = params.analysis
    try:
        parse_config(rig, source)
    except ConfigError as exc:
        raise InputError(source, "", f"cannot be expressed as a rotorcheck rig: {exc.field}: {exc.message}") from None
    return RossImport(rig=rig, not_carried=tuple(notes), source=source, ross_version=version)
