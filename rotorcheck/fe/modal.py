"""Modal analysis at speed: damped natural frequencies, damping ratios, whirl, Campbell, criticals.

State space ``x = [q; q']``, ``A = [[0, I], [-M^-1 K, -M^-1 (C + Omega G)]]``; each eigenvalue
``lambda`` with ``Im(lambda) > 0`` is a mode: damped natural frequency ``Im(lambda) / 2 pi`` (Hz),
natural frequency ``|lambda| / 2 pi``, damping ratio ``-Re(lambda) / |lambda|``.

Whirl convention (spin positive from +x towards +y, i.e. about +z): with the phasor convention
``x(t) = Re(U e^{j w t})``, ``y(t) = Re(V e^{j w t})`` the orbit's mean angular momentum is
``w Im(U conj(V))``. The whirl ratio of a mode is
``r = 2 sum Im(U conj(V)) / sum(|U|^2 + |V|^2)`` over the translational DOF of all nodes: ``r = +1``
circular forward, ``-1`` circular backward, 0 planar. ``forward`` if ``r > 1e-3``, ``backward`` if
``r < -1e-3``, else ``planar``. (Equivalently forward iff ``Im(conj(U) V) < 0``.)

Degenerate pairs (an axisymmetric rotor at rest, or a mode without gyroscopic participation) have
an arbitrary basis; it is rotated to the circular forward/backward pair, so that whirl labels and
Campbell tracking are deterministic.

Campbell tracking follows eigenvectors from speed to speed (MAC between consecutive speeds, optimal
assignment), not frequency order, so crossing branches keep their identity.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq, linear_sum_assignment

from rotorcheck.config import RigConfig
from rotorcheck.fe.damping import undamped_modes
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem

TWO_PI = 2.0 * np.pi
PLANAR_TOL = 1e-3
_DEGENERATE_TOL = 1e-7


@dataclass(frozen=True)
class Modes:
    """Modes of a system at one speed, sorted by damped natural frequency (Hz at the interface)."""

    speed_rpm: float
    eigenvalues: np.ndarray  # (m,) complex, rad/s, Im > 0
    shapes: np.ndarray  # (n_dof, m) complex displacement shapes, max |translation| = 1 (real)
    whirl_ratio: np.ndarray  # (m,) in [-1, 1]; nan for lumped models

    @property
    def frequency_hz(self) -> np.ndarray:
        """Damped natural frequencies Im(lambda) / 2 pi (Hz)."""
        return self.eigenvalues.imag / TWO_PI

    @property
    def natural_frequency_hz(self) -> np.ndarray:
        """Undamped-equivalent natural frequencies |lambda| / 2 pi (Hz)."""
        return np.abs(self.eigenvalues) / TWO_PI

    @property
    def damping_ratio(self) -> np.ndarray:
        """-Re(lambda) / |lambda|."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)

    @property
    def whirl(self) -> tuple[str, ...]:
        """'forward' | 'backward' | 'planar' per mode ('none' for lumped models)."""
        return tuple(whirl_label(r) for r in self.whirl_ratio)

    def __len__(self) -> int:
        return self.eigenvalues.size


def whirl_label(ratio: float) -> str:
    """Label of a whirl ratio (see module docstring)."""
    if not np.isfinite(ratio):
        return "none"
    if ratio > PLANAR_TOL:
        return "forward"
    if ratio < -PLANAR_TOL:
        return "backward"
    return "planar"


def whirl_ratio(shapes: np.ndarray) -> np.ndarray:
    """Whirl ratio of rotor displacement shapes (n_dof, m) from the translational DOF (u, v).

    Falls back to the slopes (psi, -theta) for a mode without translation.
    """
    U, V = shapes[0::4], shapes[1::4]
    den = np.sum(np.abs(U) ** 2 + np.abs(V) ** 2, axis=0)
    num = 2.0 * np.sum(np.imag(U * np.conj(V)), axis=0)
    Px, Py = shapes[3::4], -shapes[2::4]
    den_r = np.sum(np.abs(Px) ** 2 + np.abs(Py) ** 2, axis=0)
    num_r = 2.0 * np.sum(np.imag(Px * np.conj(Py)), axis=0)
    use_rot = den <= 1e-20 * np.maximum(den_r, 1e-300)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(use_rot, num_r / den_r, num / den)


def _whirl_components(shapes: np.ndarray, lc: float) -> tuple[np.ndarray, np.ndarray]:
    """Forward and backward circular components of rotor shapes (translations, lc * slopes)."""
    U, V = shapes[0::4], shapes[1::4]
    Px, Py = lc * shapes[3::4], -lc * shapes[2::4]
    fwd = np.concatenate([U + 1j * V, Px + 1j * Py]) / 2.0
    bwd = np.concatenate([U - 1j * V, Px - 1j * Py]) / 2.0
    return fwd, bwd


def _circularize(lam: np.ndarray, vec: np.ndarray, lc: float) -> np.ndarray:
    """Rotate bases of degenerate eigenvalue pairs to (backward, forward) circular modes."""
    vec = vec.copy()
    i = 0
    while i < lam.size - 1:
        if abs(lam[i + 1] - lam[i]) <= _DEGENERATE_TOL * abs(lam[i]):
            Q = vec[:, [i, i + 1]]
            n = Q.shape[0] // 2
            fwd, bwd = _whirl_components(Q[:n], lc)
            # forward mode: combination with no backward component, and vice versa
            cf = np.linalg.svd(bwd)[2][-1].conj()
            cb = np.linalg.svd(fwd)[2][-1].conj()
            vec[:, i], vec[:, i + 1] = Q @ cb, Q @ cf
            i += 2
        else:
            i += 1
    return vec


def _normalise(shapes: np.ndarray, kind: str) -> np.ndarray:
    """Scale each shape so its largest translational component is 1 (real)."""
    trans = shapes[0::4] if kind == "rotor" else shapes
    idx = np.argmax(np.abs(trans), axis=0)
    ref = trans[idx, np.arange(shapes.shape[1])]
    ref = np.where(np.abs(ref) > 0, ref, 1.0)
    return shapes / ref[None, :]


def state_matrix(system: MechanicalSystem, speed_rpm: float = 0.0) -> np.ndarray:
    """First-order system matrix A (2n, 2n) at ``speed_rpm`` (x = [q, q'])."""
    M, C, G, K = system.matrices(speed_rpm)
    n = system.n_dof
    D = C + speed_rpm * RPM_TO_RAD_S * G
    MiKD = np.linalg.solve(M, np.hstack([K, D]))
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -MiKD[:, :n]
    A[n:, n:] = -MiKD[:, n:]
    return A


def _characteristic_length(system: MechanicalSystem) -> float:
    pos = np.asarray(system.node_positions)
    return float(pos.max() - pos.min()) / 4.0 if pos.size > 1 else 1.0


def modes(system: MechanicalSystem, speed_rpm: float = 0.0, n_modes: int | None = None) -> Modes:
    """Modes at ``speed_rpm`` (oscillatory ones, Im(lambda) > 0), lowest ``n_modes`` if given."""
    A = state_matrix(system, speed_rpm)
    lam, vec = sla.eig(A)
    scale = max(np.abs(lam).max(), 1.0)
    keep = lam.imag > 1e-9 * scale
    lam, vec = lam[keep], vec[:, keep]
    order = np.argsort(lam.imag, kind="stable")
    lam, vec = lam[order], vec[:, order]
    n = system.n_dof
    if system.kind == "rotor":
        vec = _circularize(lam, vec, _characteristic_length(system))
    shapes = _normalise(vec[:n], system.kind)
    if system.kind == "rotor":
        ratio = whirl_ratio(shapes)
    else:
        ratio = np.full(lam.size, np.nan)
    if n_modes is not None:
        lam, shapes, ratio = lam[:n_modes], shapes[:, :n_modes], ratio[:n_modes]
    return Modes(float(speed_rpm), lam, shapes, ratio)


def natural_frequencies_at_rest(system: MechanicalSystem) -> np.ndarray:
    """Undamped natural frequencies (Hz) of (K, M) at 0 rpm, ascending (every DOF)."""
    M, _, _, K = system.matrices(0.0)
    w, _ = undamped_modes(M, K)
    return w / TWO_PI


def mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion between columns of a (n, p) and b (n, q): (p, q) in [0, 1]."""
    num = np.abs(a.conj().T @ b) ** 2
    den = np.real(np.sum(a.conj() * a, axis=0))[:, None] * np.real(np.sum(b.conj() * b, axis=0))
    return num / den


# --------------------------------------------------------------------------------------------
# Campbell diagram


@dataclass(frozen=True)
class CampbellResult:
    """Tracked branches over speed. Arrays (s, m): speed index, branch index (Hz, -, -)."""

    speeds_rpm: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    whirl_ratio: np.ndarray
    min_mac: np.ndarray  # (m,) smallest MAC between consecutive speeds along each branch
    critical_speeds_rpm: tuple[float, ...] = ()
    critical_branch: tuple[int, ...] = ()
    order: int = 1

    @property
    def whirl(self) -> np.ndarray:
        """Labels (s, m)."""
        return np.vectorize(whirl_label, otypes=[object])(self.whirl_ratio)

    @property
    def branch_whirl(self) -> tuple[str, ...]:
        """One label per branch: the label at the highest speed (where splitting is largest)."""
        return tuple(whirl_label(r) for r in self.whirl_ratio[-1])


def _track(
    system: MechanicalSystem, speeds: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    """Track every oscillatory mode over ``speeds`` by MAC with the previous speed's shapes and an
    optimal assignment (ties broken by frequency proximity).

    Returns (lam (s, p), whirl ratio (s, p), min MAC per branch (p,), shapes per speed [(n, p)]).
    """
    first = modes(system, speeds[0])
    p = len(first)
    lam = np.full((speeds.size, p), np.nan + 0j)
    ratio = np.full((speeds.size, p), np.nan)
    lam[0], ratio[0] = first.eigenvalues, first.whirl_ratio
    ref = first.shapes.copy()
    refs = [ref.copy()]
    minmac = np.ones(p)
    for k in range(1, speeds.size):
        cur = modes(system, speeds[k])
        m = mac(ref, cur.shapes)
        f_prev = np.abs(lam[k - 1].imag)[:, None]
        df = np.abs(f_prev - cur.eigenvalues.imag[None, :]) / np.maximum(f_prev, 1e-12)
        cost = (1.0 - m) + 1e-3 * np.nan_to_num(df, nan=1.0)
        rows, cols = linear_sum_assignment(cost)
        lam[k, rows] = cur.eigenvalues[cols]
        ratio[k, rows] = cur.whirl_ratio[cols]
        minmac[rows] = np.minimum(minmac[rows], m[rows, cols])
        ref[:, rows] = cur.shapes[:, cols]
        refs.append(ref.copy())
    return lam, ratio, minmac, refs


def _branch_order(lam: np.ndarray) -> np.ndarray:
    """Branches by frequency at the first speed; (near-)degenerate ones by frequency at the last
    speed, so that a pair split by speed lists backward before forward."""
    w0, w1 = lam[0].imag, np.nan_to_num(lam[-1].imag, nan=np.inf)
    order = list(np.argsort(w0, kind="stable"))
    i = 0
    while i < len(order):
        j = i + 1
        while j < len(order) and w0[order[j]] - w0[order[i]] <= _DEGENERATE_TOL * abs(w0[order[i]]):
            j += 1
        order[i:j] = sorted(order[i:j], key=lambda b: w1[b])
        i = j
    return np.asarray(order, dtype=int)


def campbell(
    system: MechanicalSystem,
    speeds_rpm: Sequence[float] | np.ndarray,
    n_modes: int = 6,
    order: int = 1,
    criticals: bool = True,
) -> CampbellResult:
    """Campbell diagram: the lowest ``n_modes`` branches (at the first speed) tracked over speed.

    With ``criticals``, forward branches crossing ``order`` x running speed are root-found.
    """
    speeds = np.asarray(speeds_rpm, dtype=float)
    lam, ratio, minmac, refs = _track(system, speeds)
    sel = _branch_order(lam)[: min(n_modes, lam.shape[1])]
    f = lam.imag / TWO_PI
    zeta = -lam.real / np.abs(lam)
    crit: list[tuple[float, int]] = []
    if criticals and system.kind == "rotor":
        for j, b in enumerate(sel):
            for rpm in _branch_crossings(system, speeds, f[:, b], ratio[:, b], refs, b, order):
                crit.append((rpm, j))
    crit.sort()
    return CampbellResult(
        speeds_rpm=speeds,
        frequency_hz=f[:, sel],
        damping_ratio=zeta[:, sel],
        whirl_ratio=ratio[:, sel],
        min_mac=minmac[sel],
        critical_speeds_rpm=tuple(c[0] for c in crit),
        critical_branch=tuple(c[1] for c in crit),
        order=order,
    )


def _branch_crossings(
    system: MechanicalSystem,
    speeds: np.ndarray,
    f: np.ndarray,
    ratio: np.ndarray,
    refs: list[np.ndarray],
    b: int,
    order: int,
) -> list[float]:
    """Root-found speeds (rpm) where forward branch ``b`` crosses ``order`` x running speed."""
    g = f - order * speeds / 60.0
    out = []
    for k in np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]:
        if not (ratio[k] > PLANAR_TOL or ratio[k + 1] > PLANAR_TOL):
            continue
        if g[k] == 0.0:
            out.append(float(speeds[k]))
            continue
        ref = refs[k][:, b : b + 1]

        def h(rpm: float, ref: np.ndarray = ref) -> float:
            md = modes(system, rpm)
            j = int(np.argmax(mac(ref, md.shapes)[0]))
            return float(md.frequency_hz[j] - order * rpm / 60.0)

        out.append(float(brentq(h, speeds[k], speeds[k + 1], xtol=1e-6, rtol=1e-12)))
    return out


def critical_speeds(
    system: MechanicalSystem, max_rpm: float, order: int = 1, n_grid: int = 41
) -> list[float]:
    """Forward critical speeds (rpm) up to ``max_rpm``: forward branches crossing order x speed.

    Branches are tracked on a grid of ``n_grid`` speeds; every sign change of
    ``f(rpm) - order rpm / 60`` on a forward branch is root-found with Brent's method.
    """
    if system.kind != "rotor":
        return []
    speeds = np.linspace(0.0, float(max_rpm), n_grid)
    camp = campbell(system, speeds, n_modes=system.n_dof, order=order)
    return sorted(camp.critical_speeds_rpm)


# --------------------------------------------------------------------------------------------
# summary for the CLI


def model_summary(
    config: RigConfig, speed_rpm: float = 0.0, system: MechanicalSystem | None = None
) -> dict[str, Any]:
    """The ``rotorcheck model`` JSON document (cli.md): modes, whirl, critical speeds, shapes.

    Keys: ``speed_rpm``, ``modes`` (list of ``frequency_hz`` (damped), ``natural_frequency_hz``,
    ``damping_ratio``, ``whirl``, ``whirl_ratio``), ``critical_speeds_rpm`` (forward, 1X, up to
    ``analysis.campbell_max_rpm``), ``undamped_frequencies_at_rest_hz``, ``mode_shapes`` (per
    station, x and y, real and imaginary parts).
    """
    from rotorcheck.fe.assembly import build_system

    sys_ = system if system is not None else build_system(config)
    n = config.analysis.n_modes
    md = modes(sys_, speed_rpm, n_modes=n)
    rest = natural_frequencies_at_rest(sys_)[:n]
    entries = [
        {
            "frequency_hz": float(md.frequency_hz[i]),
            "natural_frequency_hz": float(md.natural_frequency_hz[i]),
            "damping_ratio": float(md.damping_ratio[i]),
            "whirl": md.whirl[i],
            "whirl_ratio": None if not np.isfinite(md.whirl_ratio[i]) else float(md.whirl_ratio[i]),
        }
        for i in range(len(md))
    ]
    out: dict[str, Any] = {
        "rig_id": config.rig_id,
        "speed_rpm": float(speed_rpm),
        "modes": entries,
        "critical_speeds_rpm": [],
        "undamped_frequencies_at_rest_hz": [float(x) for x in rest],
    }
    if sys_.kind == "rotor":
        out["critical_speeds_rpm"] = critical_speeds(sys_, config.analysis.campbell_max_rpm)
        dofs = 4 * np.asarray(sys_.station_node)
        out["mode_shapes"] = {
            "station_positions_m": [float(z) for z in sys_.station_positions],
            "modes": [
                {
                    "x_re": md.shapes[dofs, i].real.tolist(),
                    "x_im": md.shapes[dofs, i].imag.tolist(),
                    "y_re": md.shapes[dofs + 1, i].real.tolist(),
                    "y_im": md.shapes[dofs + 1, i].imag.tolist(),
                }
                for i in range(len(md))
            ],
        }
    else:
        out["mode_shapes"] = {
            "masses": list(sys_.mass_index),
            "modes": [
                {"re": md.shapes[:, i].real.tolist(), "im": md.shapes[:, i].imag.tolist()}
                for i in range(len(md))
            ],
        }
    return out
