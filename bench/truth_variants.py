"""Truth rigs the model does not share (issue 29): each a variant of ``configs/crack_rig_truth.yaml`` with
physics the nominal model (``configs/crack_rig.yaml``) leaves out in another way. Bench only: never used by
the detector. Every detection and location figure of the drift work is reported per variant.

- ``truth``: the bundled truth rig (modal damping, anisotropic supports, hub, laminated AMB rotor, coupling).
- ``dampers``: no modal damping; physical, non-proportional bearing dampers (300 N s/m at both bearings, the
  coupling's 5 N s/m) and light stiffness-proportional damping of the shaft elements (beta 2e-6 s).
- ``heavy_dampers``: as ``dampers`` with 3,000 N s/m at the bearings (an oil-film or squeeze-film bearing).
- ``fine_mesh``: every shaft segment in 3 elements and Cowper's shear coefficient (the model: 1 element per
  segment, Hutchinson's).
- ``pedestal``: the motor-end support as a bearing (4e7 N/m) on a 1.5 kg pedestal with its own stiffness
  (x 4.6e6, y 2.5e7 N/m) and damping (50 N s/m): a support mode, the static sideways stiffness as the truth's.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import yaml

from rotorcheck.config import RigConfig, load_config, parse_config
from rotorcheck.resources import configs_dir

TRUTH = configs_dir() / "crack_rig_truth.yaml"


def _raw() -> dict[str, Any]:
    return yaml.safe_load(TRUTH.read_text())


def _dampers(c_bearing: float) -> Callable[[dict[str, Any]], None]:
    def apply(d: dict[str, Any]) -> None:
        d["damping"] = {"kind": "rayleigh", "alpha": 0.0, "beta": 2e-6, "scope": "rotor"}
        for b in d["bearings"]:
            b["cxx"] = b["cyy"] = c_bearing
    return apply


def _fine_mesh(d: dict[str, Any]) -> None:
    for e in d["shaft"]:
        e["refine"] = 3
    d["shear_method"] = "cowper"


def _pedestal(d: dict[str, Any]) -> None:
    n = len(d["stations"])
    me = next(b for b in d["bearings"] if b["name"] == "me")
    me.update({"kxx": 4.0e7, "kyy": 4.0e7, "cxx": 30.0, "cyy": 30.0, "n_link": n + 1})
    d["bearings"].append({"name": "pedestal", "station": n + 1, "kxx": 4.6e6, "kyy": 2.5e7, "cxx": 50.0,
                          "cyy": 50.0})
    d.setdefault("point_masses", []).append({"name": "pedestal_mass", "station": n + 1, "mass": 1.5})


VARIANTS: dict[str, Callable[[dict[str, Any]], None] | None] = {
    "truth": None,
    "dampers": _dampers(300.0),
    "heavy_dampers": _dampers(3000.0),
    "fine_mesh": _fine_mesh,
    "pedestal": _pedestal,
}


def truth_variant(name: str, variability_from: RigConfig | None = None) -> RigConfig:
    """The truth variant ``name``; with ``variability_from``, that rig's benign ranges (to drift the truth
    inside the ranges the detector is told)."""
    d = copy.deepcopy(_raw())
    apply = VARIANTS[name]
    if apply is not None:
        apply(d)
    cfg = parse_config(d, f"{TRUTH} ({name})")
    if variability_from is not None:
        cfg = cfg.model_copy(update={"variability": variability_from.variability})
    return cfg


def nominal() -> RigConfig:
    """The model the detector uses."""
    return load_config(configs_dir() / "crack_rig.yaml")
