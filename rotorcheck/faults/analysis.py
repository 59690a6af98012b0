"""Derived results for the cracked rotor: critical speeds, unbalance harmonics and orbits.

(The sweep simulator's hooks for the cracked rotor live in :mod:`rotorcheck.sim.plants`.)
SI units; frequencies in Hz and speeds in rpm at the interface.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from rotorcheck.config import Crack, UnbalanceMass
from rotorcheck.faults.crack import CrackStiffness, crack_stiffness
from rotorcheck.faults.harmonic_balance import cracked_disturbance_tones, fold_tones, solve_hb
from rotorcheck.fe.modal import critical_speeds, modes
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.lazy import lazy_module

if TYPE_CHECKING:
    import scipy.optimize as sopt
else:  # scipy.optimize costs ~0.1 s to import: loaded at first use
    sopt = lazy_module("scipy.optimize")

__all__ = [
    "averaged_system",
    "critical_speed_summary",
    "frozen_system",
    "hb_resonance_hz",
    "orbit_from_harmonics",
    "unbalance_harmonics",
    "unbalance_orbit",
]


def _ck(system: MechanicalSystem, crack: Crack | CrackStiffness, **kw: Any) -> CrackStiffness:
    return crack if isinstance(crack, CrackStiffness) else crack_stiffness(system, crack, **kw)


def _with_stiffness_change(system: MechanicalSystem, dk: np.ndarray) -> MechanicalSystem:
    """``system`` with ``K - dk`` at every speed (damping matrix unchanged)."""

    def mats(speed_rpm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        M, C, G, K = system.matrices(speed_rpm)
        return M, C, G, K - dk

    return replace(system, _matrices=mats)


def averaged_system(system: MechanicalSystem, crack: Crack | CrackStiffness) -> MechanicalSystem:
    """Time-invariant approximation ``K0 - <K_c>`` (revolution average of the breathing crack)."""
    ck = _ck(system, crack)
    return _with_stiffness_change(system, ck.scatter(ck.mean(), system.n_dof))


def frozen_system(system: MechanicalSystem, crack: Crack | CrackStiffness, rotation: float = 0.0) -> MechanicalSystem:
    """Non-rotating snapshot ``K0 - K_c(rotation)`` (e.g. the crack's opening angle at pi: open)."""
    ck = _ck(system, crack)
    return _with_stiffness_change(system, ck.scatter(ck.at_rotation(rotation)[0], system.n_dof))


def hb_resonance_hz(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    in_dof: int,
    out_dof: int,
    band_hz: tuple[float, float],
    n_harmonics: int = 8,
    n_grid: int = 201,
) -> float:
    """Frequency (Hz) of the largest k = 0 response |H(f)| in ``band_hz`` (grid, then refined)."""
    ck = None if crack is None else _ck(system, crack)
    grid = np.linspace(*band_hz, n_grid)

    def mag(f: float | np.ndarray) -> np.ndarray:
        res = solve_hb(system, ck, speed_rpm, f, in_dof, [out_dof], n_harmonics)
        return np.abs(res.fundamental[:, 0, 0])

    g = mag(grid)
    i = int(np.argmax(g))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    r = sopt.minimize_scalar(lambda f: -float(mag(f)[0]), bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
    return float(r.x)


def critical_speed_summary(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness,
    speed_rpm: float = 1000.0,
    max_rpm: float = 10000.0,
    in_dof: int | None = None,
    out_dof: int | None = None,
) -> dict[str, Any]:
    """First modes and first forward critical speed, healthy vs cracked.

    Cracked: the revolution-averaged stiffness (``averaged``) and the fully open crack frozen at
    rest (``open_at_rest``); with ``in_dof``/``out_dof`` also the k = 0 HB resonance of the LTP
    system near mode 1 at ``speed_rpm``. Frequencies in Hz, speeds in rpm.
    """
    ck = _ck(system, crack)
    avg = averaged_system(system, ck)
    opened = frozen_system(system, ck, np.pi - ck.theta0)
    out: dict[str, Any] = {}
    for name, sys_ in (("healthy", system), ("averaged", avg)):
        md = modes(sys_, speed_rpm, 4)
        rest = modes(sys_, 0.0, 2)
        crit = critical_speeds(sys_, max_rpm)
        out[name] = {
            "modes_at_speed_hz": [float(x) for x in md.frequency_hz],
            "whirl_at_speed": list(md.whirl),
            "mode1_at_rest_hz": float(rest.frequency_hz[0]),
            "first_critical_rpm": float(crit[0]) if crit else float("nan"),
            "first_critical_hz": float(crit[0]) / 60.0 if crit else float("nan"),
        }
    out["open_at_rest"] = {"modes_hz": [float(x) for x in modes(opened, 0.0, 4).frequency_hz]}
    if in_dof is not None and out_dof is not None:
        f1 = out["healthy"]["modes_at_speed_hz"][0]
        band = (0.85 * f1, 1.1 * f1)
        out["hb_resonance_hz"] = {
            "healthy": hb_resonance_hz(system, None, speed_rpm, in_dof, out_dof, band),
            "cracked": hb_resonance_hz(system, ck, speed_rpm, in_dof, out_dof, band),
        }
    return out


def unbalance_harmonics(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    unbalance: Sequence[UnbalanceMass],
    out_dofs: Sequence[int],
    n_harmonics: int = 10,
) -> tuple[np.ndarray, np.ndarray]:
    """Folded unbalance response: ``(orders n = 0, 1, 2, ... (q,), phasors (q, n_out))`` in m.

    ``y(t) = sum_n Re{X_n exp(j n Omega t)}`` (X_0 real: the DC offset).
    """
    ck = None if crack is None else _ck(system, crack)
    f, a = cracked_disturbance_tones(system, ck, speed_rpm, out_dofs, unbalance, None, n_harmonics)
    ff, aa = fold_tones(f, a)
    orders = np.rint(ff / (speed_rpm / 60.0)).astype(int)
    return orders, aa


def unbalance_orbit(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    unbalance: Sequence[UnbalanceMass],
    station: int,
    n_points: int = 361,
    n_harmonics: int = 10,
) -> tuple[np.ndarray, np.ndarray]:
    """Steady-state orbit at ``station`` over one revolution from harmonic balance.

    Returns ``(t (n_points,) s, xy (n_points, 2) m)``, t from 0 to one revolution.
    """
    outs = [system.dof(station, "x"), system.dof(station, "y")]
    orders, ph = unbalance_harmonics(system, crack, speed_rpm, unbalance, outs, n_harmonics)
    return orbit_from_harmonics(orders, ph, speed_rpm, n_points)


def orbit_from_harmonics(orders: np.ndarray, phasors: np.ndarray, speed_rpm: float, n_points: int = 361
                         ) -> tuple[np.ndarray, np.ndarray]:
    """``(t (n_points,) s, xy (n_points, 2) m)`` over one revolution from harmonic phasors (orders, (n, 2))
    as :func:`unbalance_harmonics` returns them."""
    om = speed_rpm * RPM_TO_RAD_S
    t = np.linspace(0.0, 2.0 * np.pi / om, n_points)
    return t, np.real(np.exp(1j * om * np.outer(t, orders)) @ phasors)
