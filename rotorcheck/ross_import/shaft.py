"""ROSS shaft elements: reading a ``ShaftElement`` table (diameters, flags, material), the shear
coefficient ROSS uses for ``shear_method_calc = "hutchinson"``, and the rig's materials and ``shaft``
entries (one per element; concentric layers of a span are several entries on one station pair)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from rotorcheck.ross_import.tables import COSMETIC, Table, listing, slug, unique_name

#: the keys of a ROSS ``ShaftElement`` table this import reads (others are reported as not carried)
SHAFT_KEYS = frozenset({
    "L", "idl", "odl", "idr", "odr", "n", "axial_force", "torque", "shear_effects", "rotary_inertia",
    "gyroscopic", "shear_method_calc", "alpha", "beta", "material",
}) | COSMETIC


def ross_hutchinson_coefficient(poisson: float, outer_diameter: float, inner_diameter: float) -> float:
    """The shear coefficient ROSS 2.3.0 uses for ``shear_method_calc="hutchinson"``.

    ``kappa = 6 (1 + r^2)^2 (1 + nu) / ((1 + r^2)^2 (7 + 12 nu + 4 nu^2) + 4 r^2 (5 + 6 nu + 2 nu^2))``
    with ``r = inner / outer`` (ROSS passes the mean diameters of a tapered element). Hutchinson's
    (2001) own formula has ``(1 + nu)^2``; ROSS's gives 0.712 for a solid section at nu = 0.3.

    Parameters
    ----------
    poisson : Poisson's ratio (ROSS: ``E / (2 G_s) - 1``).
    outer_diameter, inner_diameter : m (only their ratio matters).
    """
    from rotorcheck.fe.elements import shear_coefficient  # lazy: the FE package only for this coefficient

    return float(shear_coefficient(poisson, outer_diameter, inner_diameter)) / (1.0 + poisson)



@dataclass
class Shaft:
    """One ROSS shaft element as read (lengths and diameters in m, forces in N, torque in N m; ``order``
    is its place in the file, ``n`` its span number)."""

    table: Table
    order: int
    n: int
    L: float
    idl: float
    odl: float
    idr: float
    odr: float
    axial_force: float
    torque: float
    shear: bool
    rotary_inertia: bool
    gyroscopic: bool
    method: str
    alpha: float
    beta: float
    material: tuple[float, float, float]  # rho, E, G_s
    material_name: str

    @property
    def poisson(self) -> float:
        """ROSS's Poisson's ratio, E / (2 G_s) - 1."""
        return self.material[1] / (2.0 * self.material[2]) - 1.0



def read_shaft(table: Table, order: int) -> Shaft:
    """A ``ShaftElement`` table, checked (``order``: its place among the file's shaft elements, the span
    number when the table gives no ``n``)."""
    n = table.integer("n")
    L = table.number("L")
    if L <= 0:
        raise table.error("L", "must be > 0 (element length, m)")
    idl, odl = table.number("idl", 0.0), table.number("odl")
    idr, odr = table.number("idr", idl), table.number("odr", odl)
    for key, value in (("odl", odl), ("odr", odr)):
        if value <= 0:
            raise table.error(key, "must be > 0 (outer diameter, m)")
    for key, value, outer in (("idl", idl, odl), ("idr", idr, odr)):
        if value < 0:
            raise table.error(key, "must be >= 0 (inner diameter, m)")
        if value >= outer:
            raise table.error(key, f"must be < the outer diameter {outer:g} m")
    shear = table.flag("shear_effects", True)
    method = table.text("shear_method_calc", "cowper")
    if shear and method not in ("cowper", "hutchinson"):
        raise table.error("shear_method_calc", f"{method!r}: ROSS knows 'cowper' and 'hutchinson'")
    mat = table.table("material")
    rho = mat.number("rho")
    E = mat.number("E") if mat.has("E") else None
    G = mat.number("G_s") if mat.has("G_s") else None
    nu = mat.number("Poisson") if mat.has("Poisson") else None
    if E is not None and G is not None:
        pass
    elif E is not None and nu is not None:
        G = E / (2.0 * (1.0 + nu))
    elif G is not None and nu is not None:
        E = G * 2.0 * (1.0 + nu)
    else:
        raise mat.error("", "needs two of E, G_s and Poisson")
    assert E is not None and G is not None
    for key, value in (("rho", rho), ("E", E), ("G_s", G)):
        if value <= 0:
            raise mat.error(key if mat.has(key) else "", f"{key} must be > 0")
    return Shaft(
        table=table, order=order, n=order if n is None else n, L=L, idl=idl, odl=odl, idr=idr, odr=odr,
        axial_force=table.number("axial_force", 0.0), torque=table.number("torque", 0.0), shear=shear,
        rotary_inertia=table.flag("rotary_inertia", True), gyroscopic=table.flag("gyroscopic", True),
        method=method, alpha=table.number("alpha", 0.0), beta=table.number("beta", 0.0),
        material=(rho, E, G), material_name=mat.text("name", ""),
    )


@dataclass(frozen=True)
class RigShaft:
    """The rig's shaft from ROSS's shaft elements.

    Attributes
    ----------
    materials : the rig's ``materials`` (one per distinct ``(rho, E, G_s)``, SI units).
    entries : the rig's ``shaft`` entries, in the order of ``shafts``.
    shear, rotary_inertia : the rig-wide flags (the majority of the elements'); an element that differs
        says so in its entry.
    notes : what was approximated.
    """

    materials: dict[str, dict[str, float]]
    entries: list[dict[str, Any]]
    shear: bool
    rotary_inertia: bool
    notes: list[str]


def rig_shaft(shafts: list[Shaft], node_station: dict[int, int]) -> RigShaft:
    """The materials and shaft entries of ``shafts`` (sorted by span), each element from the station of its
    span's left node (``node_station``: ROSS node -> rig station)."""
    notes: list[str] = []
    # ---- materials
    mats: dict[tuple[float, float, float], list[str]] = {}
    for s in shafts:
        names = mats.setdefault(s.material, [])
        if s.material_name not in names:
            names.append(s.material_name)
    taken: set[str] = set()
    mat_name: dict[tuple[float, float, float], str] = {}
    materials: dict[str, dict[str, float]] = {}
    for props, names in mats.items():
        clean = sorted({n if re.fullmatch(r"[A-Za-z0-9_.-]+", n) else slug(n, "material") for n in names})
        name = unique_name("+".join(clean), taken)
        mat_name[props] = name
        materials[name] = {"density": props[0], "youngs_modulus": props[1], "shear_modulus": props[2]}

    # ---- shaft entries
    def majority(values: list[bool]) -> bool:
        return sum(values) * 2 >= len(values)

    rig_shear = majority([s.shear for s in shafts])
    rig_rotary = majority([s.rotary_inertia for s in shafts])
    shaft_entries: list[dict[str, Any]] = []
    hutchinson: list[str] = []
    for s in shafts:
        start = node_station[s.n]
        e: dict[str, Any] = {"start": start, "end": start + 1, "material": mat_name[s.material],
                             "outer_diameter": s.odl}
        if s.idl:
            e["inner_diameter"] = s.idl
        if s.odr != s.odl or s.idr != s.idl:
            e["outer_diameter_right"] = s.odr
            e["inner_diameter_right"] = s.idr
        if s.axial_force:
            e["axial_force"] = s.axial_force
        if s.torque:
            e["torque"] = s.torque
        if s.shear != rig_shear:
            e["shear"] = s.shear
        if s.shear and s.method == "hutchinson":
            mean_od, mean_id = 0.5 * (s.odl + s.odr), 0.5 * (s.idl + s.idr)
            e["shear_coefficient"] = ross_hutchinson_coefficient(s.poisson, mean_od, mean_id)
            hutchinson.append(s.table.path)
        if s.rotary_inertia != rig_rotary:
            e["rotary_inertia"] = s.rotary_inertia
        if not s.gyroscopic:
            e["gyroscopic"] = False
        shaft_entries.append(e)
    if hutchinson:
        notes.append(f"{listing(hutchinson)}: ROSS's shear_method_calc 'hutchinson' is not Hutchinson's (2001) "
                     "formula (it lacks a factor 1 + nu); written as the shear_coefficient ROSS actually uses, "
                     "6 (1+r^2)^2 (1+nu) / ((1+r^2)^2 (7+12nu+4nu^2) + 4 r^2 (5+6nu+2nu^2)) with r = mean inner / "
                     "mean outer diameter, not as rotorcheck's shear_method hutchinson.")
    return RigShaft(materials=materials, entries=shaft_entries, shear=rig_shear, rotary_inertia=rig_rotary,
                    notes=notes)
