r"""Local flexibility of a transverse surface crack in a solid circular shaft, from its depth.

Strip method (strain energy release rate integrated over the crack front) of

- A. D. Dimarogonas, C. A. Papadopoulos, "Vibration of cracked shafts in bending",
  J. Sound Vib. 91(4) (1983) 583-593;
- C. A. Papadopoulos, A. D. Dimarogonas, "Coupled longitudinal and bending vibrations of a rotating
  shaft with an open crack", J. Sound Vib. 117(1) (1987) 81-93;

with the stress-intensity corrections of an edge-cracked strip (H. Tada, P. C. Paris, G. R. Irwin,
*The Stress Analysis of Cracks Handbook*; both better than 0.5 % for any depth/height):

    bending  F_b(s) = sqrt(tan(lam)/lam) (0.923 + 0.199 (1 - sin lam)^4) / cos lam,
    tension  F_t(s) = sqrt(tan(lam)/lam) (0.752 + 2.02 s + 0.37 (1 - sin lam)^3) / cos lam,
    lam = pi s / 2,  s = (crack depth in the strip) / (strip height);  F_b(0) = F_t(0) = 1.122.

Geometry. Shaft radius R, crack depth a from the surface, ``depth_ratio`` alpha = a/R (the
dissertation's alpha, eq. 5.25, and the config's ``depth_ratio``). Cross-section coordinates: x
along the straight crack edge, y towards the crack mouth (the rotating ``xi`` axis). The crack is
the circular segment y > R - a, of half-width b = sqrt(a (2R - a)). The strip at x has height
h(x) = 2 sqrt(R^2 - x^2) and crack depth s_max(x) = sqrt(R^2 - x^2) - (R - a).

- ``xi`` (the strong reduction): bending about the axis parallel to the crack edge, i.e. in the
  plane that opens the crack. Each strip is a strip in pure bending with outer-fibre stress
  sigma = M sqrt(R^2 - x^2) / I0: K_I = sigma sqrt(pi s) F_b(s/h).
- ``eta``: bending about the ``xi`` axis (perpendicular to the crack edge). The stress
  sigma = M x / I0 is uniform along each strip: K_I = sigma sqrt(pi s) F_t(s/h).

Compliance (Castigliano, plane strain): the crack's strain energy is U = (1 - nu^2)/E int_A K_I^2 dA,
so the added rotational compliance is c = d^2U/dM^2 = 2 (1 - nu^2)/E int_A (K_I/M)^2 dA (rad/(N m);
note the factor 2). Made dimensionless as c = cbar (1 - nu^2) / (E R^3):

    cbar_xi  = (32/pi) int_{-b}^{b} (1 - x^2) int_0^{s_max(x)} s F_b(s/h)^2 ds dx
    cbar_eta = (32/pi) int_{-b}^{b}    x^2    int_0^{s_max(x)} s F_t(s/h)^2 ds dx   (x, s in units of R)

evaluated by Gauss-Legendre quadrature (x = b sin(phi), s = s_max u; both integrands smooth).
``eta="open"`` (default) integrates over the whole crack: the linearisation of a crack held open
(the fully open state of eq. 5.13, 5.24-5.25, where the static moment keeps every strip in tension).
``eta="half_closed"`` keeps the tension half only (the perpendicular moment acting alone closes the
other half): exactly half of the open value. cbar_xi and the half-closed cbar_eta reproduce the
tabulated ``c55`` and ``c44`` distributed with ROSS (petrobras/ross,
``ross/faults/data/PAPADOPOULOS.csv``, indexed by depth/radius) to its 6 printed digits.

Normalisation onto eq. 5.25. A section of length l and stiffness E I0 in series with the crack
compliance c equals a section of second moment I0 - dI:
l/(E (I0 - dI)) = l/(E I0) + c, i.e. dI/I0 = x/(1 + x) with x = c E I0 / l = (R/l)(1 - nu^2) F and

    F = (pi/4) cbar     (F = c E I0 / ((1 - nu^2) R)).

At 40 % of the diameter (alpha = 0.8): F_xi = 3.121 (dissertation 3.0), F_eta = 1.300 open / 0.650
half-closed (dissertation 0.47); with R/l = 0.4, nu = 0.3: dI/I0 = 53.2 % (52.2 %) and 32.1 % /
19.1 % (14.6 %). The dissertation does not give the source of its F values (Mayes and Davies'
compliance function); the xi values agree to 4 %, the eta value is smaller than either convention.

Validity: 0 < alpha <= 1 (depth up to the radius, half the diameter). Deeper, the strips near the
crack ends are cut through (s/h -> 1, where F diverges) and the strip idealisation fails
(Papadopoulos, J. Sound Vib. 278 (2004) 1205-1211, restricts it to half the diameter as well).
Shallow limit: F_b, F_t -> 1.122, cbar_xi -> (256 sqrt 2/(15 pi)) 1.122^2 alpha^(5/2) (a^2 per unit
crack width, times a width growing as sqrt(a)), cbar_eta -> (512 sqrt 2/(105 pi)) 1.122^2 alpha^(7/2).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Literal

import numpy as np

from rotorcheck.config import Crack, RigConfig

__all__ = [
    "MAX_DEPTH_RATIO",
    "crack_compliances",
    "mayes_davies_compliances",
    "open_crack_modulus_factor",
    "rotational_compliances",
    "strip_compliances",
    "tada_bending",
    "tada_tension",
    "with_crack_depth",
]

#: Largest depth / radius of the strip relation (half the diameter).
MAX_DEPTH_RATIO = 1.0
#: Default Gauss-Legendre order per direction (converged to ~1e-12 relative, see the tests).
N_QUAD = 48

EtaConvention = Literal["open", "half_closed"]


def _lam(s: np.ndarray | float) -> np.ndarray:
    s = np.asarray(s, dtype=float)
    if np.any((s < 0) | (s >= 1)):
        raise ValueError("depth/height of a strip must be in [0, 1)")
    return 0.5 * np.pi * s


def _root_tan(lam: np.ndarray) -> np.ndarray:
    """sqrt(tan(lam)/lam), with its limit 1 at lam = 0."""
    safe = np.where(lam > 0, lam, 1.0)
    return np.where(lam > 1e-8, np.sqrt(np.tan(safe) / safe), 1.0)


def _tada_parts(s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What both of Tada's F share at ``s`` (depth / height): ``(s, sqrt(tan(lam)/lam), 1 - sin(lam),
    cos(lam))`` with ``lam = pi s / 2`` (the strip integral needs both F on one grid: computed once)."""
    lam = _lam(s)
    return np.asarray(s, dtype=float), _root_tan(lam), 1.0 - np.sin(lam), np.cos(lam)


def _tada_bending(parts: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    _, root, one_minus_sin, cos = parts
    return root * (0.923 + 0.199 * one_minus_sin ** 4) / cos


def _tada_tension(parts: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    s, root, one_minus_sin, cos = parts
    return root * (0.752 + 2.02 * s + 0.37 * one_minus_sin ** 3) / cos


def tada_bending(s: np.ndarray | float) -> np.ndarray:
    """Tada's F for an edge-cracked strip in pure bending; ``s`` = depth / height in [0, 1)."""
    return _tada_bending(_tada_parts(s))


def tada_tension(s: np.ndarray | float) -> np.ndarray:
    """Tada's F for an edge-cracked strip in tension; ``s`` = depth / height in [0, 1)."""
    return _tada_tension(_tada_parts(s))


@lru_cache(maxsize=16)
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(n)


def _check_depth(depth_ratio: float) -> float:
    a = float(depth_ratio)
    if not (0.0 < a <= MAX_DEPTH_RATIO):
        raise ValueError(
            f"depth_ratio {depth_ratio!r}: the strip relation needs 0 < depth/radius <= {MAX_DEPTH_RATIO} "
            f"(up to half the diameter)"
        )
    return a


@lru_cache(maxsize=256)
def _strip(depth_ratio: float, n: int) -> tuple[float, float]:
    a = depth_ratio
    b = np.sqrt(a * (2.0 - a))  # crack half-width / R
    t, w = _gauss(n)
    phi, wphi = 0.5 * np.pi * t, 0.5 * np.pi * w  # x = b sin(phi), phi in (-pi/2, pi/2)
    x = b * np.sin(phi)
    wx = wphi * b * np.cos(phi)
    root = np.sqrt(1.0 - x**2)
    h = 2.0 * root
    s_max = (b * np.cos(phi)) ** 2 / (root + 1.0 - a)  # = root - (1 - a), without cancellation
    u, wu = 0.5 * (t + 1.0), 0.5 * w
    s = s_max[:, None] * u[None, :]
    ws = s_max[:, None] * wu[None, :]
    parts = _tada_parts(s / h[:, None])
    inner_b = np.sum(ws * s * _tada_bending(parts) ** 2, axis=1)
    inner_t = np.sum(ws * s * _tada_tension(parts) ** 2, axis=1)
    c_xi = 32.0 / np.pi * float(np.sum(wx * (1.0 - x**2) * inner_b))
    c_eta = 32.0 / np.pi * float(np.sum(wx * x**2 * inner_t))
    return c_xi, c_eta


def strip_compliances(depth_ratio: float, n: int = N_QUAD, eta: EtaConvention = "open") -> tuple[float, float]:
    """Dimensionless crack compliances ``(cbar_xi, cbar_eta)``; ``c = cbar (1 - nu^2)/(E R^3)``.

    ``depth_ratio`` = depth / radius in (0, 1]; ``n`` Gauss points per direction; ``eta``: the
    convention of the perpendicular plane (module docstring).
    """
    a = _check_depth(depth_ratio)
    if n < 2:
        raise ValueError("n: at least 2 quadrature points")
    if eta not in ("open", "half_closed"):
        raise ValueError(f"eta: 'open' or 'half_closed', not {eta!r}")
    c_xi, c_eta = _strip(a, int(n))
    return c_xi, (c_eta if eta == "open" else 0.5 * c_eta)


def mayes_davies_compliances(depth_ratio: float, n: int = N_QUAD, eta: EtaConvention = "open") -> tuple[float, float]:
    """The dissertation's ``(F_xi, F_eta)`` of eq. 5.25 at ``depth_ratio`` = depth / radius: ``(pi/4) cbar``."""
    c_xi, c_eta = strip_compliances(depth_ratio, n, eta)
    return 0.25 * np.pi * c_xi, 0.25 * np.pi * c_eta


def rotational_compliances(
    depth_ratio: float, radius: float, youngs_modulus: float, poisson: float, eta: EtaConvention = "open"
) -> tuple[float, float]:
    """Added rotational compliances ``(c_xi, c_eta)`` in rad/(N m); radius in m, E in Pa."""
    c_xi, c_eta = strip_compliances(depth_ratio, eta=eta)
    scale = (1.0 - poisson**2) / (youngs_modulus * radius**3)
    return c_xi * scale, c_eta * scale


def crack_compliances(crack: Crack) -> tuple[float, float]:
    """``(F_xi, F_eta)`` of a ``mayes_davies``/``gasch`` config crack: as given, else from its depth."""
    if crack.compliance_xi is not None and crack.compliance_eta is not None:
        return float(crack.compliance_xi), float(crack.compliance_eta)
    alpha = crack.depth_over_radius
    if alpha is None:
        raise ValueError("the crack gives neither compliance_xi/compliance_eta nor a depth")
    f_xi, f_eta = mayes_davies_compliances(alpha)
    return float(f_xi), float(f_eta)


def open_crack_modulus_factor(depth_ratio: float, radius: float, length: float, poisson: float) -> float:
    """E factor of an element (length m, radius m) equivalent to the open crack at ``depth_ratio``.

    An isotropic element cannot carry the crack's two compliances, so it takes their mean
    ``F = (F_xi + F_eta)/2`` (the compliance averaged over the crack's orientation):
    ``l/(E' I0) = l/(E I0) + c`` gives ``E'/E = 1/(1 + x)``, ``x = (R/l)(1 - nu^2) F``.
    """
    f_xi, f_eta = mayes_davies_compliances(depth_ratio)
    x = radius / length * (1.0 - poisson**2) * 0.5 * (f_xi + f_eta)
    return 1.0 / (1.0 + x)


def with_crack_depth(config: RigConfig, fault: str, depth_fraction_of_diameter: float) -> RigConfig:
    """A copy of ``config`` with crack ``fault`` at ``depth_fraction_of_diameter`` (depth / diameter).

    ``mayes_davies``/``gasch``: ``depth = d`` (depth / diameter) replaces the crack's depth or
    compliances, which are then computed by :func:`mayes_davies_compliances`. ``open``:
    ``modulus_factor`` from :func:`open_crack_modulus_factor` with the crack's ``section_length``
    (else the element's length) and ``poisson`` (else the material's). ``jun`` is not a function of
    depth. Raises ValueError outside 0 < d < 1 and beyond the relation's validity (d <= 0.5).
    """
    d = float(depth_fraction_of_diameter)
    if not (0.0 < d < 1.0):
        raise ValueError(f"crack depth {depth_fraction_of_diameter!r}: must be a fraction of the diameter in (0, 1)")
    if d > 0.5 * MAX_DEPTH_RATIO:
        raise ValueError(
            f"crack depth {d:g} of the diameter: beyond the strip relation's validity "
            f"(up to {0.5 * MAX_DEPTH_RATIO:g} of the diameter)"
        )
    crack = config.faults.get(fault)
    if not isinstance(crack, Crack):
        cracks = sorted(k for k, f in config.faults.items() if isinstance(f, Crack))
        raise ValueError(f"fault {fault!r}: not a crack of this rig (cracks: {', '.join(cracks) or 'none'})")
    shaft = next(e for e in config.shaft if e.start == crack.element)
    if shaft.inner_diameter > 0:
        raise ValueError(f"fault {fault!r}: the strip relation needs a solid shaft (element {crack.element} is hollow)")
    data = crack.model_dump()
    if crack.model in ("mayes_davies", "gasch"):
        data.update(depth=d, depth_ratio=None, compliance_xi=None, compliance_eta=None)
    elif crack.model == "open":
        radius = 0.5 * shaft.outer_diameter
        length = crack.section_length
        if length is None:
            length = config.stations[crack.element] - config.stations[crack.element - 1]
        nu = crack.poisson if crack.poisson is not None else config.materials[shaft.material].nu
        data.update(modulus_factor=open_crack_modulus_factor(2.0 * d, radius, length, nu))
    else:
        raise ValueError(f"fault {fault!r}: the {crack.model} model is a stiffness series, not a function of depth")
    faults = dict(config.faults)
    faults[fault] = Crack.model_validate(data)
    return config.model_copy(update={"faults": faults})
