"""The healthy sweep's own modes as the anchor of every predicted change (issue 29).

A change the FE model predicts (a benign parameter, an element's stiffness loss) moves the model's poles
and residues. The model's resonances sit a little off the machine's (mesh, shear coefficient, supports,
damping the model does not share), and a resonance's change is steep: a change predicted as the model's
own ``G(theta) / G - 1`` puts its peaks where the model has them, not where the machine has them. Here the
healthy FRF is fitted with a modal model: the poles the FE model has inside the measured band, refined on
the data, and their residues (linear). A change is then predicted by moving the *fitted* poles and residues
by the FE model's sensitivities (relative pole shift ``d ln(lambda) / d theta``, residue change
``dR / d theta``), plus the FE model's change of everything else (modes outside the band or invisible at the
channel), which is smooth:

    T(theta) - T_h = sum_r [R_r(theta) / (j w - lambda_r(theta)) - R_r / (j w - lambda_r) + conj.]
                     + theta * dH_out / d theta

with ``lambda_r(theta) = lambda_r sqrt(1 + 2 theta . d ln(lambda_r))`` (a stiffness moves a pole by a relative
amount the mesh hardly changes; lambda^2 is linear in a stiffness to first order) and
``R_r(theta) = R_r + theta . dR_r``; the predicted change is exact in the poles (not a first-order expansion of the
FRF: E -2 % moves a mode by a half-power bandwidth).

Measured on the five truth variants of ``bench/truth_variants.py`` (0 rpm, one probe, 6 random benign
states inside the ranges, noiseless, whitened at the samples' noise): what the best benign fit leaves of the
change falls from 350-5,800 noise widths (the FE ratio) to 15-120 on the truth and the fine mesh, 14-210
with a pedestal, 110-710 with bearing dampers (the change itself: 1,900-440,000).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.lazy import lazy_module
from rotorcheck.robust.affine import coupled_blocks

optimize = lazy_module("scipy.optimize")
linalg = lazy_module("scipy.linalg")

#: poles closer than this (relative) are one mode (x and y of an isotropic rotor at rest)
REPEATED = 1e-6
#: a mode whose peak (largest |R| / |Re lambda| over the channel pairs) is below this share of the largest
#: is invisible at the channels: it stays with the model's own (out-of-band) part
VISIBLE_PEAK = 1e-5
#: the model's error in a stiffness parameter's relative pole sensitivity d ln(lambda) / d theta, absolute, one
#: standard deviation: a parameter's share of a mode's strain energy is what the model can get wrong, and those
#: shares add to one, so the error is alike for every stiffness (the shaft's E and each support). Measured on the
#: five truth variants of bench/truth_variants.py, every mode below 600 Hz, 0 and 1000 rpm (``python -m
#: bench.pole_sensitivity``): the truths' sensitivities differ from the model's by up to 0.0170 (E; 0.015 at the 54 Hz
#: mode), 0.0086 (bearing nme) and 0.0091 (bearing me). The prior's reach is this error times the summed ranges
#: (:func:`rotorcheck.signatures.benign_prediction`): 0.006 puts the worst corner of the crack rig's ranges
#: (8.7e-4 of a pole, every error adding) at 1.8 standard deviations. The former 0.002 put it at 5.4: at 1000 rpm
#: 4-5 of 100 healthy sweeps drifted inside the ranges were called damage on the truth and the fine mesh (stated 1 %)
POLE_SENSITIVITY_ERROR = 0.006
#: the same for a residue's relative sensitivity d ln(R) / d theta (a mode shape at the channel)
RESIDUE_SENSITIVITY_ERROR = 0.01
#: the fit's residual norm relative to the healthy FRF's above which the anchor is refused (the model's modes do not
#: describe the data: x and y probes on a rotor whose model is isotropic and whose truth is not, 1.09; the bundled
#: samples' single probe at 0, 1000 and 2000 rpm: 0.0008-0.004; bearing dampers at 1000 rpm: 0.012)
MAX_MISFIT = 0.05
#: a channel pair whose model receptance is below this fraction of the largest pair's is silent (as
#: :data:`rotorcheck.signatures.SILENT`)
SILENT = 1e-9
#: a fitted pole that moved more than this (relative) from the model's is no fit: that mode stays the model's
MAX_POLE_MOVE = 0.05
#: a fit leaving more than this of the data is tried again with close pairs of poles split (:func:`_fit_split`):
#: the bundled samples' fits leave 4e-5 to 0.004
SPLIT_MISFIT = 0.002
#: poles this close (relative) are a pair (forward and backward whirl of one bending mode) ...
CLOSE_PAIR = 0.01
#: ... and are started split by these relative spreads
SPLIT_STARTS = (0.005, 0.01, 0.02)


@dataclass(frozen=True)
class FEModes:
    """The FE model's modes seen from channel pairs: ``poles`` (m,) rad/s (upper half plane; a real pole
    once), ``residues`` (m, P) m/N s^-1 per channel pair, ``real`` (m,) bool: a real pole (one term)."""

    poles: np.ndarray
    residues: np.ndarray
    real: np.ndarray
    plane: np.ndarray | None = None  # (m,) int: the uncoupled DOF set the mode lives on (None: one set)

    def planes(self) -> np.ndarray:
        """(m,) int: :attr:`plane`, zeros when the system is one coupled set."""
        return np.zeros(self.poles.size, dtype=int) if self.plane is None else self.plane


def fe_modes(system: MechanicalSystem, speed_rpm: float, dofs: Sequence[tuple[int, int]]) -> FEModes:
    """Every mode of ``system`` at ``speed_rpm`` and its residue at each (input DOF, output DOF) pair, from
    the first-order state matrix with left and right eigenvectors (``H(s) = sum_r R_r / (s - lambda_r)``).
    Where no matrix couples two DOF sets (the bending planes of a rotor that does not spin) each set's modes
    are its own (:attr:`FEModes.plane`): the x and y modes of an isotropic rotor share a pole but not a pair."""
    M, C, G, K = system.matrices(speed_rpm)
    D = C + speed_rpm * RPM_TO_RAD_S * G
    blocks = coupled_blocks([M, D, K])
    if len(blocks) > 1:
        parts = []
        for i, d in enumerate(blocks):
            cut = np.ix_(d, d)
            where = {int(g): k for k, g in enumerate(d)}
            inside = [k for k, (a, b) in enumerate(dofs) if a in where and b in where]
            sub = _modes(M[cut], D[cut], K[cut], [(where[a], where[b]) for a, b in (dofs[k] for k in inside)])
            res = np.zeros((sub.poles.size, len(dofs)), dtype=complex)
            res[:, inside] = sub.residues
            parts.append((sub, res, np.full(sub.poles.size, i)))
        return FEModes(np.concatenate([x.poles for x, _, _ in parts]), np.concatenate([r for _, r, _ in parts]),
                       np.concatenate([x.real for x, _, _ in parts]), np.concatenate([k for _, _, k in parts]))
    return _modes(M, D, K, dofs)


def _modes(M: np.ndarray, D: np.ndarray, K: np.ndarray, dofs: Sequence[tuple[int, int]]) -> FEModes:
    """:func:`fe_modes` of the second-order system ``M, D, K`` (n, n) for the (input, output) DOF pairs."""
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])
    lam, wl, vr = linalg.eig(A, left=True, right=True)
    scale = np.einsum("ij,ij->j", wl.conj(), vr)
    B = np.zeros((2 * n, len(dofs)))
    out = np.array([o for _, o in dofs], dtype=int)
    for k, (i, _) in enumerate(dofs):
        B[n:, k] = Minv[:, i]
    res = vr[out, :].T * (wl.conj().T @ B) / scale[:, None]  # (2n, P)
    # a repeated eigenvalue's left and right eigenvectors are not bi-orthogonal member by member: its residue is
    # the block's, C V (W^H V)^-1 W^H B, given to its first member (the others 0; the pole is the same)
    done = np.zeros(lam.size, dtype=bool)
    for j in range(lam.size):
        if done[j]:
            continue
        members = np.flatnonzero(~done & (np.abs(lam - lam[j]) <= REPEATED * np.abs(lam[j])))
        done[members] = True
        if members.size > 1:
            V, W = vr[:, members], wl[:, members]
            block = V[out, :] @ np.linalg.solve(W.conj().T @ V, W.conj().T @ B)  # (P, P): rows outputs
            res[members] = 0.0
            res[members[0]] = np.diagonal(block)
    tol = 1e-9 * np.maximum(np.abs(lam), 1e-300)
    real = np.abs(lam.imag) <= tol
    keep = (lam.imag > tol) | real
    return FEModes(lam[keep], res[keep], real[keep])


def modal_frf(poles: np.ndarray, residues: np.ndarray, real: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``sum_r R_r / (j w - lambda_r) + conj`` (a real pole once) at ``omega`` (f,) rad/s: (f, P) m/N."""
    jw = 1j * np.asarray(omega, dtype=float)[:, None]
    lam = np.asarray(poles)[None, :]
    direct = 1.0 / (jw - lam)  # (f, m)
    mirror = np.where(np.asarray(real)[None, :], 0.0, 1.0 / (jw - lam.conj()))
    R = np.asarray(residues)
    return direct @ R + mirror @ R.conj()


def _merged(modes: FEModes, index: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The modes of ``index`` with repeated poles (:data:`REPEATED`) of one plane merged: (poles, residues summed,
    members (m,) int: which merged mode each of ``index`` joined)."""
    poles: list[complex] = []
    res: list[np.ndarray] = []
    plane: list[int] = []
    where = modes.planes()
    member = np.empty(index.size, dtype=int)
    for k, i in enumerate(index):
        lam = modes.poles[i]
        j = next((j for j, p in enumerate(poles) if abs(p - lam) <= REPEATED * abs(lam) and plane[j] == where[i]),
                 None)
        if j is None:
            poles.append(complex(lam))
            res.append(modes.residues[i].copy())
            plane.append(int(where[i]))
            member[k] = len(poles) - 1
        else:
            res[j] = res[j] + modes.residues[i]
            member[k] = j
    return np.array(poles, dtype=complex), np.array(res, dtype=complex).reshape(len(poles), -1), member


@dataclass(frozen=True)
class ModalAnchor:
    """The healthy FRF's modal model: fitted ``poles`` (k,) rad/s and ``residues`` (k, P) of the modes the
    FE model has inside the band (``fe_poles`` (k,): the model's, merged where repeated), at ``omega`` (f,)
    rad/s; ``misfit``: the fit's residual norm relative to the healthy FRF's."""

    omega: np.ndarray
    poles: np.ndarray
    residues: np.ndarray
    fe_poles: np.ndarray
    fe_residues: np.ndarray
    fe: FEModes
    group: np.ndarray  # (m,) int: the fitted mode each FE mode (of ``fe``) stands for; -1: not fitted, the model's
    fe_out: np.ndarray  # (f, P) m/N: the FE modes not fitted, summed (:meth:`out_of_band` of ``fe``)
    misfit: float
    heard: np.ndarray  # (P,) bool: pairs the model says respond (x force -> y probe at rest: no); others change 0
    seen: np.ndarray | None = None  # (k, P) bool: the fitted modes each pair hears (None: every one)
    weighted: bool = False  # the pairs weighed by their noise in the fit (one plane per pair), else by their size

    def change(self, d_lnpole: np.ndarray, d_res: np.ndarray, d_out: np.ndarray) -> np.ndarray:
        """(f, P) m/N: the FRF change when each fitted pole moves by the relative ``d_lnpole`` (k,), each
        residue by ``d_res`` (k, P) m/N s^-1, and the rest by ``d_out`` (f, P) m/N (exact in the poles)."""
        real = np.zeros(self.poles.size, dtype=bool)
        # lambda^2 is what a stiffness moves to first order (a Rayleigh quotient): lambda sqrt(1 + 2 d ln lambda),
        # exact for a stiffness scaling every mode alike (E -2 %: 5e-5 of the pole closer than 1 + d ln lambda)
        moved = modal_frf(self.poles * np.sqrt(1.0 + 2.0 * d_lnpole), self.residues + d_res, real, self.omega)
        return (moved - modal_frf(self.poles, self.residues, real, self.omega) + d_out) * self.heard

    def derivative(self, d_lnpole: np.ndarray, d_res: np.ndarray, d_out: np.ndarray) -> np.ndarray:
        """(f, P): the first-order change per unit of a parameter with those sensitivities (m/N per unit)."""
        jw = 1j * self.omega[:, None]
        lam = self.poles[None, :]
        dlam = (self.poles * d_lnpole)[None, :]
        direct = dlam / (jw - lam) ** 2  # d/d lambda of 1 / (jw - lambda) times the pole's move
        mirror = dlam.conj() / (jw - lam.conj()) ** 2
        return ((1.0 / (jw - lam)) @ d_res + (1.0 / (jw - lam.conj())) @ d_res.conj()
                + direct @ self.residues + mirror @ self.residues.conj() + d_out) * self.heard

    def pole_directions(self) -> np.ndarray:
        """(2k, f, P) m/N: the FRF change per unit relative move of each fitted pole, ``lambda_r (1 + e)``, for
        real ``e`` (frequency and decay together) then imaginary ``e`` (a turn: damping), mode after mode."""
        jw = 1j * self.omega[:, None, None]
        lam = self.poles[None, :, None]
        R = self.residues[None, :, :]
        a = lam * R / (jw - lam) ** 2
        b = (lam * R).conj() / (jw - lam.conj()) ** 2
        out = np.concatenate([np.moveaxis(a + b, 1, 0), np.moveaxis(1j * a - 1j * b, 1, 0)])
        return np.asarray(out) * self.heard

    def residue_directions(self) -> np.ndarray:
        """(k, 2, f, P, P) m/N per unit (m/N s^-1) change of each fitted mode's residue at each pair, real then
        imaginary part: ``[k, c, :, :, q]`` is the FRF change (f, P) when pair ``q``'s residue moves."""
        jw = 1j * self.omega[:, None]
        lam = self.poles[None, :]
        a = 1.0 / (jw - lam) + 1.0 / (jw - lam.conj())  # (f, k)
        b = 1j / (jw - lam) - 1j / (jw - lam.conj())
        P = self.residues.shape[1]
        out = np.zeros((self.poles.size, 2, self.omega.size, P, P), dtype=complex)
        for q in np.flatnonzero(self.heard):
            out[:, 0, :, q, q] = a.T
            out[:, 1, :, q, q] = b.T
        return out

    def out_of_band(self, modes: FEModes, member: np.ndarray) -> np.ndarray:
        """(f, P) m/N: ``modes``' sum over the modes that follow no fitted one (``member`` (m,) int: the fitted mode
        each of ``modes`` follows, -1 for none)."""
        rest = member < 0
        return modal_frf(modes.poles[rest], modes.residues[rest], modes.real[rest], self.omega)


def fit_anchor(system: MechanicalSystem, speed_rpm: float, dofs: Sequence[tuple[int, int]], freq_hz: np.ndarray,
               healthy_frf: np.ndarray, healthy_var: np.ndarray | None = None) -> ModalAnchor | None:
    """Fit the healthy FRF ``healthy_frf`` (f, P) m/N at ``freq_hz`` with the modes the model has inside the
    band: poles by nonlinear least squares from the model's, residues and a residual term per pair (a
    constant and a 1 / w^2 line) linear; the model's other modes fixed. None when no mode of the model is
    visible inside the band, a pole would move more than :data:`MAX_POLE_MOVE` or the misfit exceeds
    :data:`MAX_MISFIT`. With ``healthy_var`` (f, P) m^2/N^2, the variance of the healthy FRF at each point, the
    pairs weigh by their signal to noise (each scaled by its rms noise, not its largest value) and the misfit is
    what the fit leaves beyond that noise (:func:`_fit`): a quiet pair's noise is no model error. That holds for
    one pair and for pairs of uncoupled planes (at rest); several pairs of a spinning rotor keep the plain misfit."""
    f = np.asarray(freq_hz, dtype=float)
    w = 2.0 * np.pi * f
    T = np.asarray(healthy_frf, dtype=complex).reshape(f.size, len(dofs))
    fe = fe_modes(system, speed_rpm, dofs)
    fr = fe.poles.imag / (2.0 * np.pi)
    peak = np.max(np.abs(fe.residues), axis=1) / np.maximum(np.abs(fe.poles.real), 1e-12 * np.abs(fe.poles))
    inside = (fr >= 0.98 * f.min()) & (fr <= 1.02 * f.max()) & ~fe.real
    visible = inside & (peak > VISIBLE_PEAK * (peak[inside].max() if np.any(inside) else 0.0))
    # a repeated pole (x and y of an isotropic rotor) is one mode: all its members or none (its residues add)
    plane = fe.planes()
    for i in np.flatnonzero(visible):
        visible |= inside & (np.abs(fe.poles - fe.poles[i]) <= REPEATED * np.abs(fe.poles[i])) & (plane == plane[i])
    if not np.any(visible) or f.size < 8:
        return None
    idx = np.flatnonzero(visible)
    lam0, r0, member = _merged(fe, idx)
    group = np.full(fe.poles.size, -1, dtype=int)
    group[idx] = member
    g = modal_frf(fe.poles, fe.residues, fe.real, w)
    heard = np.max(np.abs(g), axis=0) > SILENT * np.max(np.abs(g))
    T = T * heard  # a pair the model says is silent is fitted as none (its data are noise)
    # the misfit judged beyond the noise where each pair's modes are one plane's (one pair, or the planes apart at
    # rest); several pairs on a spinning rotor keep the plain misfit: there the isotropic model's circular whirl
    # modes stand for the machine's elliptical ones, whose residue sensitivities across x and y pairs it does not
    # know (measured: accepted, the x/y anchor at 1000 rpm missed 5 of 9 breathing cracks of 20-50 % depth that
    # the re-solved model finds on three truths, bench.diagnosis --quick)
    planar = len(dofs) == 1 or len(set(plane.tolist())) > 1
    noise = (None if healthy_var is None or not planar else
             np.asarray(healthy_var, dtype=float).reshape(f.size, len(dofs)) * heard)
    rest = ~visible
    fe_out = modal_frf(fe.poles[rest], fe.residues[rest], fe.real[rest], w)
    # a mode the model says a pair does not hear (a y-plane mode at an x probe, at rest) gets no residue there
    seen = np.abs(r0) > SILENT * np.maximum(np.max(np.abs(r0), axis=0, keepdims=True), 1e-300)
    pinned = np.zeros(lam0.size, dtype=bool)
    for _ in range(lam0.size):
        lam, R, misfit, moved = _fit_split(lam0, fe_out, w, T, pinned, seen, noise)
        if not np.any(moved & ~pinned):
            if misfit > MAX_MISFIT:
                return None
            return ModalAnchor(w, lam, R * heard, lam0, r0 * heard, fe, group, fe_out, misfit, heard, seen,
                               noise is not None)
        # a mode the data do not pin (a y mode seen by an x probe) would wander off: its pole stays the model's,
        # its residue the data's
        pinned |= moved
    return None


def _fit_split(lam0: np.ndarray, fe_out: np.ndarray, w: np.ndarray, T: np.ndarray, pinned: np.ndarray,
               seen: np.ndarray | None = None, noise: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """:func:`_fit` from the model's poles, and when that leaves more than :data:`SPLIT_MISFIT` of the data,
    from starts that split each close pair of free poles (forward and backward whirl, within
    :data:`CLOSE_PAIR` of each other) symmetrically by each of :data:`SPLIT_STARTS`: started together, a pair
    stays together (the misfit is symmetric in the two), while the machine's may be split further (anisotropic
    supports; on the bearing-damper truth at 1000 rpm 54.39 / 54.96 Hz, the model's 3.5e-4 apart); the best."""
    best = _fit(lam0, fe_out, w, T, pinned, seen=seen, noise=noise)
    if best[2] <= SPLIT_MISFIT:
        return best
    free = np.flatnonzero(~pinned)
    pairs = [(int(i), int(j)) for a, i in enumerate(free) for j in free[a + 1:]
             if abs(lam0[i] - lam0[j]) <= CLOSE_PAIR * abs(lam0[i])]
    if not pairs:
        return best
    for spread in SPLIT_STARTS:
        start = lam0.copy()
        for i, j in pairs:
            lo_i = lam0[i].imag <= lam0[j].imag
            start[i] = lam0[i].real + 1j * lam0[i].imag * (1.0 - (0.5 if lo_i else -0.5) * spread)
            start[j] = lam0[j].real + 1j * lam0[j].imag * (1.0 + (0.5 if lo_i else -0.5) * spread)
        trial = _fit(lam0, fe_out, w, T, pinned, start, seen, noise)
        if trial[2] < best[2]:
            best = trial
    return best


def _pair_scale(target: np.ndarray, noise: np.ndarray | None) -> np.ndarray:
    """(P,): each pair's unit in a fit: its largest value (pairs weigh alike), or with ``noise`` (f, P) m^2/N^2 its
    rms noise (pairs weigh by their signal to noise)."""
    scale = np.maximum(np.max(np.abs(target), axis=0), 1e-300)
    if noise is not None:
        rms = np.sqrt(np.mean(noise, axis=0))
        scale = np.where(rms > 0, rms, scale)
    return np.asarray(scale)


def _project(lam: np.ndarray, w: np.ndarray, target: np.ndarray, scale: np.ndarray, use: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """The linear part of a modal fit with poles ``lam`` (k,): ``(coef, residual)``, the residues (real then
    imaginary rows) and a constant and a 1 / w^2 term per pair (columns) fitted by least squares to ``target``
    (f, P) / ``scale`` (P,), each pair with the modes ``use`` (k, P) bool says it hears; the residual [Re; Im]
    flattened."""
    m = lam.size
    jw = 1j * w[:, None]
    a = 1.0 / (jw - lam) + 1.0 / (jw - lam.conj())
    b = 1j / (jw - lam) - 1j / (jw - lam.conj())
    basis = np.column_stack([a, b, np.ones_like(w), 1.0 / w**2])
    A = np.vstack([basis.real, basis.imag])
    Y = np.vstack([(target / scale).real, (target / scale).imag])
    if np.all(use):
        coef = np.linalg.lstsq(A, Y, rcond=None)[0]
    else:  # pair by pair with the modes it hears: one solve per set of modes (the pairs that hear the same)
        coef = np.zeros((A.shape[1], Y.shape[1]))
        seen, group = np.unique(use.T, axis=0, return_inverse=True)
        for k, heard in enumerate(seen):
            q = np.flatnonzero(group.reshape(-1) == k)
            cols = np.r_[np.flatnonzero(heard), np.flatnonzero(heard) + m, 2 * m, 2 * m + 1]
            coef[np.ix_(cols, q)] = np.linalg.lstsq(A[:, cols], Y[:, q], rcond=None)[0]
    return coef, (Y - A @ coef).ravel()


def _fit(lam0: np.ndarray, fe_out: np.ndarray, w: np.ndarray, T: np.ndarray, pinned: np.ndarray,
         start: np.ndarray | None = None, seen: np.ndarray | None = None, noise: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """One fit of :func:`fit_anchor`: poles from ``start`` (default the model's ``lam0`` (k,, merged), around
    which they are bounded), those of ``pinned`` held at the model's, the model's other modes ``fe_out`` (f, P)
    fixed; ``seen`` (k, P) bool the modes each pair hears (default all; the others' residues there are 0):
    (poles, residues, misfit, moved (k,) bool: a pole at its bound, :data:`MAX_POLE_MOVE` from the model's, or
    at no damping). The misfit: the residual's norm relative to the data's, each pair scaled to unit size (its
    largest value); with ``noise`` (f, P) m^2/N^2 each pair scaled by its rms noise instead and the residual's
    squared norm less what the noise leaves after the fit (its variance times the share of the real residuals the
    pair's linear coefficients do not absorb), floored at 0: the model's error, not the quiet pairs' noise."""
    m = lam0.size
    free = ~pinned
    target = T - fe_out
    use = np.ones((m, T.shape[1]), dtype=bool) if seen is None else np.asarray(seen, dtype=bool)
    scale = _pair_scale(target, noise)

    def poles(x: np.ndarray) -> np.ndarray:
        lam = lam0.copy()
        k = int(np.count_nonzero(free))
        lam[free] = x[:k] + 1j * x[k:]
        return lam

    def solve(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        lam = poles(x)
        coef, left = _project(lam, w, target, scale, use)
        return lam, coef, left

    lf = lam0[free]
    size = np.abs(lf)
    # each pole kept near its own (frequency within MAX_POLE_MOVE, damping ratio below 0.3): modes cannot swap
    lo = np.concatenate([-0.3 * size, lf.imag * (1.0 - MAX_POLE_MOVE)])
    hi = np.concatenate([-1e-6 * size, lf.imag * (1.0 + MAX_POLE_MOVE)])
    sf = (lam0 if start is None else start)[free]
    x0 = np.clip(np.concatenate([sf.real, sf.imag]), lo, hi)
    moved = np.zeros(m, dtype=bool)
    if x0.size:
        fit = optimize.least_squares(lambda x: solve(x)[2], x0, x_scale=np.abs(x0) + 1.0, bounds=(lo, hi),
                                     method="trf", max_nfev=200)
        x = fit.x
        k = lf.size
        edge = 1e-3 * MAX_POLE_MOVE * lf.imag
        moved[free] = (x[k:] <= lo[k:] + edge) | (x[k:] >= hi[k:] - edge) | (x[:k] >= hi[:k] * 0.999)
    else:
        x = x0
    lam, coef, left = solve(x)
    R = (coef[:m] + 1j * coef[m:2 * m]) * scale
    size_T = float(np.linalg.norm(np.vstack([(T / scale).real, (T / scale).imag])))
    left2 = float(left @ left)
    if noise is not None:
        # the noise's expected share of the residual: its variance (both parts) scaled as the data, times the real
        # residuals' share the pair's linear coefficients (residues of the modes it hears, two residual terms) leave
        n_real = 2 * w.size
        kept = np.maximum(0.0, 1.0 - (2 * use.sum(axis=0) + 2) / n_real)
        share = np.divide(np.sum(noise, axis=0), scale**2, out=np.zeros(scale.size), where=scale > 1e-150)
        left2 = max(0.0, left2 - float(np.sum(share * kept)))
    misfit = float(np.sqrt(left2)) / size_T if size_T > 0 else 0.0
    return lam, R, misfit, moved


@dataclass(frozen=True)
class PoleRefit:
    """Another sweep's poles of an anchor's modes (:func:`refit_poles`): ``poles`` (k,) rad/s, ``shift`` (k,) the
    relative change of ``|lambda|^2`` from the anchor's (a stiffness moves it linearly to first order) and its
    standard error ``se_shift`` (both sweeps' fits), the fit's ``misfit`` (as :attr:`ModalAnchor.misfit`) and
    ``moved`` (k,) the poles at a bound of the fit (not pinned by the data)."""

    poles: np.ndarray
    shift: np.ndarray
    se_shift: np.ndarray
    misfit: float
    moved: np.ndarray

    @property
    def ok(self) -> bool:
        """The fit describes the sweep: misfit at most :data:`MAX_MISFIT` and no pole at a bound."""
        return bool(self.misfit <= MAX_MISFIT and not np.any(self.moved) and np.all(np.isfinite(self.se_shift)))


def _shift_se(lam: np.ndarray, w: np.ndarray, target: np.ndarray, noise: np.ndarray | None, use: np.ndarray
              ) -> np.ndarray:
    """(k,): the standard error of each fitted pole's ``|lambda|^2`` relative to itself, from the fit's Jacobian
    (central differences in the poles' real and imaginary parts, the residues projected out) and the residual's
    variance per degree of freedom (at least the noise's, 1/2 per real part, where ``noise`` scales the pairs)."""
    scale = _pair_scale(target, noise)
    k = lam.size
    x0 = np.r_[lam.real, lam.imag]
    r0 = _project(lam, w, target, scale, use)[1]
    h = 1e-6 * np.r_[np.abs(lam), np.abs(lam)]
    J = np.empty((r0.size, 2 * k))
    for i in range(2 * k):
        xp, xm = x0.copy(), x0.copy()
        xp[i] += h[i]
        xm[i] -= h[i]
        rp = _project(xp[:k] + 1j * xp[k:], w, target, scale, use)[1]
        rm = _project(xm[:k] + 1j * xm[k:], w, target, scale, use)[1]
        J[:, i] = (rp - rm) / (2.0 * h[i])
    n_lin = 2 * int(use.sum()) + 2 * target.shape[1]
    dof = max(r0.size - n_lin - 2 * k, 1)
    s2 = max(float(r0 @ r0) / dof, 0.5 if noise is not None else 0.0)
    cov = s2 * np.linalg.pinv(J.T @ J)
    out = np.empty(k)
    for r in range(k):  # d(|lambda|^2) / |lambda|^2 = 2 (Re dRe + Im dIm) / |lambda|^2
        g = np.zeros(2 * k)
        g[r], g[k + r] = 2.0 * lam[r].real / abs(lam[r]) ** 2, 2.0 * lam[r].imag / abs(lam[r]) ** 2
        out[r] = float(np.sqrt(max(g @ cov @ g, 0.0)))
    return out


def refit_poles(anchor: ModalAnchor, frf: np.ndarray, var: np.ndarray | None, healthy_frf: np.ndarray,
                healthy_var: np.ndarray | None, start: np.ndarray | None = None) -> PoleRefit:
    """The poles of the anchor's modes in another sweep ``frf`` (f, P) m/N (variance ``var``), fitted as the anchor
    was (:func:`fit_anchor`: residues and residual terms linear, the model's other modes fixed) from ``start`` (k,)
    rad/s (default the anchor's poles; each pole bounded within :data:`MAX_POLE_MOVE` of its start), with the
    standard error of each shift from both fits (``healthy_frf``, ``healthy_var``: the sweep the anchor was fitted
    to)."""
    w = anchor.omega
    P = anchor.heard.size
    T = np.asarray(frf, dtype=complex).reshape(w.size, P) * anchor.heard
    Th = np.asarray(healthy_frf, dtype=complex).reshape(w.size, P) * anchor.heard
    use = (np.ones((anchor.poles.size, P), dtype=bool) if anchor.seen is None else anchor.seen)

    def noise_of(v: np.ndarray | None) -> np.ndarray | None:
        if v is None or not anchor.weighted:
            return None
        return np.asarray(v, dtype=float).reshape(w.size, P) * anchor.heard

    noise, noise_h = noise_of(var), noise_of(healthy_var)
    lam0 = anchor.poles if start is None else np.asarray(start, dtype=complex)
    lam, _, misfit, moved = _fit_split(lam0, anchor.fe_out, w, T, np.zeros(lam0.size, dtype=bool), use, noise)
    shift = np.abs(lam) ** 2 / np.abs(anchor.poles) ** 2 - 1.0
    se = np.hypot(_shift_se(lam, w, T - anchor.fe_out, noise, use),
                  _shift_se(anchor.poles, w, Th - anchor.fe_out, noise_h, use))
    return PoleRefit(lam, shift, se, misfit, moved)


@dataclass(frozen=True)
class ModalSensitivity:
    """What a unit of one parameter does in the anchor's terms: relative pole shift (k,), residue change
    (k, P) m/N s^-1, the change of the model's other modes (f, P) m/N, all per unit of the parameter."""

    d_lnpole: np.ndarray
    d_res: np.ndarray
    d_out: np.ndarray


def sensitivity(anchor: ModalAnchor, changed: FEModes, step: float) -> ModalSensitivity | None:
    """The sensitivity of the anchor's modes to a parameter whose change by ``step`` gives the model's
    ``changed`` modes (same channel pairs): each changed mode follows one of the model's, one to one. None
    when a fitted mode has no follower (the change is too large to track)."""
    base = anchor.fe
    # one to one, the least total move (close modes, 172.72 and 172.78 Hz at 1000 rpm, must not both follow one)
    dist = np.abs(changed.poles[:, None] - base.poles[None, :])
    # a mode follows one of its own plane (x and y modes of an isotropic rotor at rest share their poles)
    dist = np.where(changed.planes()[:, None] == base.planes()[None, :], dist, 1e6 * (dist.max() + 1.0))
    rows, cols = optimize.linear_sum_assignment(dist)
    near = np.full(changed.poles.size, -1, dtype=int)
    near[rows] = cols
    follows = np.where(near >= 0, anchor.group[np.maximum(near, 0)], -1)
    k = anchor.poles.size
    lam1 = np.zeros(k, dtype=complex)
    r1 = np.zeros_like(anchor.fe_residues)
    for j in range(k):
        mine = follows == j
        if not np.any(mine):
            return None
        wgt = np.max(np.abs(changed.residues[mine]), axis=1) + 1e-300
        lam1[j] = np.sum(changed.poles[mine] * wgt) / np.sum(wgt)
        r1[j] = np.sum(changed.residues[mine], axis=0)
    d_out = anchor.out_of_band(changed, follows) - anchor.fe_out
    return ModalSensitivity((lam1 / anchor.fe_poles - 1.0) / step, (r1 - anchor.fe_residues) / step, d_out / step)
