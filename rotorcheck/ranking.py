"""Which element: every candidate shaft element ranked by how well a local stiffness loss there explains the
new sweep (the one ranking that ``detect``'s diagnosis and ``locate`` both report).

The data: the new sweep's FRF against the healthy one at every point and channel pair, with the model's
error bounds of the location (:class:`SweepChange`; the same figures :mod:`rotorcheck.location` certifies
with). Per candidate element ``e`` the hypothesis "a loss ``a`` in ``[0, MAX_LOSS]`` of ``e``'s bending
stiffness, benign parameters ``theta`` in their box and a gain ``g`` in its range" is fitted by bounded
nonlinear least squares at the fit points (:data:`N_FIT_TOP` frequencies of the largest whitened change
and :data:`N_FIT_SPREAD` spread over the band, every trusted pair there); each residual is

    r = (T_new - g T_h G(theta, a) / G(0)) / sd,   sd^2 = var_new + var_h + A^2 + (eps |T_h| |g rho - 1|)^2

(``rho = G / G(0)``, ``A`` and ``eps`` the model's error bounds of the location, as standard deviations).
``chi2_e`` is the sum of ``|r|^2`` at the optimum; the relative likelihood of ``e`` is
``exp(-chi2_e / 2)`` normalised over the candidates (equal prior per element). The benign-only fit
(``a = 0``) is reported beside them. The Jacobian is analytic: ``dG/dtheta_i = -y^T A_i(w) x`` with
``x = Z^-1 b`` and ``y = Z^-T c`` (one batched solve per evaluation, two when Z is not symmetric).
Starts: the loss at the best of a scan (:data:`LOSS_SCAN`, benign parameters at the box centre), and at
the best scan value elsewhere when it is a separate local minimum (a loss moves resonances: the misfit
has more than one valley).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck.config import Crack, RigConfig
from rotorcheck.faults.crack import crack_stiffness
from rotorcheck.fe.assembly import build_system
from rotorcheck.modal_anchor import ModalAnchor
from rotorcheck.nominal import ChannelPair
from rotorcheck.progress import Progress, report
from rotorcheck.robust.affine import AffineModel, AffineParameter
from rotorcheck.robust.joint import linearized_se
from rotorcheck.robust.measured import io_model_error
from rotorcheck.sizing import POLE_SHIFTS, POLE_SIZE_RULE, model_poles, size_from_poles

#: assumed bound on the model's error in the predicted change at a point, relative to that change: the
#: nominal model's crack shapes agree with the truth rig's to a cosine of 0.987-0.990 (limits.md 1), an
#: error of 14-16 % of the change
CRACK_MODEL_ERROR = 0.2
#: and relative to the largest benign change the ranges allow there (the envelope): the nominal model
#: predicts a benign change to 40-60 % (limits.md 4)
BENIGN_MODEL_ERROR = 0.6
#: points are used only where the model's receptance errs on the healthy data by at most this much
#: (relative, the largest over +-HALFWIDTH points): near a resonance the model misplaces, its predicted
#: change is wrong by more than the change (on the crack rig: 30-97 % at 500-517 Hz)
MAX_MODEL_ERROR, HALFWIDTH = 0.3, 5
#: breathing hypothesis: a point is not used when a sideband f +- Omega or f +- 2 Omega lies within this
#: relative distance of a natural frequency: the revolution average leaves out the crack's parametric
#: coupling through the sidebands, which is large there (on the crack rig a 50 % deep crack's first mode
#: at 50 Hz moves the response at 33 and 67 Hz by more than the mean stiffness predicts)
SIDEBAND_GUARD = 0.08
#: the largest severity searched (stiffness loss of the element, fraction)
MAX_LOSS = 0.8
#: fit frequencies: the largest whitened changes (largest over the pairs) and as many spread over the band
N_FIT_TOP, N_FIT_SPREAD = 32, 32
#: losses scanned for the fit's starts (fraction)
LOSS_SCAN = (0.0, 0.03, 0.07, 0.12, 0.2, 0.3, 0.42, 0.55, 0.68, 0.8)
#: least-squares evaluations per start
MAX_NFEV = 25
#: what an estimate's interval rests on when the poles do not size it (:attr:`ElementFit.size_basis`)
FRF_FIT = "FRF fit"
#: the estimate's interval: confidence of the profile-likelihood interval of the best ranked elements' loss,
#: and the width (fraction) to which its ends are found
INTERVAL_LEVEL, INTERVAL_TOL = 0.95, 0.005



@dataclass(frozen=True)
class SweepChange:
    """The new sweep against the healthy one at every frequency and channel pair (arrays (f, P)), as the
    ranking and the certificates read it: FRFs (m/N) and the variances of their means (m^2/N^2), the
    benign error bound ``a`` (m/N, :data:`BENIGN_MODEL_ERROR` of the envelope), the model's relative error
    on the healthy FRF ``err``, the model's receptances at no change ``g_zero``, the points ``trusted``
    (model error at most :data:`MAX_MODEL_ERROR`, off the sidebands' resonances when rotating) and the
    whitened change ``change2``; ``B``, ``Cm`` (n, P) each pair's input and output."""

    freq_hz: np.ndarray
    speed_rpm: float
    hypothesis: str  # "open" (standstill) | "breathing" (rotating)
    t_new: np.ndarray
    var_new: np.ndarray
    t_h: np.ndarray
    var_h: np.ndarray
    a: np.ndarray
    err: np.ndarray
    g_zero: np.ndarray
    trusted: np.ndarray
    change2: np.ndarray
    B: np.ndarray
    Cm: np.ndarray
    gain: tuple[float, float]
    anchor: ModalAnchor | None = None  # the healthy sweep's modal fit (standstill): sizes by the pole shifts

    @property
    def omega(self) -> np.ndarray:
        return 2.0 * np.pi * self.freq_hz

    @property
    def n_pairs(self) -> int:
        return int(self.t_new.shape[1])


def natural_frequencies_hz(model: AffineModel) -> np.ndarray:
    """The undamped-equivalent natural frequencies |lambda| / 2 pi (Hz) of ``model`` at its parameters'
    zero (state space of M, D, K; each conjugate pair once)."""
    return np.sort(np.abs(model_poles(model, np.zeros(len(model.parameters))))) / (2.0 * np.pi)


def _near_sideband(model: AffineModel, freq_hz: np.ndarray, speed_rpm: float) -> np.ndarray:
    """(f,) bool: a sideband f +- Omega, f +- 2 Omega within :data:`SIDEBAND_GUARD` of a natural frequency."""
    fn = natural_frequencies_hz(model)
    spin = abs(speed_rpm) / 60.0
    out = np.zeros(np.asarray(freq_hz).size, dtype=bool)
    for k in (-2, -1, 1, 2):
        side = np.abs(np.asarray(freq_hz, dtype=float) + k * spin)
        out |= np.any(np.abs(side[:, None] - fn[None, :]) <= SIDEBAND_GUARD * fn[None, :], axis=1)
    return out


def receptances(model: AffineModel, omega: np.ndarray, theta: np.ndarray, B: np.ndarray, Cm: np.ndarray
                ) -> np.ndarray:
    """(f, P) receptances ``c_j^T Z(w, theta)^-1 b_j`` of each pair j (columns of B, Cm), batched over w."""
    Z = model.stiffness_stack(omega, theta)
    X = Z.solve(B)
    return np.einsum("nj,fnj->fj", Cm, X)


def sweep_change(box: Any, pairs: Sequence[ChannelPair], freq_hz: np.ndarray, speed_rpm: float, t_new: np.ndarray,
                 var_new: np.ndarray, t_healthy: np.ndarray, var_healthy: np.ndarray, benign_envelope: np.ndarray,
                 exclude: np.ndarray | None = None, anchor: ModalAnchor | None = None) -> SweepChange:
    """The :class:`SweepChange` of a new sweep: ``box`` the benign parameters
    (:class:`rotorcheck.signatures.BenignBox`, its model at ``speed_rpm``), ``t_*``, ``var_*`` (f, P) one
    column per pair of ``pairs``, ``benign_envelope`` (P f,) m/N the largest benign change the ranges
    allow at each point; ``exclude`` (f,) bool points never used (on a shaft harmonic); ``anchor`` the healthy
    sweep's modal fit (:mod:`rotorcheck.modal_anchor`; at standstill the best ranked loss is sized by the pole
    shifts, :mod:`rotorcheck.sizing`)."""
    f = np.asarray(freq_hz, dtype=float)
    nf, n_pairs = np.asarray(t_new).reshape(f.size, -1).shape
    t_new, var_new, t_h, var_h = (np.asarray(x).reshape(nf, n_pairs) for x in (t_new, var_new, t_healthy,
                                                                                 var_healthy))
    a = BENIGN_MODEL_ERROR * np.asarray(benign_envelope, dtype=float).reshape(n_pairs, nf).T
    hypothesis = "breathing" if speed_rpm != 0.0 else "open"
    views = [box.for_pair(p) if n_pairs > 1 else box for p in pairs]
    B = np.stack([v.model.b for v in views], axis=1)
    Cm = np.stack([v.model.c for v in views], axis=1)
    g_zero = receptances(box.model, 2.0 * np.pi * f, np.zeros(len(box.model.parameters)), B, Cm)
    err = np.stack([io_model_error(g_zero[:, j], t_h[:, j], HALFWIDTH) for j in range(n_pairs)], axis=1)
    change2 = np.abs(t_new - t_h) ** 2 / (var_new + var_h + a**2)
    trusted = err <= MAX_MODEL_ERROR
    if hypothesis == "breathing":
        trusted &= ~_near_sideband(box.model, f, speed_rpm)[:, None]
    if exclude is not None:
        trusted &= ~np.asarray(exclude, dtype=bool).reshape(nf, 1)
    return SweepChange(f, float(speed_rpm), hypothesis, t_new, var_new, t_h, var_h, a, err, g_zero, trusted,
                       change2, B, Cm, (float(box.gain[0]), float(box.gain[1])),
                       anchor if hypothesis == "open" else None)


def section_length(config: RigConfig, element: int, given: float | None = None) -> float:
    """The breathing crack's section length ``l`` of eq. 5.25 (m): ``given``, else the rig's own breathing
    crack's, else the element's outer diameter (the usual estimate of the zone a crack weakens)."""
    if given is not None:
        return float(given)
    own = next((f for f in config.faults.values() if isinstance(f, Crack) and f.model == "mayes_davies"
                and f.section_length is not None), None)
    if own is not None and own.section_length is not None:
        return float(own.section_length)
    return float(next(e for e in config.shaft if e.start == element).outer_diameter)


def breathing_crack(config: RigConfig, element: int, depth: float, length: float | None = None) -> Crack:
    """A Mayes-Davies crack ``depth`` (fraction of the diameter) deep in ``element`` (section length by
    :func:`section_length`; Poisson ratio the rig's crack's, else the material's)."""
    own = next((f for f in config.faults.values() if isinstance(f, Crack) and f.model == "mayes_davies"), None)
    return Crack(element=element, model="mayes_davies", depth=depth,
                 section_length=section_length(config, element, length),
                 poisson=None if own is None else own.poisson)


def _loss_shape(config: RigConfig, sys0: Any, element: int, speed_rpm: float, hypothesis: str
                ) -> tuple[np.ndarray, np.ndarray | None]:
    """``(A_K, A_D)``: the change of K (and of C where damping follows K affinely) per unit loss of
    ``element`` (N/m per 1), to be subtracted; A_D None where the damping is held (modal damping);
    ``sys0`` the assembled ``config``."""
    _, C0, _, K0 = sys0.matrices(speed_rpm)
    if hypothesis == "breathing":
        ck = crack_stiffness(sys0, breathing_crack(config, element, 0.25))
        s_ref = 0.25 * (ck.delta_xi + ck.delta_eta)
        return ck.scatter(ck.mean(), sys0.n_dof) / s_ref, None
    _, C1, _, K1 = build_system(config, modulus_factors={element: 0.5}).matrices(speed_rpm)
    _, Cq, _, _ = build_system(config, modulus_factors={element: 0.75}).matrices(speed_rpm)
    dC = (C0 - C1) / 0.5
    affine = np.allclose(0.5 * (C0 + C1), Cq, rtol=0.0, atol=1e-9 * max(np.abs(C0).max(), 1e-300))
    return (K0 - K1) / 0.5, (dC if affine and np.abs(dC).max() > 0 else None)


def loss_model(config: RigConfig, box: Any, element: int, speed_rpm: float, hypothesis: str) -> AffineModel:
    """The box's model with one more parameter: the loss of ``element`` in ``[0, MAX_LOSS]`` (last)."""
    A_K, A_D = _loss_shape(config, box.system, element, speed_rpm, hypothesis)
    terms: tuple[tuple[str, np.ndarray], ...] = (("K", -A_K),) + ((("D", -A_D),) if A_D is not None else ())
    return AffineModel(box.model.M, box.model.D, box.model.K, box.model.b, box.model.c,
                       (*box.model.parameters, AffineParameter(f"loss_{element}", terms, 0.0, MAX_LOSS)))


def fit_frequencies(change: SweepChange, n_top: int = N_FIT_TOP, n_spread: int = N_FIT_SPREAD) -> np.ndarray:
    """Indices of the fit frequencies: the ``n_top`` largest whitened changes (largest over the trusted
    pairs) and ``n_spread`` more spread evenly over the rest."""
    return fit_indices(change.change2, change.trusted, n_top, n_spread)


def fit_indices(change2: np.ndarray, trusted: np.ndarray, n_top: int = N_FIT_TOP, n_spread: int = N_FIT_SPREAD
                ) -> np.ndarray:
    """:func:`fit_frequencies` of a whitened change ``change2`` (f, P) trusted at ``trusted`` (f, P) bool (a
    predicted change too: :mod:`rotorcheck.sensor_advice`)."""
    c = np.where(trusted, change2, -np.inf).max(axis=1)
    ok = np.flatnonzero(np.isfinite(c))
    top = ok[np.argsort(c[ok])[::-1][:n_top]]
    rest = np.setdiff1d(ok, top)
    spread = rest[np.linspace(0, rest.size - 1, min(n_spread, rest.size)).round().astype(int)] if rest.size else rest
    return np.unique(np.r_[top, spread])


class _Fit:
    """The whitened residual and its analytic Jacobian of one loss model at the fit frequencies."""

    def __init__(self, model: AffineModel, change: SweepChange, idx: np.ndarray) -> None:
        self.model = model
        self.w = change.omega[idx]
        ch = change
        self.used = ch.trusted[idx]
        self.t_new, self.t_h, self.g0 = ch.t_new[idx], ch.t_h[idx], ch.g_zero[idx]
        self.var = ch.var_new[idx] + ch.var_h[idx] + ch.a[idx] ** 2
        self.rel2 = ((CRACK_MODEL_ERROR + ch.err[idx]) * np.abs(self.t_h)) ** 2
        # distinct inputs and outputs: one solve per input (and output, when Z is not symmetric)
        self.Bu, self.in_idx = np.unique(ch.B, axis=1, return_inverse=True)
        self.Cu, self.out_idx = np.unique(ch.Cm, axis=1, return_inverse=True)
        self.in_idx, self.out_idx = self.in_idx.reshape(-1), self.out_idx.reshape(-1)
        self.p = len(model.parameters)
        self._cache: tuple[bytes, np.ndarray, np.ndarray] | None = None

    def receptances(self, theta: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """``(G (k, P), dG/dtheta (k, P, p) or None)`` at ``theta`` (p,)."""
        Z = self.model.stiffness_stack(self.w, theta)
        k = self.w.size
        if not jac:
            X = Z.solve(self.Bu)
            return np.einsum("nj,knj->kj", self.Cu[:, self.out_idx], X[:, :, self.in_idx]), None
        X, Y = self.model.solve_both(Z, self.Bu, self.Cu)
        G = np.einsum("nj,knj->kj", self.Cu[:, self.out_idx], X[:, :, self.in_idx])
        Yp = Y[:, :, self.out_idx]
        dG = np.zeros((k, G.shape[1], self.p), dtype=complex)
        s_of = {"K": np.ones(k), "D": 1j * self.w, "M": -(self.w**2)}
        for i, prm in enumerate(self.model.parameters):
            for kind, A in prm.terms:
                AX = np.matmul(A, X)[:, :, self.in_idx]  # (k, n, P)
                dG[:, :, i] -= s_of[kind][:, None] * np.einsum("knj,knj->kj", Yp, AX)
        return G, dG

    def evaluate(self, x: np.ndarray, jac: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """``(r, J)``: the used residuals [Re; Im] at ``x = (theta, gain)`` and their Jacobian (2u, p + 1);
        with ``x = (theta, gain, scale)`` the model's predicted change ``rho - 1`` is multiplied by ``scale``
        (a model-form error common to every point: :func:`profile_interval`), J then (2u, p + 2)."""
        G, dG = self.receptances(x[: self.p], jac)
        g = x[self.p]
        scaled = x.size > self.p + 1
        s = float(x[self.p + 1]) if scaled else 1.0
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rho = np.where(np.abs(self.g0) > 0, G / self.g0, 1.0)
            shape = 1.0 + s * (rho - 1.0)  # the predicted T / (gain T_h)
            u = g * shape - 1.0
            sd = np.sqrt(self.var + self.rel2 * np.abs(u) ** 2)
            r = (self.t_new - g * self.t_h * shape) / sd
        m = self.used
        res = np.r_[r[m].real, r[m].imag]
        if dG is None:
            return res, None
        g0, sd, u, r = self.g0[m][:, None], sd[m][:, None], u[m][:, None], r[m][:, None]
        # du/dx: g s dG/G(0) for theta, the shape for the gain, g (rho - 1) for the scale
        cols = [g * s * dG[m] / g0, shape[m][:, None]]
        if scaled:
            cols.append(g * (rho[m][:, None] - 1.0))
        du = np.concatenate(cols, axis=1)
        dsd = self.rel2[m][:, None] * (np.conj(u) * du).real / sd
        dr = -(self.t_h[m][:, None] * du) / sd - r * dsd / sd
        J = np.concatenate([dr.real, dr.imag], axis=0)
        return res, J

    def fun(self, x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if self._cache is None or self._cache[0] != key:
            r, J = self.evaluate(x)
            assert J is not None
            self._cache = (key, r, J)
        return self._cache[1]

    def jac(self, x: np.ndarray) -> np.ndarray:
        self.fun(x)
        assert self._cache is not None
        return self._cache[2]


@dataclass(frozen=True)
class ElementFit:
    """One candidate's best fit: the loss (fraction), chi2 (whitened residual sum), relative likelihood,
    and the benign parameters and gain that went with it."""

    element: int
    loss: float
    chi2: float
    likelihood: float
    theta: tuple[float, ...]
    gain: float
    loss_interval: tuple[float, float] | None = None  # at INTERVAL_LEVEL (None: not computed), by ``size_basis``
    inflation: float = 1.0  # the interval's widening: sqrt(chi2 / dof) of the best fit when above 1
    size: float | None = None  # the loss the interval is about: the pole shifts' estimate, else ``loss``

    @property
    def size_basis(self) -> str:
        """What the interval rests on: :data:`~rotorcheck.sizing.POLE_SHIFTS` (sized by :mod:`rotorcheck.sizing`),
        :data:`FRF_FIT` (:func:`profile_interval`), or '' (no interval)."""
        if self.loss_interval is None:
            return ""
        return FRF_FIT if self.size is None else POLE_SHIFTS

    @property
    def size_estimate(self) -> float:
        """The size estimate (fraction): the pole shifts' where they size it, else the best fit's loss."""
        return self.loss if self.size is None else self.size


@dataclass
class Ranking:
    """Every candidate element's fit (:func:`rank_elements`), best first, and the benign-only fit."""

    hypothesis: str
    fits: list[ElementFit]  # best (largest likelihood) first
    chi2_benign: float  # the fit with no loss (benign change and gain only)
    n_residuals: int  # real residuals in each chi2
    n_frequencies: int
    rule: str = ""
    notes: list[str] = field(default_factory=list)

    @property
    def best(self) -> ElementFit | None:
        return self.fits[0] if self.fits else None

    def of(self, element: int) -> ElementFit | None:
        return next((f for f in self.fits if f.element == element), None)

    @property
    def evidence_over_benign(self) -> float:
        """chi2 the best element's loss removes over benign change alone (>= 0)."""
        return max(0.0, self.chi2_benign - self.fits[0].chi2) if self.fits else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"rule": self.rule, "chi2_benign_only": self.chi2_benign, "n_residuals": self.n_residuals,
                "n_frequencies": self.n_frequencies, "notes": list(self.notes),
                "interval_rule": INTERVAL_RULE,
                "elements": [{"element": f.element, "loss_estimate": f.loss, "chi2": f.chi2,
                              "relative_likelihood": f.likelihood,
                              **({} if f.loss_interval is None else
                                 {"size_estimate": f.size_estimate, "loss_estimate_interval": list(f.loss_interval),
                                  "interval_level": INTERVAL_LEVEL, "interval_inflation": f.inflation,
                                  "interval_basis": f.size_basis,
                                  "interval_rule": INTERVAL_RULE if f.size is None else POLE_SIZE_RULE})}
                             for f in self.fits]}


#: how the ranking is made (report.json)
RANKING_RULE = ("every candidate element fitted: one loss of its bending stiffness in [0, 0.8], benign parameters in "
                "their ranges and a gain in its range, bounded least squares of the whitened misfit (noise of both "
                "sweeps and the model's error bounds as standard deviations) at the fit frequencies; relative "
                "likelihood exp(-chi2/2) normalised over the candidates (equal prior per element)")


#: how the estimate's interval is made (report.json)
INTERVAL_RULE = ("the best ranked element's loss: every loss whose fit (benign parameters, gain and a scale of the "
                 "predicted change within 1 +- the crack model's error bound refitted, loss held) exceeds the best "
                 "fit's chi2 by at most the chi2(1 dof) quantile at the level, times the best fit's chi2 per degree "
                 "of freedom when that exceeds 1 (a model error larger than its stated bounds widens the interval); "
                 "assumes the residuals independent Gaussian with the noise and the model's error bounds as "
                 "standard deviations, and the model's crack signature right up to that common scale")


def _solve(fit: _Fit, lo: np.ndarray, hi: np.ndarray, starts: Sequence[np.ndarray]) -> tuple[np.ndarray, float]:
    """The best bounded least-squares solution over ``starts``: ``(x, chi2)``."""
    from scipy.optimize import least_squares  # lazy: scipy.optimize only for the fits

    hi = np.where(hi > lo, hi, lo + 1e-12)  # least_squares needs lo < hi (a fixed gain or loss)
    best: tuple[np.ndarray, float] | None = None
    for x0 in starts:
        sol = least_squares(fit.fun, np.clip(x0, lo, hi), jac=fit.jac, bounds=(lo, hi), x_scale=hi - lo,
                            max_nfev=MAX_NFEV, method="trf")
        chi2 = float(2.0 * sol.cost)
        if best is None or chi2 < best[1]:
            best = (sol.x, chi2)
    assert best is not None
    return best


def _starts(fit: _Fit, centre: np.ndarray, g: float) -> list[np.ndarray]:
    """Start points: the loss at the best of :data:`LOSS_SCAN`, and at the best other local minimum of
    the scan (benign parameters at ``centre``, gain ``g``)."""
    chi = []
    for a in LOSS_SCAN:
        r, _ = fit.evaluate(np.r_[centre, a, g], jac=False)
        chi.append(float(r @ r) if np.all(np.isfinite(r)) else np.inf)
    chi_a = np.array(chi)
    order = np.argsort(chi_a)
    first = int(order[0])
    picks = [first]
    for k in order[1:]:
        k = int(k)
        left = chi_a[k - 1] if k > 0 else np.inf
        right = chi_a[k + 1] if k + 1 < chi_a.size else np.inf
        if abs(k - first) > 1 and chi_a[k] <= left and chi_a[k] <= right and np.isfinite(chi_a[k]):
            picks.append(k)
            break
    return [np.r_[centre, LOSS_SCAN[k], g] for k in picks]


def profile_interval(fit: _Fit, lo: np.ndarray, hi: np.ndarray, x: np.ndarray, dof: int,
                     level: float = INTERVAL_LEVEL, tol: float = INTERVAL_TOL, form: float = CRACK_MODEL_ERROR
                     ) -> tuple[tuple[float, float], float]:
    """``((lower, upper), inflation)``: the profile-likelihood interval of the loss (``x[-2]`` of the best
    fit ``x = (theta, loss, gain)`` in ``[lo, hi]``; ``dof`` degrees of freedom) at ``level``
    (:data:`INTERVAL_RULE`). The predicted change is scaled by a free factor in ``[1 - form, 1 + form]`` (the
    model's error common to every point: a loss is kept when some scale explains the data with it); the
    interval holds the losses whose refitted misfit (benign parameters, gain and scale free, the loss held)
    exceeds the best by at most ``chi2_1(level) * inflation^2``, ``inflation = max(1, sqrt(chi2 / dof))``.
    Each end is bracketed by steps that double from the linearised standard error, then bisected to ``tol``."""
    from scipy.special import chdtri  # lazy: scipy.special only for the interval's quantile

    k = lo.size - 2  # the loss's index
    lo_s, hi_s = np.r_[lo, 1.0 - form], np.r_[hi, 1.0 + form]
    best, chi2 = _solve(fit, lo_s, hi_s, [np.r_[x, 1.0]])
    inflation = float(max(1.0, np.sqrt(chi2 / max(dof, 1))))
    allowed = float(chdtri(1.0, 1.0 - level)) * inflation**2
    _, J = fit.evaluate(best)
    assert J is not None
    span = hi_s - lo_s
    free = (best > lo_s + 1e-6 * span) & (best < hi_s - 1e-6 * span)
    free[k] = True
    se = float(linearized_se(J, free)[k])
    first = min(max(np.sqrt(allowed) * se, 4.0 * tol), 0.5 * (hi[k] - lo[k]))

    def excess(loss: float, start: np.ndarray) -> tuple[float, np.ndarray]:
        """The refitted misfit's excess over the best with the loss held at ``loss``."""
        l1, h1 = lo_s.copy(), hi_s.copy()
        l1[k] = h1[k] = loss
        x0 = start.copy()
        x0[k] = loss
        xs, c = _solve(fit, l1, h1, [x0])
        return c - chi2, xs

    ends = []
    for sign in (-1.0, 1.0):
        bound = lo[k] if sign < 0 else hi[k]
        inside, start, step, end = float(best[k]), best, first, None
        while end is None:
            out = float(np.clip(inside + sign * step, lo[k], hi[k]))
            ex, xs = excess(out, start)
            if ex > allowed:
                while abs(out - inside) > tol:  # bisect between the last loss inside and the first outside
                    mid = 0.5 * (inside + out)
                    ex, xm = excess(mid, start)
                    if ex > allowed:
                        out = mid
                    else:
                        inside, start = mid, xm
                end = out
            elif out == bound:
                end = bound
            else:
                inside, start, step = out, xs, 2.0 * step
        ends.append(end)
    return (float(ends[0]), float(ends[1])), inflation


def rank_elements(config: RigConfig, box: Any, change: SweepChange, elements: Sequence[int],
                  models: dict[int, AffineModel] | None = None, progress: Progress | None = None,
                  intervals: int = 1) -> Ranking:
    """Every element of ``elements`` fitted and ranked (module docstring); ``models`` the loss models
    already built (:func:`loss_model`), filled in here; ``progress`` (:data:`rotorcheck.progress.Progress`)
    hears each element done; ``intervals``: the best ranked elements that get the loss's profile-likelihood
    interval (:func:`profile_interval`)."""
    models = {} if models is None else models
    idx = fit_frequencies(change)
    lo_b = np.array([q.lo for q in box.model.parameters], dtype=float)
    hi_b = np.array([q.hi for q in box.model.parameters], dtype=float)
    centre = np.clip(0.0, lo_b, hi_b)
    g_lo, g_hi = change.gain
    g = float(np.clip(1.0, g_lo, g_hi))
    raw: list[tuple[int, float, float, np.ndarray]] = []
    fitted: dict[int, tuple[_Fit, np.ndarray, np.ndarray]] = {}
    chi2_benign = float("nan")
    n_res = 0
    report(progress, 0, len(elements), "ranking")
    for k, e in enumerate(elements):
        if e not in models:
            models[e] = loss_model(config, box, e, change.speed_rpm, change.hypothesis)
        fit = _Fit(models[e], change, idx)
        lo, hi = np.r_[lo_b, 0.0, g_lo], np.r_[hi_b, MAX_LOSS, g_hi]
        if k == 0:  # benign change alone: the loss held at 0 (the same model whatever the element)
            _, chi2_benign = _solve(fit, lo, np.r_[hi_b, 0.0, g_hi], [np.r_[centre, 0.0, g]])
        x, chi2 = _solve(fit, lo, hi, _starts(fit, centre, g))
        n_res = 2 * int(fit.used.sum())
        raw.append((e, float(x[-2]), chi2, x))
        fitted[e] = (fit, lo, hi)
        report(progress, k + 1, len(elements), f"ranking: element {e}")
    chis = np.array([c for _, _, c, _ in raw])
    lik = np.exp(-0.5 * (chis - chis.min())) if chis.size else chis
    lik = lik / lik.sum() if lik.size else lik
    fits = [ElementFit(e, a, c, float(w), tuple(float(v) for v in x[:-2]), float(x[-1]))
            for (e, a, c, x), w in zip(raw, lik)]
    fits.sort(key=lambda f: (-f.likelihood, f.chi2, f.element))
    dof = n_res - (lo_b.size + 2)
    for j, f in enumerate(fits[:intervals]):
        sized = None
        if change.anchor is not None:
            sized = size_from_poles(models[f.element], change.anchor, change.t_new, change.var_new, change.t_h,
                                    change.var_h, f.loss, INTERVAL_LEVEL)
        if sized is not None:
            fits[j] = dataclasses.replace(f, loss_interval=sized.interval, inflation=sized.inflation,
                                          size=sized.estimate)
            continue
        fit, lo, hi = fitted[f.element]
        x = np.r_[f.theta, f.loss, f.gain]
        interval, inflation = profile_interval(fit, lo, hi, x, dof)
        fits[j] = dataclasses.replace(f, loss_interval=interval, inflation=inflation)
    return Ranking(change.hypothesis, fits, chi2_benign, n_res, int(idx.size), RANKING_RULE)
