r"""Harmonic balance (Hill's method) for the breathing-crack rotor, a linear time-periodic system.

Equation (eq. 5.9: weight dominance, static sag removed), SI units, Omega in rad/s:

    M q'' + (C + Omega G) q' + (K0 - K_c(t)) q = Re{ b U exp(j w t) },
    K_c(t) = sum_p K_p exp(j p Omega t)                (rotorcheck.faults.crack)

Steady state for the complex forcing ``b exp(j w t)``: ``q(t) = sum_{k=-H..H} Q_k exp(j (w + k Omega) t)``
with ``Z(w + k Omega) Q_k - sum_p K_p Q_{k-p} = b delta_k0``, ``Z(nu) = K0 - nu^2 M + j nu (C + Omega G)``.
For a real input ``Re{U e^{jwt}}`` the real response is ``Re{U sum_k Q_k e^{j(w + k Omega)t}}``
(the conjugate part of the force produces the conjugate response), so tones are returned with
**signed** frequencies ``f + k f_s`` (Hz; some negative when ``f < H f_s``) and complex amplitudes
per unit input phasor ``U``; this is exactly the form ``x(t) = Re sum_m Y_m exp(j 2 pi F_m t)`` that
:func:`rotorcheck.signal.lockin.tone_lockin` accepts. :func:`fold_tones` gives the equivalent
non-negative-frequency phasors for a given ``U`` (for display).

Solver. K_c lives on the cracked element's m DOF (m = 8 for one element), so the (2H+1) n block
system is reduced exactly to (2H+1) m unknowns ``Y_k = S^T Q_k`` (S selects the crack DOF):

    (I - blkdiag(S^T Z_k^-1 S) Kblk) Y = [S^T Z_0^-1 b at k = 0],  Kblk[k, j] = K_{k-j},
    Q_k = Z_k^-1 (b delta_k0 + S (Kblk Y)_k),

with the receptances ``S^T Z_k^-1 [S, b]`` and ``C Z_k^-1 [S, b]`` of every tone from the engine
(:class:`rotorcheck.fe.frf.Receptance`, all frequencies and harmonics at once) and one batched
(2H+1) m solve per frequency. The full block (Hill) matrix and an independent dense HB are test
oracles (tests/oracles/hb.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotorcheck.config import Crack, Misalignment, UnbalanceMass
from rotorcheck.faults.crack import CrackStiffness, crack_stiffness
from rotorcheck.fe.blas import one_blas_thread
from rotorcheck.fe.frf import Method, Receptance
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem

__all__ = [
    "CrackedPlant",
    "HBResult",
    "HBSolver",
    "convergence_table",
    "cracked_disturbance_tones",
    "cracked_tones",
    "fold_tones",
    "misalignment_force",
    "solve_hb",
    "unbalance_force",
]

TWO_PI = 2.0 * np.pi
_CHUNK_ENTRIES = 8_000_000  # complex entries per chunk of frequencies (128 MB)


@dataclass(frozen=True)
class HBResult:
    """Harmonic-balance steady state per unit input phasor.

    ``out[f, i, o, s]``: complex amplitude (m per N for force inputs) of output ``o`` at the tone
    ``tones_hz[f, i] = freq_hz[f] + orders[i] * speed_hz`` for input ``s``.
    """

    freq_hz: np.ndarray  # (F,)
    orders: np.ndarray  # (2H+1,) k = -H..H
    speed_rpm: float
    out: np.ndarray  # (F, 2H+1, n_out, n_in) complex

    @property
    def speed_hz(self) -> float:
        return self.speed_rpm / 60.0

    @property
    def tones_hz(self) -> np.ndarray:
        """Signed tone frequencies (F, 2H+1), Hz."""
        return self.freq_hz[:, None] + self.orders[None, :] * self.speed_hz

    @property
    def fundamental(self) -> np.ndarray:
        """The k = 0 tone (F, n_out, n_in): the cracked rotor's direct FRF at the excitation."""
        return self.out[:, int(np.flatnonzero(self.orders == 0)[0])]


def _as_crack(system: MechanicalSystem, crack: Crack | CrackStiffness | None, **kw: Any) -> CrackStiffness | None:
    if crack is None or isinstance(crack, CrackStiffness):
        return crack
    return crack_stiffness(system, crack, **kw)


def _inputs(n: int, inputs: Any) -> np.ndarray:
    """Input matrix (n, n_in) complex from an int DOF, a list of DOFs or an (n,)/(n, n_in) array."""
    if isinstance(inputs, (int, np.integer)):
        b = np.zeros((n, 1), dtype=complex)
        b[int(inputs), 0] = 1.0
        return b
    arr = np.asarray(inputs)
    if arr.ndim == 1 and arr.dtype.kind in "iu" and arr.size != n:
        b = np.zeros((n, arr.size), dtype=complex)
        b[arr, np.arange(arr.size)] = 1.0
        return b
    arr = arr.astype(complex)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.shape[0] != n:
        raise ValueError(f"input vectors need {n} rows, got {arr.shape}")
    return arr


def _crack_blocks(crack: CrackStiffness | None, speed_rpm: float, n_harm: int) -> tuple[np.ndarray, np.ndarray]:
    """Fourier orders and coefficients of K_c used for this speed (constant K_c when Omega = 0)."""
    if crack is None:
        return np.zeros(0, dtype=int), np.zeros((0, 0, 0))
    if speed_rpm == 0.0:
        return np.array([0]), crack.at_rotation(0.0).astype(complex)
    orders, kp = crack.harmonics()
    keep = np.abs(orders) <= 2 * n_harm
    return orders[keep], kp[keep]


class HBSolver:
    """Harmonic-balance solver with everything that depends only on the speed precomputed
    (receptance factorization, the Fourier blocks of K_c); call :meth:`solve` per frequency set.

    Arguments as :func:`solve_hb`.
    """

    def __init__(
        self,
        system: MechanicalSystem,
        crack: Crack | CrackStiffness | None,
        speed_rpm: float,
        inputs: Any,
        out_dofs: Sequence[int] | int | np.ndarray,
        n_harmonics: int = 8,
        method: Method = "auto",
        **crack_kw: Any,
    ):
        self.crack = _as_crack(system, crack, **crack_kw)
        self.speed_rpm = float(speed_rpm)
        M, C, G, K = system.matrices(speed_rpm)
        n = system.n_dof
        self.omega = self.speed_rpm * RPM_TO_RAD_S
        D = C + self.omega * G
        b = _inputs(n, inputs)
        self.n_in = b.shape[1]
        self.outs = np.atleast_1d(np.asarray(out_dofs, dtype=int))
        self.H = int(n_harmonics)
        self.orders = np.arange(-self.H, self.H + 1)
        nk = self.orders.size
        porders, kp = _crack_blocks(self.crack, self.speed_rpm, self.H)
        self.coupled = porders.size > 0
        if not self.coupled:
            self.m = 0
            self.rec = Receptance(M, D, K, self.outs, b, method=method)
            return
        assert self.crack is not None
        dofs = self.crack.dofs
        m = self.m = dofs.size
        kblk = np.zeros((nk, m, nk, m), dtype=complex)  # Kblk[k, :, j, :] = K_{k - j}
        for p, kpp in zip(porders, kp):
            for k in range(nk):
                j = k - int(p)
                if 0 <= j < nk:
                    kblk[k, :, j, :] = kpp
        self.kflat = kblk.reshape(nk * m, nk * m)
        self.kblk_rows = kblk.reshape(nk, m, nk * m)  # block row k: [K_{k-j}]_j
        cols = np.zeros((n, m + self.n_in), dtype=complex)
        cols[dofs, np.arange(m)] = 1.0
        cols[:, m:] = b
        self.rec = Receptance(M, D, K, np.r_[dofs, self.outs], cols, method=method)
        self.eye = np.eye(nk * m)

    def solve(self, freq_hz: np.ndarray | float, chunk: int = 64) -> HBResult:
        """Tones for the excitation frequencies ``freq_hz`` (Hz)."""
        # many small dense operations: BLAS threads only synchronise (bench/bench_engine.py)
        with one_blas_thread():
            return self._solve(freq_hz, chunk)

    def _solve(self, freq_hz: np.ndarray | float, chunk: int) -> HBResult:
        f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
        H, m, nk, n_in = self.H, self.m, self.orders.size, self.n_in
        result = np.zeros((f.size, nk, self.outs.size, n_in), dtype=complex)
        if f.size:  # every tone of this call in one band (a reduced basis is built once)
            self.rec.ensure_band(float(np.max(np.abs(f))) + (H * self.omega / TWO_PI if self.coupled else 0.0))
        if not self.coupled:
            result[:, H] = self.rec(TWO_PI * f)
            return HBResult(f, self.orders, self.speed_rpm, result)
        # bounded working memory per chunk: the receptances and the (2H+1) m system of each frequency
        per_f = nk * (m + self.outs.size) * (m + n_in) + 2 * (nk * m) ** 2
        chunk = max(1, min(int(chunk), _CHUNK_ENTRIES // per_f))
        for s in range(0, f.size, chunk):
            fc = f[s : s + chunk]
            nu = TWO_PI * fc[:, None] + self.orders[None, :] * self.omega  # (Fc, nk) rad/s
            X = self.rec(nu)  # (Fc, nk, m + n_out, m + n_in): rows [dofs, outs], cols [S, b]
            g_ss = X[:, :, :m, :m]  # S^T Z_k^-1 S
            h_os = X[:, :, m:, :m]  # C Z_k^-1 S
            g_in = X[:, H, :m, m:]  # S^T Z_0^-1 b
            h_oi = X[:, H, m:, m:]  # C Z_0^-1 b
            gk = np.matmul(g_ss, self.kblk_rows).reshape(fc.size, nk * m, nk * m)
            rhs = np.zeros((fc.size, nk * m, n_in), dtype=complex)
            rhs[:, H * m : (H + 1) * m] = g_in
            y = np.linalg.solve(self.eye - gk, rhs)  # (Fc, nk m, n_in)
            w = (self.kflat @ y).reshape(fc.size, nk, m, n_in)
            out = np.matmul(h_os, w)
            out[:, H] += h_oi
            result[s : s + chunk] = out
        return HBResult(f, self.orders, self.speed_rpm, result)


def solve_hb(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    freq_hz: np.ndarray | float,
    inputs: Any,
    out_dofs: Sequence[int] | int | np.ndarray,
    n_harmonics: int = 8,
    chunk: int = 64,
    method: Method = "auto",
    **crack_kw: Any,
) -> HBResult:
    """Steady-state tones of the cracked rotor for complex forcing ``b exp(j 2 pi f t)``.

    ``inputs``: a DOF index (unit force), a list of DOFs, or force vectors (n,)/(n, n_in) (N);
    ``out_dofs``: DOF indices of the outputs; ``n_harmonics`` = H (tones k = -H..H).
    ``crack=None`` gives the healthy (time-invariant) response in the k = 0 tone.
    ``method``: how the engine computes the receptances (:class:`rotorcheck.fe.frf.Receptance`:
    ``"modal"``, ``"direct"``, ``"reduced"`` or ``"auto"``).
    """
    solver = HBSolver(system, crack, speed_rpm, inputs, out_dofs, n_harmonics, method, **crack_kw)
    return solver.solve(freq_hz, chunk)


def fold_tones(
    tones_hz: np.ndarray, amps: np.ndarray, phasor: complex = 1.0, tol_hz: float = 1e-9
) -> tuple[np.ndarray, np.ndarray]:
    """Non-negative-frequency phasors of ``Re{U sum_m Y_m e^{j 2 pi F_m t}}``.

    A tone at ``F < 0`` becomes ``conj(U Y)`` at ``|F|``; tones at equal ``|F|`` are summed; the DC
    entry (F = 0) is the real value ``Re{sum U Y}`` (stored as a real phasor).
    Returns ``(freqs (q,) ascending, phasors (q, ...))``.
    """
    tones = np.asarray(tones_hz, dtype=float)
    y = np.asarray(amps, dtype=complex) * phasor
    a = np.where((tones < 0).reshape(-1, *([1] * (y.ndim - 1))), np.conj(y), y)
    fa = np.abs(tones)
    order = np.argsort(fa, kind="stable")
    fa, a = fa[order], a[order]
    freqs: list[float] = []
    vals: list[np.ndarray] = []
    for fi, ai in zip(fa, a):
        if freqs and abs(fi - freqs[-1]) <= tol_hz:
            vals[-1] = vals[-1] + ai
        else:
            freqs.append(float(fi))
            vals.append(ai.copy())
    out = np.array(vals)
    if freqs and freqs[0] <= tol_hz:
        out[0] = out[0].real
    return np.array(freqs), out


def convergence_table(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness,
    speed_rpm: float,
    freq_hz: Sequence[float],
    in_dof: int,
    out_dof: int,
    h_values: Sequence[int] = tuple(range(1, 11)),
    h_ref: int = 30,
) -> dict[str, Any]:
    """Relative change of the k = 0 sensor tone with the harmonic count H.

    Returns ``{"freq_hz", "H", "rel_to_ref" (len(H), len(f)), "rel_step" (change from H-1), "H_ref"}``.
    """
    ck = _as_crack(system, crack)
    f = np.asarray(freq_hz, dtype=float)
    ref = solve_hb(system, ck, speed_rpm, f, in_dof, [out_dof], h_ref).fundamental[:, 0, 0]
    vals = []
    for h in [0, *h_values]:
        vals.append(solve_hb(system, ck, speed_rpm, f, in_dof, [out_dof], h).fundamental[:, 0, 0])
    v = np.array(vals)
    rel_ref = np.abs(v[1:] - ref) / np.abs(ref)
    rel_step = np.abs(v[1:] - v[:-1]) / np.abs(v[1:])
    return {
        "freq_hz": f,
        "H": np.array(list(h_values)),
        "rel_to_ref": rel_ref,
        "rel_step": rel_step,
        "H_ref": h_ref,
    }


# --------------------------------------------------------------------------------------------
# synchronous forces


def unbalance_force(
    system: MechanicalSystem, station: int, amount: float, phase: float, speed_rpm: float
) -> np.ndarray:
    """Complex 1X force vector (n,) of an unbalance ``amount`` (kg m) at ``phase`` (rad, +x to +y).

    ``F_x = m e Omega^2 cos(Omega t + phase)``, ``F_y = m e Omega^2 sin(Omega t + phase)``, i.e. the
    phasor ``m e Omega^2 e^{j phase} (e_x - j e_y)`` at ``w = Omega``.
    """
    om = speed_rpm * RPM_TO_RAD_S
    b = np.zeros(system.n_dof, dtype=complex)
    a = amount * om**2 * np.exp(1j * phase)
    b[system.dof(station, "x")] += a
    b[system.dof(station, "y")] += -1j * a
    return b


def misalignment_force(
    system: MechanicalSystem, mis: Misalignment, speed_rpm: float, whirl: str = "forward"
) -> np.ndarray:
    """Complex 2X force vector (n,) of a misalignment (at ``w = 2 Omega``).

    Amplitude ``force_2x (speed/1000 rpm)^2`` (N). ``whirl="forward"``: a force rotating at 2X
    like an unbalance (``e_x - j e_y``); ``whirl="x"``: along x only, ``F_x = A cos(2 Omega t + phase)``.
    """
    a = mis.force_2x * (speed_rpm / 1000.0) ** 2 * np.exp(1j * mis.phase)
    b = np.zeros(system.n_dof, dtype=complex)
    b[system.dof(mis.station, "x")] += a
    if whirl == "forward":
        b[system.dof(mis.station, "y")] += -1j * a
    elif whirl != "x":
        raise ValueError(f"unknown whirl {whirl!r}")
    return b


def cracked_disturbance_tones(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    out_dofs: Sequence[int] | int | np.ndarray,
    unbalance: Sequence[UnbalanceMass] = (),
    misalignment: Misalignment | None = None,
    n_harmonics: int = 8,
    misalignment_whirl: str = "forward",
) -> tuple[np.ndarray, np.ndarray]:
    """Synchronous disturbance tones (unbalance 1X, misalignment 2X and crack harmonics).

    Returns ``(tone_freqs_hz (q,), amps (q, n_out))``: signed frequencies ``r f_s`` (r integer),
    absolute complex amplitudes (m), ``y(t) = Re sum_m amps_m exp(j 2 pi F_m t)``.
    """
    ck = _as_crack(system, crack)
    outs = np.atleast_1d(np.asarray(out_dofs, dtype=int))
    fs = speed_rpm / 60.0
    acc: dict[int, np.ndarray] = {}
    jobs: list[tuple[int, np.ndarray]] = []
    b1 = np.zeros(system.n_dof, dtype=complex)
    for u in unbalance:
        b1 += unbalance_force(system, u.station, u.amount, u.phase, speed_rpm)
    if np.any(b1):
        jobs.append((1, b1))
    if misalignment is not None and speed_rpm > 0:
        jobs.append((2, misalignment_force(system, misalignment, speed_rpm, misalignment_whirl)))
    for order, b in jobs:
        res = solve_hb(system, ck, speed_rpm, order * fs, b, outs, n_harmonics)
        for k, y in zip(res.orders, res.out[0, :, :, 0]):
            acc[order + int(k)] = acc.get(order + int(k), 0.0) + y
    if not acc:
        return np.zeros(0), np.zeros((0, outs.size), dtype=complex)
    r = np.array(sorted(acc))
    return r * fs, np.array([acc[int(i)] for i in r])


class CrackedPlant:
    """Plant callable for the sweep simulator: ``plant(f_exc_hz) -> (tone_freqs_hz, amps)``.

    ``tone_freqs_hz`` (2H+1,) signed (``f_exc + k f_s``), ``amps`` (2H+1, n_out) complex per unit
    input force phasor ``U`` at ``in_dof``: the real output is ``Re{U sum amps e^{j 2 pi F t}}``.
    """

    def __init__(
        self,
        system: MechanicalSystem,
        crack: Crack | CrackStiffness | None,
        speed_rpm: float,
        in_dof: int,
        out_dof: Sequence[int] | int | np.ndarray,
        n_harmonics: int = 8,
        **crack_kw: Any,
    ):
        self.system = system
        self.crack = _as_crack(system, crack, **crack_kw)
        self.speed_rpm = float(speed_rpm)
        self.in_dof = int(in_dof)
        self.out_dofs = np.atleast_1d(np.asarray(out_dof, dtype=int))
        self.n_harmonics = int(n_harmonics)
        self.solver = HBSolver(system, self.crack, self.speed_rpm, self.in_dof, self.out_dofs, self.n_harmonics)

    def sweep(self, freq_hz: np.ndarray) -> HBResult:
        """All tones for many excitation frequencies at once (vectorized)."""
        return self.solver.solve(freq_hz)

    def __call__(self, f_exc_hz: float) -> tuple[np.ndarray, np.ndarray]:
        res = self.sweep(np.array([float(f_exc_hz)]))
        return res.tones_hz[0], res.out[0, :, :, 0]

    def disturbance_tones(
        self,
        unbalance: Sequence[UnbalanceMass] = (),
        misalignment: Misalignment | None = None,
        misalignment_whirl: str = "forward",
    ) -> tuple[np.ndarray, np.ndarray]:
        """Synchronous tones at the outputs (see :func:`cracked_disturbance_tones`)."""
        return cracked_disturbance_tones(
            self.system,
            self.crack,
            self.speed_rpm,
            self.out_dofs,
            unbalance,
            misalignment,
            self.n_harmonics,
            misalignment_whirl,
        )


def cracked_tones(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    in_dof: int,
    out_dof: Sequence[int] | int | np.ndarray,
    n_harmonics: int = 8,
    **crack_kw: Any,
) -> CrackedPlant:
    """The simulator's plant callable ``f_exc_hz -> (tone_freqs_hz (2H+1,), amps (2H+1, n_out))``.

    Signed tone frequencies, amplitudes per unit input force phasor (m/N); see :class:`CrackedPlant`.
    ``crack_kw`` go to :func:`rotorcheck.faults.crack.crack_stiffness` (``form``, ``n_terms``, ...).
    """
    return CrackedPlant(system, crack, speed_rpm, in_dof, out_dof, n_harmonics, **crack_kw)
