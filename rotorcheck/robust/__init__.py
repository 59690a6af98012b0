"""Robust-control numerics: LFTs, the generalized-mu LMI, closed forms, noise bound, validation,
detection and identification. Pure numerics on complex arrays with a leading frequency axis.

The names below are loaded on first use (PEP 562), so that importing one submodule (e.g. the
measured detection) does not load the LMI machinery and its solvers.
"""

from __future__ import annotations

from rotorcheck.lazy import lazy_exports

_HOME = {
    "DamageSet": "identify", "damage_dynamics": "identify", "damage_set": "identify", "damage_set_io": "identify",
    "Block": "mu", "GammaResult": "mu", "Structure": "mu", "inject_solver_failure": "mu",
    "required_gamma": "mu", "required_gamma_bisection": "mu",
    "NoiseBound": "noise", "noise_bound_from_floor": "noise", "noise_bound_from_periods": "noise",
    "noise_bound_from_variance": "noise", "noise_bound_manual": "noise",
    "DetectionResult": "validation", "ValidationResult": "validation", "Verdict": "validation",
    "detect": "validation", "validate": "validation", "verdict": "validation",
}

__all__, __getattr__, __dir__ = lazy_exports(__name__, _HOME)
