"""ROSS discs and point masses as the rig's ``discs`` and ``point_masses``: a disc's ``m``, ``Id``, ``Ip``
(kg, kg m^2) and a point mass's lateral ``mx``, ``my`` (kg) carry over as they are."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rotorcheck.ross_import.layout import Layout
from rotorcheck.ross_import.tables import COSMETIC, Table, slug, unique_name

#: the keys of a ROSS ``DiskElement`` table this import reads
DISK_KEYS = frozenset({"n", "m", "Id", "Ip"}) | COSMETIC
#: the keys of a ROSS ``PointMass`` table this import reads
POINT_MASS_KEYS = frozenset({"n", "m", "mx", "my", "mz"}) | COSMETIC


@dataclass(frozen=True)
class RigMasses:
    """The rig's discs and point masses.

    Attributes
    ----------
    discs, point_masses : the rig's entries (SI units), in file order.
    mz_tables : the point-mass tables with an axial mass (not carried: the model is lateral).
    notes : what was left out.
    """

    discs: list[dict[str, Any]]
    point_masses: list[dict[str, Any]]
    mz_tables: list[str]
    notes: list[str]


def rig_masses(
    discs: Sequence[tuple[Table, str, str]],
    point_masses: Sequence[tuple[Table, str]],
    layout: Layout,
    names_taken: set[str],
) -> RigMasses:
    """The entries of ``discs`` (``(table, class, tag)``) and ``point_masses`` (``(table, tag)``, at
    ``layout.point_mass_nodes``), named after their tags, unique within ``names_taken`` (which grows)."""
    notes: list[str] = []
    disc_entries: list[dict[str, Any]] = []
    for table, _cls, tag in discs:
        node = table.integer("n")
        if node is None:
            raise table.error("n", "required field is missing")
        station = layout.station_of(table, "n", node, shaft_only=True)
        m, Id, Ip = table.number("m"), table.number("Id", 0.0), table.number("Ip", 0.0)
        for key, value in (("Id", Id), ("Ip", Ip)):
            if value < 0:
                raise table.error(key, "must be >= 0 (kg m^2)")
        if m < 0:
            raise table.error("m", "must be >= 0 (kg)")
        if m == 0:
            if Id or Ip:
                notes.append(f"{table.path}: a disc without mass (m = 0) but with inertia; rotorcheck's discs need "
                             "a mass, so it is left out.")
            continue
        disc_entries.append({"name": unique_name(slug(tag, "disc"), names_taken), "station": station, "mass": m,
                             "polar_inertia": Ip, "transverse_inertia": Id})
    pm_entries: list[dict[str, Any]] = []
    mz_tables: list[str] = []
    for (table, tag), node in zip(point_masses, layout.point_mass_nodes):
        station = layout.station_of(table, "n", node)
        m_all = table.number("m") if table.has("m") else None
        mx = table.number("mx") if table.has("mx") else m_all
        my = table.number("my") if table.has("my") else m_all
        if mx is None or my is None:
            raise table.error("mx" if mx is None else "my", "required field is missing (or give m)")
        for key, value in (("mx", mx), ("my", my)):
            if value < 0:
                raise table.error(key if table.has(key) else "m", "must be >= 0 (kg)")
        mz = table.number("mz", 0.0) if table.has("mz") else (m_all or 0.0)
        if mz:
            mz_tables.append(table.path)
        pm_name = unique_name(slug(tag, "point_mass"), names_taken)
        if mx == 0 and my == 0:
            notes.append(f"{table.path}: a point mass of zero lateral mass; left out.")
            continue
        if mx == 0 or my == 0:
            raise table.error("mx" if mx == 0 else "my", "0 in one direction only: rotorcheck's point masses carry "
                              "mass in x and y")
        pm_entries.append({"name": pm_name, "station": station, "mass": mx} if mx == my else
                          {"name": pm_name, "station": station, "mx": mx, "my": my})
    return RigMasses(discs=disc_entries, point_masses=pm_entries, mz_tables=mz_tables, notes=notes)
