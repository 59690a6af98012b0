"""Robust-control numerics: LFTs, the generalized-mu LMI, closed forms, noise bound, validation,
detection and identification. Pure numerics on complex arrays with a leading frequency axis."""

from rotorcheck.robust.identify import DamageSet, damage_dynamics, damage_set, damage_set_io
from rotorcheck.robust.mu import (
    Block,
    GammaResult,
    Structure,
    inject_solver_failure,
    required_gamma,
    required_gamma_bisection,
)
from rotorcheck.robust.noise import (
    NoiseBound,
    noise_bound_from_floor,
    noise_bound_from_periods,
    noise_bound_from_variance,
    noise_bound_manual,
)
from rotorcheck.robust.validation import (
    DetectionResult,
    ValidationResult,
    Verdict,
    detect,
    validate,
    verdict,
)

__all__ = [
    "Block",
    "DamageSet",
    "DetectionResult",
    "GammaResult",
    "NoiseBound",
    "Structure",
    "ValidationResult",
    "Verdict",
    "damage_dynamics",
    "damage_set",
    "damage_set_io",
    "detect",
    "inject_solver_failure",
    "noise_bound_from_floor",
    "noise_bound_from_periods",
    "noise_bound_from_variance",
    "noise_bound_manual",
    "required_gamma",
    "required_gamma_bisection",
    "validate",
    "verdict",
]
