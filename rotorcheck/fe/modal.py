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

Size. Up to :data:`rotorcheck.fe.frf.N_FULL` DOF every mode comes from one eigendecomposition of the
state matrix (:func:`rotorcheck.fe.frf.state_matrix`). Larger meshes are solved in a Ritz basis
(:func:`rotorcheck.fe.frf.ritz_basis`: the undamped modes up to ten times the band asked for plus the
static responses to their damping and gyroscopic coupling), built once per set of matrices (the
system's ``matrix_key``, so once for a whole Campbell diagram over constant bearings) and kept in the
system's cache; only modes up to the band are returned (``n_modes`` or ``max_hz`` set the band).
The Ritz values carry the basis's truncation (1e-10 relative on the 72-element rig, 1.7e-7 on ROSS's
compressor with its cross-coupled seals), a small model's eigendecomposition its round-off (2e-9 on
1e20 N/m supports), so :func:`modes` refines each pair on the full matrices (:func:`_refine`, one LU
of ``l^2 M + l D + K`` per mode or degenerate pair, sparse on a large mesh): 1e-10 relative or
better against the full first-order eigenproblem (tests/fe/test_fe_modal_accuracy.py). Campbell
tracking uses the values as they are; critical speeds refine the followed mode at each trial speed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rotorcheck.config import RigConfig
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.blas import one_blas_thread
from rotorcheck.fe.damping import undamped_modes
from rotorcheck.fe.frf import N_FULL, lowest_undamped_modes, ritz_basis, state_matrix
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.lazy import lazy_module

if TYPE_CHECKING:
    import scipy.linalg as sla
    import scipy.optimize as sopt
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
else:  # loaded at first use: importing the FE package stays cheap
    sla = lazy_module("scipy.linalg")
    sopt = lazy_module("scipy.optimize")
    sp = lazy_module("scipy.sparse")
    spla = lazy_module("scipy.sparse.linalg")

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


def _circularize(lam: np.ndarray, vec: np.ndarray, lc: float, n_shaft: int) -> np.ndarray:
    """Rotate bases of degenerate eigenvalue pairs to (backward, forward) circular modes (whirl judged on
    the first ``n_shaft`` displacement DOF: the shaft's)."""
    vec = vec.copy()
    i = 0
    while i < lam.size - 1:
        if abs(lam[i + 1] - lam[i]) <= _DEGENERATE_TOL * abs(lam[i]):
            Q = vec[:, [i, i + 1]]
            fwd, bwd = _whirl_components(Q[:n_shaft], lc)
            # forward mode: combination with no backward component, and vice versa
            cf = np.linalg.svd(bwd, full_matrices=False)[2][-1].conj()
            cb = np.linalg.svd(fwd, full_matrices=False)[2][-1].conj()
            vec[:, i], vec[:, i + 1] = Q @ cb, Q @ cf
            i += 2
        else:
            i += 1
    return vec


def _normalise(shapes: np.ndarray, kind: str, n_shaft: int) -> np.ndarray:
    """Scale each shape so its largest translational (shaft) component is 1 (real)."""
    trans = shapes[: n_shaft : 4] if kind == "rotor" else shapes
    idx = np.argmax(np.abs(trans), axis=0)
    ref = trans[idx, np.arange(shapes.shape[1])]
    ref = np.where(np.abs(ref) > 0, ref, 1.0)
    return shapes / ref[None, :]


def _characteristic_length(system: MechanicalSystem) -> float:
    pos = np.asarray(system.node_positions)
    return float(pos.max() - pos.min()) / 4.0 if pos.size > 1 else 1.0


#: modes asked for without ``n_modes`` or ``max_hz`` on a large mesh (Ritz basis)
DEFAULT_REDUCED_MODES = 12
_BAND_MARGIN = 1.25  # band above the highest wanted undamped mode (gyroscopic stiffening)


def _undamped(system: MechanicalSystem, speed_rpm: float, f_max_hz: float, count: int) -> np.ndarray:
    """Lowest undamped frequencies (Hz) of a large system: up to f_max_hz and at least ``count``."""
    key = ("undamped", system.matrix_key(speed_rpm))
    hit = system.cache.get(key)
    if hit is None or (hit.size < count and hit.size < system.n_dof - 2) or hit[-1] < f_max_hz:
        M, _, _, K = system.matrices(speed_rpm)
        with one_blas_thread():
            w, _ = lowest_undamped_modes(M, K, f_max_hz, min_count=count)
        hit = w / TWO_PI
        system.cache[key] = hit
    return hit


def _band_hz(system: MechanicalSystem, speed_rpm: float, n_modes: int | None, max_hz: float | None) -> float:
    """Band (Hz) a Ritz basis must cover for ``n_modes`` (or ``max_hz``) modes."""
    if max_hz is not None:
        return float(max_hz)
    count = (n_modes if n_modes is not None else DEFAULT_REDUCED_MODES) + 2
    f = _undamped(system, speed_rpm, 0.0, count)
    return _BAND_MARGIN * float(f[min(count, f.size) - 1])


def _reduced_matrices(system: MechanicalSystem, speed_rpm: float, band_hz: float) -> tuple[np.ndarray, ...]:
    """(V, M_r, C_r, G_r, K_r) of the cached Ritz basis covering ``band_hz`` (built when needed)."""
    key = ("ritz", system.matrix_key(speed_rpm))
    hit = system.cache.get(key)
    if hit is None or hit[0] < band_hz:
        M, C, G, K = system.matrices(speed_rpm)
        with one_blas_thread():
            V = ritz_basis(M, K, [C, G], [], band_hz, levels=1).V
            hit = (band_hz, (V, V.T @ M @ V, V.T @ C @ V, V.T @ G @ V, V.T @ K @ V))
        system.cache[key] = hit
    return hit[1]


#: eigenvalues within this relative distance are refined together (one subspace)
_CLUSTER_TOL = 1e-4
#: inverse-iteration steps of :func:`_refine` (each gains about ``|lambda - sigma| / gap``)
_REFINE_STEPS = 3


def _refine(M: np.ndarray, D: np.ndarray, K: np.ndarray, lam: np.ndarray, vec: np.ndarray) -> tuple[np.ndarray, ...]:
    """Eigenpairs ``(lam, shapes (n, p))`` of ``T(l) = l^2 M + l D + K`` refined on the full matrices.

    A Ritz basis carries its truncation into the eigenvalues (1.7e-7 relative on ROSS's compressor,
    cross-coupled seals; 4.4e-10 on a damped anisotropic 340-DOF rotor), the state matrix's own
    eigendecomposition round-off of ``eps ||A||``, ``||A|| ~ w_max^2`` (2e-9 on the cone on 1e20 N/m
    supports: its degenerate pairs split). Each cluster of eigenvalues
    (relative spacing below :data:`_CLUSTER_TOL`: a degenerate or split pair) is refined as one
    subspace: ``_REFINE_STEPS``
    steps of inverse iteration, right ``Q <- T(s)^-1 T'(s) Q`` and left ``P <- T(s)^-H T'(s)^H P``, at
    the cluster's mean ``s``, then the two-sided projection ``P^H T(l) Q c = 0`` (its eigenvalues
    nearest ``s``), whose error is the product of the right and left subspaces' errors.
    """
    n = M.shape[0]
    out_lam, out_vec = lam.astype(complex), np.array(vec[:n], dtype=complex)
    large = n > N_FULL  # sparse LU and products on a large mesh, dense ones on a small model
    Ms, Ds, Ks = (sp.csc_matrix(A) for A in (M, D, K)) if large else (M, D, K)
    i = 0
    while i < lam.size:
        j = i + 1
        while j < lam.size and abs(lam[j] - lam[j - 1]) <= _CLUSTER_TOL * abs(lam[j - 1]):
            j += 1
        s = complex(np.mean(lam[i:j]))
        Tp = 2.0 * s * Ms + Ds  # T'(s); M, D, K real
        TpH = Tp.conj().T
        if large:
            lu = spla.splu((s * s * Ms + s * Ds + Ks).astype(complex).tocsc())  # T(s)
            solve = lambda b, h=False, lu=lu: lu.solve(b, trans="H" if h else "N")  # noqa: E731
        else:
            fac = sla.lu_factor(s * s * M + s * D + K)
            solve = lambda b, h=False, fac=fac: sla.lu_solve(fac, b, trans=2 if h else 0)  # noqa: E731
        Q = out_vec[:, i:j]
        P = Q.conj()
        for _ in range(_REFINE_STEPS):
            Q = np.linalg.qr(solve(Tp @ Q))[0]
            P = np.linalg.qr(solve(TpH @ P, True))[0]
        Ph = P.conj().T
        m, d, k = Ph @ (Ms @ Q), Ph @ (Ds @ Q), Ph @ (Ks @ Q)
        z = np.zeros_like(m)
        eye = np.eye(m.shape[0])
        mu, c = sla.eig(np.block([[z, eye], [-k, -d]]), np.block([[eye, z], [z, m]]))
        near = np.argsort(np.abs(mu - s))[: j - i]
        near = near[np.argsort(mu[near].imag, kind="stable")]
        out_lam[i:j] = mu[near]
        out_vec[:, i:j] = Q @ c[: m.shape[0], near]
        i = j
    return out_lam, out_vec


def _state_modes(
    system: MechanicalSystem, speed_rpm: float, n_modes: int | None, max_hz: float | None, refine: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (p,) and displacement eigenvectors (n, p) with Im(lambda) > 0, ascending, with
    ``refine`` refined on the full matrices (:func:`_refine`; the lowest ``n_modes`` only, when given
    without ``max_hz``)."""
    n = system.n_dof
    omega = speed_rpm * RPM_TO_RAD_S
    band = None
    if n <= N_FULL:
        M, C, G, K = system.matrices(speed_rpm)
        with one_blas_thread():  # small dense problems: BLAS threads only synchronise
            lam, vec = sla.eig(state_matrix(M, C + omega * G, K))
    else:
        band = _band_hz(system, speed_rpm, n_modes, max_hz)
        V, Mr, Cr, Gr, Kr = _reduced_matrices(system, speed_rpm, band)
        with one_blas_thread():
            lam, z = sla.eig(state_matrix(Mr, Cr + omega * Gr, Kr))
        m = Mr.shape[0]
        keep = (lam.imag > 1e-9 * max(np.abs(lam).max(), 1.0)) & (lam.imag <= TWO_PI * band)
        lam, z = lam[keep], z[:, keep]
        vec = np.vstack([V @ z[:m], V @ z[m:]])
    scale = max(np.abs(lam).max(), 1.0) if lam.size else 1.0
    keep = lam.imag > 1e-9 * scale
    lam, vec = lam[keep], vec[:, keep]
    order = np.argsort(lam.imag, kind="stable")
    lam, vec = lam[order], vec[:n, order]
    if not refine:
        return lam, vec
    if n_modes is not None and max_hz is None:  # the lowest n_modes and the rest of the last one's cluster
        keep = min(n_modes, lam.size)
        while 0 < keep < lam.size and abs(lam[keep] - lam[keep - 1]) <= _CLUSTER_TOL * abs(lam[keep - 1]):
            keep += 1
        lam, vec = lam[:keep], vec[:, :keep]
    M, C, G, K = system.matrices(speed_rpm)
    with one_blas_thread():
        lam, vec = _refine(M, C + omega * G, K, lam, vec)
    order = np.argsort(lam.imag, kind="stable")
    return lam[order], vec[:, order]


def modes(
    system: MechanicalSystem, speed_rpm: float = 0.0, n_modes: int | None = None, max_hz: float | None = None,
    refine: bool = True,
) -> Modes:
    """Modes at ``speed_rpm`` (oscillatory ones, Im(lambda) > 0), lowest ``n_modes`` if given.

    ``max_hz``: only modes up to this damped frequency. Small models return every mode otherwise;
    large meshes (Ritz basis, see the module docstring) the modes of the band that ``n_modes``
    (default :data:`DEFAULT_REDUCED_MODES`) needs. Each mode is refined on the full matrices
    (``refine=False``: the eigendecomposition's values as they are, for tracking: Ritz values 1.7e-7
    relative off at worst measured, a small model's 2e-9).
    """
    lam, vec = _state_modes(system, speed_rpm, n_modes, max_hz, refine)
    if max_hz is not None:
        within = lam.imag <= TWO_PI * max_hz
        lam, vec = lam[within], vec[:, within]
    n, ns = system.n_dof, system.n_shaft_dof  # support-node DOF (x, y) follow the shaft's
    if system.kind == "rotor":
        vec = _circularize(lam, vec, _characteristic_length(system), ns)
    shapes = _normalise(vec[:n], system.kind, ns)
    if system.kind == "rotor":
        ratio = whirl_ratio(shapes[:ns])
    else:
        ratio = np.full(lam.size, np.nan)
    if n_modes is not None:
        lam, shapes, ratio = lam[:n_modes], shapes[:, :n_modes], ratio[:n_modes]
    return Modes(float(speed_rpm), lam, shapes, ratio)


def natural_frequencies_at_rest(system: MechanicalSystem, n_modes: int | None = None) -> np.ndarray:
    """Undamped natural frequencies (Hz) of (K, M) at 0 rpm, ascending (every DOF, or the lowest
    ``n_modes``: shift-invert Lanczos on a large mesh)."""
    if n_modes is not None and system.n_dof > N_FULL:
        return _undamped(system, 0.0, 0.0, n_modes)[:n_modes]
    M, _, _, K = system.matrices(0.0)
    Ks = 0.5 * (K + K.T)
    try:  # 1 / w^2 from (M, K_s): the low modes to round-off of 1 / w_min^2, not of ||K|| (rigid supports)
        mu = sla.eigh(M, Ks, eigvals_only=True)
        w = np.sort(1.0 / np.sqrt(mu)) if mu.min() > 0 else undamped_modes(M, K)[0]
    except np.linalg.LinAlgError:  # K_s not positive definite (no support, negative stiffness)
        w, _ = undamped_modes(M, K)
    return w / TWO_PI if n_modes is None else w[:n_modes] / TWO_PI


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
    notes: tuple[str, ...] = ()  # what the critical speed search could not settle (see _branch_crossings)

    @property
    def whirl(self) -> np.ndarray:
        """Labels (s, m)."""
        return np.vectorize(whirl_label, otypes=[object])(self.whirl_ratio)

    @property
    def branch_whirl(self) -> tuple[str, ...]:
        """One label per branch: the label at the highest speed (where splitting is largest)."""
        return tuple(whirl_label(r) for r in self.whirl_ratio[-1])


_TRACK_WINDOW = 1.3  # large meshes: modes up to this factor x the band are candidates for a branch
_LOST_MAC = 0.5  # large meshes: a branch whose best match is below this MAC left the window


def _track(
    system: MechanicalSystem, speeds: np.ndarray, max_hz: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    """Track every oscillatory mode over ``speeds`` by MAC with the previous speed's shapes and an
    optimal assignment (ties broken by frequency proximity).

    Small models track every mode. Large meshes track the modes up to ``max_hz`` at the first
    speed among the modes up to 1.3 ``max_hz`` at each speed; a branch that leaves that window is
    NaN until it comes back.

    Returns (lam (s, p), whirl ratio (s, p), min MAC per branch (p,), shapes per speed [(n, p)]).
    """
    large = system.n_dof > N_FULL
    window: float | None = None
    if large:
        band = max_hz if max_hz is not None else _band_hz(system, speeds[0], None, None)
        window = _TRACK_WINDOW * band
    first = modes(system, speeds[0], max_hz=window, refine=False)
    p = len(first) if window is None else int(np.count_nonzero(first.frequency_hz <= window / _TRACK_WINDOW))
    lam = np.full((speeds.size, p), np.nan + 0j)
    ratio = np.full((speeds.size, p), np.nan)
    lam[0], ratio[0] = first.eigenvalues[:p], first.whirl_ratio[:p]
    ref = first.shapes[:, :p].copy()
    refs = [ref.copy()]
    minmac = np.ones(p)
    last = lam[0].copy()
    for k in range(1, speeds.size):
        cur = modes(system, speeds[k], max_hz=window, refine=False)
        m = mac(ref, cur.shapes)
        f_prev = np.abs(last.imag)[:, None]
        df = np.abs(f_prev - cur.eigenvalues.imag[None, :]) / np.maximum(f_prev, 1e-12)
        cost = (1.0 - m) + 1e-3 * np.nan_to_num(df, nan=1.0)
        rows, cols = sopt.linear_sum_assignment(cost)
        if large:
            ok = m[rows, cols] >= _LOST_MAC
            rows, cols = rows[ok], cols[ok]
        lam[k, rows] = cur.eigenvalues[cols]
        ratio[k, rows] = cur.whirl_ratio[cols]
        last[rows] = cur.eigenvalues[cols]
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


#: damping ratio from which a mode has no resonance peak (|H| monotonic): not a critical speed
NO_PEAK_DAMPING = 1.0 / np.sqrt(2.0)


def campbell(
    system: MechanicalSystem,
    speeds_rpm: Sequence[float] | np.ndarray,
    n_modes: int = 6,
    order: int = 1,
    criticals: bool = True,
    max_hz: float | None = None,
) -> CampbellResult:
    """Campbell diagram: the lowest ``n_modes`` branches (at the first speed) tracked over speed.

    With ``criticals``, forward branches crossing ``order`` x running speed are root-found.
    ``max_hz``: large meshes track the branches up to this frequency at the first speed (default:
    the band ``n_modes`` needs); small models track every mode.
    """
    speeds = np.asarray(speeds_rpm, dtype=float)
    if max_hz is None and system.n_dof > N_FULL:
        max_hz = _band_hz(system, float(speeds[0]), min(n_modes, system.n_dof), None)
    lam, ratio, minmac, refs = _track(system, speeds, max_hz)
    window = None if max_hz is None else _TRACK_WINDOW * max_hz
    sel = _branch_order(lam)[: min(n_modes, lam.shape[1])]
    f = lam.imag / TWO_PI
    zeta = -lam.real / np.abs(lam)
    crit: list[tuple[float, int]] = []
    notes: list[str] = []
    if criticals and system.kind == "rotor":
        for j, b in enumerate(sel):
            for rpm in _branch_crossings(system, speeds, f[:, b], ratio[:, b], refs, b, order, window, notes):
                # a mode damped beyond 1/sqrt(2) has no resonance peak: its crossing is no critical speed
                if np.interp(rpm, speeds, zeta[:, b]) < NO_PEAK_DAMPING:
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
        notes=tuple(notes),
    )


#: a grid interval whose ends do not bracket the crossing once the branch is followed by MAC is scanned
#: at this many sub-intervals for a sign change before the crossing is reported as not found
_SCAN_STEPS = 8


def _branch_crossings(
    system: MechanicalSystem,
    speeds: np.ndarray,
    f: np.ndarray,
    ratio: np.ndarray,
    refs: list[np.ndarray],
    b: int,
    order: int,
    window: float | None = None,
    notes: list[str] | None = None,
) -> list[float]:
    """Root-found speeds (rpm) where forward branch ``b`` crosses ``order`` x running speed
    (``window``: the modes searched at each trial speed, None for all).

    At a trial speed the branch is the mode of largest MAC with the shape at the previous speed. A
    sign change on the Campbell grid whose ends do not bracket a root when the branch is followed
    that way (the optimal assignment of the whole grid and the best MAC of one mode can differ where
    branches swap) is scanned at :data:`_SCAN_STEPS` sub-intervals, following the mode from step to
    step; without a sign change there the crossing is not reported and ``notes`` gets a sentence.
    """
    g = f - order * speeds / 60.0
    out = []

    def follow(rpm: float, ref: np.ndarray) -> tuple[float, np.ndarray]:
        md = modes(system, rpm, max_hz=window, refine=False)
        j = int(np.argmax(mac(ref, md.shapes)[0]))
        lam = md.eigenvalues
        near = np.nonzero(np.abs(lam - lam[j]) <= _CLUSTER_TOL * abs(lam[j]))[0]  # its cluster (a degenerate pair)
        M, C, G, K = system.matrices(rpm)
        with one_blas_thread():  # refine the followed mode (with its cluster) alone
            refined = _refine(M, C + rpm * RPM_TO_RAD_S * G, K, lam[near], md.shapes[:, near])[0]
        f = refined[np.argmin(np.abs(refined - lam[j]))].imag / TWO_PI
        return float(f - order * rpm / 60.0), md.shapes[:, j : j + 1]

    for k in np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]:
        if not (ratio[k] > PLANAR_TOL or ratio[k + 1] > PLANAR_TOL):
            continue
        if g[k] == 0.0:
            out.append(float(speeds[k]))
            continue
        lo, hi, ref = float(speeds[k]), float(speeds[k + 1]), refs[k][:, b : b + 1]
        g_lo, _ = follow(lo, ref)
        g_hi, _ = follow(hi, ref)
        if np.sign(g_lo) * np.sign(g_hi) > 0:  # scan: follow the mode step by step
            bracket = None
            x_prev, g_prev, ref_prev = lo, g_lo, ref
            for x in np.linspace(lo, hi, _SCAN_STEPS + 1)[1:]:
                g_x, shape = follow(float(x), ref_prev)
                if np.sign(g_prev) * np.sign(g_x) <= 0:
                    bracket = (x_prev, float(x), ref_prev)
                    break
                x_prev, g_prev, ref_prev = float(x), g_x, shape
            if bracket is None:
                if notes is not None:
                    notes.append(
                        f"order-{order} critical speed search: a forward branch ({f[k]:.4g} Hz at {lo:g} rpm) "
                        f"changes sides of the {order}X line between {lo:g} and {hi:g} rpm on the Campbell grid, "
                        f"but not when its mode is followed at {_SCAN_STEPS} finer speeds (branches swap there): "
                        "no critical speed reported in that interval")
                continue
            lo, hi, ref = bracket

        def h(rpm: float, ref: np.ndarray = ref) -> float:
            return follow(rpm, ref)[0]

        out.append(float(sopt.brentq(h, lo, hi, xtol=1e-6, rtol=1e-12)))
    return out


def critical_speeds(
    system: MechanicalSystem, max_rpm: float, order: int = 1, n_grid: int = 41, notes: list[str] | None = None
) -> list[float]:
    """Forward critical speeds (rpm) up to ``max_rpm``: forward branches crossing order x speed.

    Branches are tracked on a grid of ``n_grid`` speeds; every sign change of
    ``f(rpm) - order rpm / 60`` on a forward branch is root-found with Brent's method (a sign change
    that following the mode does not confirm is left out, with a sentence in ``notes``).
    """
    if system.kind != "rotor":
        return []
    speeds = np.linspace(0.0, float(max_rpm), n_grid)
    band = None
    if system.n_dof > N_FULL:  # a forward branch crossing order x speed starts below that line
        band = max(1.1 * order * float(max_rpm) / 60.0, _band_hz(system, 0.0, 2, None))
    camp = campbell(system, speeds, n_modes=system.n_dof, order=order, max_hz=band)
    if notes is not None:
        notes.extend(camp.notes)
    return sorted(camp.critical_speeds_rpm)


# --------------------------------------------------------------------------------------------
# summary for the CLI


#: below this (unit-diagonal scaling) the static stiffness counts as not positive definite
STATIC_MARGIN_TOL = 1e-9


def static_stiffness_warnings(system: MechanicalSystem, speeds_rpm: list[float]) -> list[str]:
    """Warnings where the assembled static stiffness (symmetric part) is not positive definite."""
    out: list[str] = []
    for sp in dict.fromkeys(float(x) for x in speeds_rpm):
        margin = system.static_stiffness_margin(sp)
        if margin <= STATIC_MARGIN_TOL:
            what = "singular (a free rigid-body motion: no support?)" if margin > -STATIC_MARGIN_TOL else \
                "indefinite (negative net stiffness: a negative-stiffness bearing or seal, or compressive load)"
            out.append(f"static stiffness at {sp:g} rpm is {what}; smallest scaled eigenvalue {margin:.3g}; "
                       "undamped frequencies of negative-stiffness modes are reported as 0")
    return out


def mode_table(md: Any) -> list[dict[str, Any]]:
    """The modes of a :func:`modes` result as the ``model`` table's rows (``frequency_hz`` damped,
    ``natural_frequency_hz``, ``damping_ratio``, ``whirl``, ``whirl_ratio``)."""
    return [
        {
            "frequency_hz": float(md.frequency_hz[i]),
            "natural_frequency_hz": float(md.natural_frequency_hz[i]),
            "damping_ratio": float(md.damping_ratio[i]),
            "whirl": md.whirl[i],
            "whirl_ratio": None if not np.isfinite(md.whirl_ratio[i]) else float(md.whirl_ratio[i]),
        }
        for i in range(len(md))
    ]


def model_summary(
    config: RigConfig, speed_rpm: float = 0.0, system: MechanicalSystem | None = None
) -> dict[str, Any]:
    """The ``rotorcheck model`` JSON document (cli.md): modes, whirl, critical speeds, shapes.

    Keys: ``speed_rpm``, ``modes`` (list of ``frequency_hz`` (damped), ``natural_frequency_hz``,
    ``damping_ratio``, ``whirl``, ``whirl_ratio``), ``critical_speeds_rpm`` (forward, 1X, up to
    ``analysis.campbell_max_rpm``), ``undamped_frequencies_at_rest_hz``, ``mode_shapes`` (per
    station, x and y, real and imaginary parts).
    """
    sys_ = system if system is not None else build_system(config)
    n = min(config.analysis.n_modes, sys_.n_dof)  # more asked than the model has: clamped (config.notes says so)
    md = modes(sys_, speed_rpm, n_modes=n)
    rest = natural_frequencies_at_rest(sys_, n)
    entries = mode_table(md)
    out: dict[str, Any] = {
        "rig_id": config.rig_id,
        "speed_rpm": float(speed_rpm),
        "modes": entries,
        "critical_speeds_rpm": [],
        "undamped_frequencies_at_rest_hz": [float(x) for x in rest],
        "warnings": config.notes() + static_stiffness_warnings(sys_, [0.0, float(speed_rpm)]),
    }
    if sys_.kind == "rotor":
        out["critical_speeds_rpm"] = critical_speeds(sys_, config.analysis.campbell_max_rpm, notes=out["warnings"])
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
