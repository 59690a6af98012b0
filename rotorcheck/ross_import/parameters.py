"""ROSS's rotor ``[parameters]`` and its element damping as the rig's ``analysis`` and ``damping``.

The rotor speeds ``min_w``, ``rated_w``, ``max_w`` (rad/s) become ``analysis.speeds_rpm`` and
``campbell_max_rpm``. Rotor-level proportional damping (``parameters.alpha``, ``beta``: M and K of the
rotor without bearings, discs and point masses included) becomes ``damping: {kind: rayleigh, scope:
rotor}``; element damping (``ShaftElement`` ``alpha``, ``beta``, the same on every element) becomes
``scope: shaft_elements`` (discs and point masses undamped, as in ROSS)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rotorcheck.ross_import.shaft import Shaft
from rotorcheck.ross_import.tables import RAD_S_TO_RPM, Table, listing

#: the keys of ROSS's ``[parameters]`` table this import reads
PARAMETERS = frozenset({"min_w", "max_w", "rated_w", "alpha", "beta", "modal_damping_ratio",
                        "default_damping_ratio", "tag"})


@dataclass(frozen=True)
class RigParameters:
    """The rig's ``damping`` and ``analysis`` (empty: none) from ROSS's parameters, and what was left out."""

    damping: dict[str, Any]
    analysis: dict[str, Any]
    notes: list[str]


def rig_parameters(parameters: Table | None, shafts: Sequence[Shaft]) -> RigParameters:
    """The damping and analysis speeds of a rotor with ``parameters`` (None: the file has no such table)
    and ``shafts`` (their element damping)."""
    notes: list[str] = []
    damping: dict[str, Any] = {"kind": "none"}
    analysis: dict[str, Any] = {}
    global_ab = (0.0, 0.0)
    if parameters is not None:
        speeds = {}
        for key in ("min_w", "rated_w", "max_w"):
            if parameters.has(key):
                speeds[key] = parameters.number(key)
        picks = sorted({round(v * RAD_S_TO_RPM, 9) for v in speeds.values() if v >= 0})
        if picks:
            analysis["speeds_rpm"] = picks
        if speeds.get("max_w", 0.0) > 0:
            analysis["campbell_max_rpm"] = speeds["max_w"] * RAD_S_TO_RPM
        global_ab = (parameters.number("alpha", 0.0), parameters.number("beta", 0.0))
        if any(global_ab):
            if min(global_ab) >= 0:
                damping = {"kind": "rayleigh", "alpha": global_ab[0], "beta": global_ab[1], "scope": "rotor"}
            else:
                notes.append(f"parameters: alpha = {global_ab[0]:g}, beta = {global_ab[1]:g}: negative proportional "
                             "damping has no counterpart (rotorcheck's Rayleigh damping takes alpha, beta >= 0); "
                             "left out.")
        if parameters.has("modal_damping_ratio"):
            notes.append("parameters.modal_damping_ratio: ROSS builds its modal damping from every mode of its 6-DOF "
                         "model (axial and torsional modes included) at zero speed, not per lateral mode pair as "
                         "rotorcheck's damping: {kind: modal}; left out (give damping: {kind: modal, ratios: [...]} "
                         "by hand if wanted).")
        other = parameters.unknown(PARAMETERS)
        if other:
            notes.append(f"parameters: {', '.join(other)} not carried (not used by this import).")
    elemental = sorted({(s.alpha, s.beta) for s in shafts})
    damped = [s.table.path for s in shafts if s.alpha or s.beta]
    if damped:
        if any(global_ab):
            notes.append(f"{listing(damped)}: element proportional damping (alpha, beta) left out, as ROSS ignores it "
                         "when the rotor has global proportional damping.")
        elif len(elemental) == 1 and min(elemental[0]) >= 0:
            # the same alpha, beta on every element: sum of alpha M_e + beta K_e over the shaft elements
            damping = {"kind": "rayleigh", "alpha": elemental[0][0], "beta": elemental[0][1],
                       "scope": "shaft_elements"}
        else:
            values = listing([f"alpha = {a:g}, beta = {b:g}" for a, b in elemental], 3)
            notes.append(f"{listing(damped)}: element proportional damping ({values}) left out: rotorcheck's "
                         "Rayleigh damping of scope shaft_elements takes one alpha >= 0 and one beta >= 0 for every "
                         "shaft element.")
    return RigParameters(damping=damping, analysis=analysis, notes=notes)
