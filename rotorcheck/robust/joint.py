"""One joint test over every frequency point (and channel): is the new sweep's change from the healthy
baseline benign, or benign plus a crack?

The residual ``r = T_new - T_healthy`` (stacked over points and channels, m/N) is whitened by the
noise of both sweeps, ``sigma_k^2 = var_new,k + var_healthy,k`` (``E|noise_k|^2``, variances of the
mean FRFs). Two hypotheses:

- H0: ``r = b(theta) + U c + e``: a benign change ``b(theta)`` predicted by re-solving the model at
  real parameter values ``theta`` inside their configured box, plus data-learned benign directions
  ``U`` (from several healthy sweeps) with bounded coefficients, plus noise; the model's own error in
  predicting a benign change is carried as extra variance ``kappa^2 m_k^2`` at each point (``kappa``:
  relative error of the prediction; ``m_k`` the size of the predicted change there, :func:`change_scale`);
- H1: the same plus ``a s_e``: a stiffness loss ``a >= 0`` (fraction) of candidate element ``e`` with
  the model's signature ``s_e`` (FRF change per unit loss).

Statistic: the generalized likelihood ratio ``T = max_e T_e``, ``T_e = min_H0 chi2 - min_H1,e chi2``
(chi2 = the whitened residual norm, real degrees of freedom; H1 is solved on the model linearized
at the H0 fit). Null distribution, stated: noise complex Gaussian with the given variances treated as
known; nuisance interior to its box and locally linear; then ``T_e`` is a one-sided normal squared
and ``max_e`` is computed exactly for the correlated candidates by seeded Monte Carlo over their
correlation (not Bonferroni).

The GLR looks for a change shaped like a small loss of one element. A change far outside that (a 20 % loss
moves a resonance by more than its bandwidth, where the first-order signature no longer resembles it; a
benign parameter far outside its range; a sensor fault) can leave ``T = 0`` while no benign change explains
the data at all. So H0 is also tested by its goodness of fit: ``chi2_H0`` (the H0 fit's whitened residual,
with the model-form prior's rows) against chi-square with ``2 n + n_form - (free benign and learned
unknowns)`` degrees of freedom (the model-form coefficients counted as not fitting: a conservative count).
The two share the false-alarm rate (Bonferroni): the GLR at ``(1 - GOF_SHARE) false_alarm``, the fit at
``GOF_SHARE false_alarm``; the sweep's p-value is ``min(p_GLR / (1 - GOF_SHARE), p_fit / GOF_SHARE, 1)`` and
``damage`` iff ``p < false_alarm``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from rotorcheck.lazy import lazy_module
from rotorcheck.robust.bounded import bounded_lsq

optimize = lazy_module("scipy.optimize")  # loaded when a benign nuisance is fitted (not for noise only)
special = lazy_module("scipy.special")  # the goodness of fit's chi-square tail

#: share of the false-alarm rate spent on H0's goodness of fit (the rest on the GLR; module docstring)
GOF_SHARE = 0.1
#: how the joint verdict is made (report.json ``verdict_rule``)
JOINT_RULE = ("joint GLR over all points and channels with H0's goodness of fit: damage iff P(max_e T_e >= T | H0) < "
              f"{1.0 - GOF_SHARE:g} false_alarm or P(chi2 >= chi2_H0 | H0) < {GOF_SHARE:g} false_alarm (Bonferroni); "
              "H0 = benign parameters inside their ranges (model re-solved) + learned benign directions + the model's "
              "error in predicting them + noise of both sweeps; T_e = chi2(H0) - chi2(H0 + stiffness loss a >= 0 in "
              "element e)")
POWER_Z = 1.2815515655446004  # standard normal 0.9 quantile: 90 % detection probability
MC_DRAWS = 200_000
MC_SEED = 20261124


@dataclass(frozen=True)
class ModelForm:
    """The benign model's own error as real-coefficient directions of H0 with a Gaussian prior (a low-rank error
    covariance ``V^T diag(scale^2) V`` added to the noise's): ``V`` (r, n) complex m/N per unit coefficient, each
    coefficient ~ N(0, ``scale``^2) (r,), fitted with that penalty (bounded at :data:`FORM_BOX` scales); ``what``
    says what they stand for (e.g. each fitted mode's pole moved beyond the model's predicted shift)."""

    V: np.ndarray
    scale: np.ndarray
    what: str = ""


#: a model-form coefficient is kept within this many of its prior scales (the penalty does the rest)
FORM_BOX = 6.0
#: chi2 gain (one dof, 95 %) from freeing a benign parameter beyond its range end above which the data are said
#: to push it beyond the range (:attr:`JointResult.theta_beyond_range`)
EDGE_EVIDENCE = 3.841458820694124


@dataclass(frozen=True)
class BenignModel:
    """Benign change predicted by the model: ``predict(theta)`` (n,) complex, m/N, with ``theta``
    (p,) real inside ``[lo, hi]``; ``kappa`` the relative error of that prediction carried in H0."""

    predict: Callable[[np.ndarray], np.ndarray]
    lo: np.ndarray
    hi: np.ndarray
    names: tuple[str, ...]
    kappa: float = 0.0
    step: np.ndarray | float = 1e-4  # finite-difference step(s) of theta for the Jacobian (theta's units)
    envelope: np.ndarray | None = None  # (n,) largest benign change the ranges allow at each point, m/N
    exact: np.ndarray | None = None  # (p,) bool: parameters whose predicted change is exact (gains): no kappa
    form: ModelForm | None = None  # the prediction's own error, part of H0 (a Gaussian prior, :class:`ModelForm`)
    cheap: bool = False  # ``predict`` is a closed form (no re-solve): the fit may scan the ranges first
    #: (p,) relative standard error of each parameter's estimate from the model's own error (its sensitivity):
    #: added to the linearized standard error as ``relative_error * |theta|`` (None: none)
    relative_error: np.ndarray | None = None

    def at(self, idx: np.ndarray) -> BenignModel:
        """The same benign change at the stacked points ``idx`` only: its prediction, envelope and model-form
        directions."""
        full = self.predict
        form = None if self.form is None else replace(self.form, V=np.asarray(self.form.V)[:, idx])
        return replace(self, predict=lambda theta: full(theta)[idx], form=form,
                       envelope=None if self.envelope is None else self.envelope[idx])


@dataclass(frozen=True)
class LearnedDirections:
    """Benign directions learned from healthy sweeps: ``U`` (q, n) complex (m/N per unit coefficient,
    unit whitened norm) and the bound ``c_max`` (q,) on each coefficient's real and imaginary part."""

    U: np.ndarray
    c_max: np.ndarray
    singular_values: np.ndarray  # whitened, all components (for the report)
    n_sweeps: int


def linearized_se(J: np.ndarray, free: np.ndarray) -> np.ndarray:
    """(q,) standard errors of the unknowns of a least-squares fit from the Jacobian ``J`` (n, q) of its whitened
    residuals: the ``free`` ones (q,) bool from ``pinv(J_f^T J_f)`` with the columns scaled to unit size first (a
    conditioned inverse), inf where held (at a bound). Multiply by ``sqrt(chi2 / dof)`` for residuals whitened
    by an unknown scale."""
    se = np.full(J.shape[1], np.inf)
    seen = free & (np.linalg.norm(J, axis=0) > 0)  # a column the data do not see leaves its unknown unbounded
    if np.any(seen):
        Jf = J[:, seen]
        size = np.linalg.norm(Jf, axis=0)
        cov = np.linalg.pinv((Jf / size).T @ (Jf / size), rcond=1e-12) / np.outer(size, size)
        se[seen] = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return se


@dataclass
class JointResult:
    """The joint test of one sweep (see the module docstring)."""

    statistic: float
    threshold: float
    p_value: float
    false_alarm: float
    damage: bool
    elements: tuple[int, ...]
    t_element: np.ndarray  # (n_e,) T_e
    severity: np.ndarray  # (n_e,) estimated stiffness loss a_e (fraction, >= 0)
    severity_se: np.ndarray  # (n_e,) its standard error (linearized)
    detectable: np.ndarray  # (n_e,) smallest loss detected with 90 % power at false_alarm (fraction)
    best: int  # index into elements
    theta: np.ndarray  # (p,) benign parameters fitted under H0
    theta_se: np.ndarray  # (p,) their standard errors (linearized, inf where on a bound)
    theta_names: tuple[str, ...]
    theta_at_bound: np.ndarray  # (p,) bool
    chi2_h0: float
    dof_h0: int
    learned: int  # number of learned directions used
    kappa: float
    n_points: int
    unexplained: np.ndarray  # (n,) complex m/N: the change left after the H0 fit (benign + learned)
    point_statistic: np.ndarray  # (n,) |unexplained|^2 / (sigma^2 / 2) per point (chi2, 2 dof under H0)
    point_threshold: float  # per-point threshold: Sidak over the points at the false-alarm rate
    model_error: np.ndarray  # (n,) m/N: the model-error allowance kappa m_k carried in H0 (sd per point)
    notes: list[str] = field(default_factory=list)
    benign: BenignModel | None = None  # the benign change the test allowed (None: none)
    #: (p,) chi2 the linearized H0 fit would gain were each parameter at a range end free beyond it (0 inside): the
    #: data's evidence that the change exceeds that range (:data:`EDGE_EVIDENCE` and more: 95 %, one dof)
    theta_edge_chi2: np.ndarray | None = None
    #: the GLR's own p-value ``P(max_e T_e >= T | H0)`` (``p_value`` is the sweep's, with the goodness of fit)
    glr_p_value: float = 1.0
    #: H0's goodness of fit: degrees of freedom of ``chi2_h0`` (module docstring) and ``P(chi2 >= chi2_h0 | H0)``
    fit_dof: int = 0
    fit_p_value: float = 1.0

    @property
    def decided_by_fit(self) -> bool:
        """Damage because no benign change fits the data (H0's goodness of fit), the GLR alone not deciding."""
        return self.damage and self.glr_p_value >= (1.0 - GOF_SHARE) * self.false_alarm

    @property
    def theta_beyond_range(self) -> np.ndarray:
        """(p,) bool: parameters at a range end that the data would move beyond it (:attr:`theta_edge_chi2` >=
        :data:`EDGE_EVIDENCE`); one at an end without that evidence is merely not fixed by the data."""
        if self.theta_edge_chi2 is None:
            return np.asarray(self.theta_at_bound, dtype=bool)
        return np.asarray(self.theta_at_bound, dtype=bool) & (np.asarray(self.theta_edge_chi2) >= EDGE_EVIDENCE)

    @property
    def remaining(self) -> np.ndarray:
        """(n,) bool: points the benign change fitted under H0 leaves unexplained beyond the noise and the
        model-error allowance (per point, Sidak at ``false_alarm`` over the points)."""
        return self.point_statistic > self.point_threshold

    @property
    def severity_interval(self) -> tuple[float, float]:
        """95 % interval of the best candidate's loss (fraction), clipped at 0."""
        a, s = float(self.severity[self.best]), float(self.severity_se[self.best])
        return max(0.0, a - 1.96 * s), a + 1.96 * s


def _ri(z: np.ndarray) -> np.ndarray:
    return np.concatenate([z.real, z.imag], axis=-1)


def change_scale(predicted: np.ndarray, halfwidth: int = 2, envelope: np.ndarray | None = None) -> np.ndarray:
    """Size of the benign change at each point (m/N) that the model-error term scales with: the predicted
    change at the fitted parameters, never more than the largest benign change the ranges allow there
    (``envelope``), the largest over +-``halfwidth`` points (a model's error moves with a resonance, not
    point by point). The observed change does not enter: a change the benign model does not predict
    (a crack) is no excuse for itself (with the observed change in it, each point's evidence was capped
    at 1 / kappa^2 and a 20 % breathing crack went unseen in 8 of 10 sweeps)."""
    m = np.abs(np.asarray(predicted))
    if envelope is not None:
        m = np.minimum(m, np.asarray(envelope, dtype=float))
    if halfwidth <= 0 or m.size == 0:
        return m
    pad = np.pad(m, halfwidth, mode="edge")
    return np.max(np.lib.stride_tricks.sliding_window_view(pad, 2 * halfwidth + 1), axis=1)


def whitening(var_total: np.ndarray) -> np.ndarray:
    """Real weights ``sqrt(2 / sigma^2)`` (2n,) for the stacked [Re, Im] residual."""
    w = np.sqrt(2.0 / np.asarray(var_total, dtype=float))
    return np.concatenate([w, w])


#: standard normal draws kept per (seed, columns): the largest array drawn so far (issue 28: one joint test
#: after another, the detectability searches' ten, draw the same numbers from the same seed)
_NORMALS: dict[tuple[int, int], np.ndarray] = {}


def _standard_normals(seed: int, draws: int, n: int) -> np.ndarray:
    """``np.random.default_rng(seed).standard_normal((draws, n))``, the same numbers, drawn once per ``(seed,
    n)``: a generator fills the array in order, so fewer draws are the first rows of more (read-only)."""
    have = _NORMALS.get((seed, n))
    if have is None or have.shape[0] < draws:
        have = np.random.default_rng(seed).standard_normal((draws, n))
        have.flags.writeable = False
        if len(_NORMALS) >= 2:  # 200,000 x 9 draws are 14 MB
            _NORMALS.pop(next(iter(_NORMALS)))
        _NORMALS[(seed, n)] = have
    return have[:draws]


def _max_one_sided(C: np.ndarray, draws: int, seed: int) -> np.ndarray:
    """Monte-Carlo draws (unsorted) of ``max_e max(g_e, 0)^2`` for ``g ~ N(0, C)``."""
    L = np.linalg.cholesky(C + 1e-12 * np.eye(C.shape[0]))
    g = _standard_normals(seed, draws, C.shape[0]) @ L.T
    # max_e max(g_e, 0) = max(max_e g_e, 0), the maximum taken column by column (a row-wise max over a few
    # columns is twice as slow); the same numbers
    if g.shape[1] == 0:
        return np.max(np.maximum(g, 0.0), axis=1) ** 2  # as before (no candidate: numpy's error)
    top = g[:, 0].copy()
    for j in range(1, g.shape[1]):
        np.maximum(top, g[:, j], out=top)
    return np.maximum(top, 0.0) ** 2


def joint_test(residual: np.ndarray, var_total: np.ndarray, signatures: np.ndarray,
               elements: Sequence[int], benign: BenignModel | None = None,
               learned: LearnedDirections | None = None, false_alarm: float = 0.01,
               draws: int = MC_DRAWS, seed: int = MC_SEED, exclude: np.ndarray | None = None,
               edge_evidence: bool = True) -> JointResult:
    """The joint GLR test (module docstring). ``residual`` (n,) complex m/N; ``var_total`` (n,) m^2/N^2;
    ``signatures`` (n_e, n) complex m/N per unit stiffness loss of each candidate element. ``exclude`` (n,)
    bool: points that carry no evidence (weight 0 in every fit and statistic, not counted in ``n_points``,
    the per-point Sidak threshold or the dof; their ``point_statistic`` is 0), e.g. points on a shaft
    harmonic. The benign model's own error (``benign.form``, :class:`ModelForm`) is part of H0. ``edge_evidence``:
    the chi2 each parameter at a range end would gain beyond it (:attr:`JointResult.theta_edge_chi2`; a caller that
    needs the verdict alone, e.g. the detectability searches, leaves it out: None)."""
    if not 0.0 < false_alarm < 1.0:
        raise ValueError(f"false_alarm must be in (0, 1), got {false_alarm}")
    r = np.asarray(residual, dtype=complex).ravel()
    var = np.asarray(var_total, dtype=float).ravel()
    S = np.asarray(signatures, dtype=complex).reshape(len(elements), r.size)
    used = np.ones(r.size, dtype=bool) if exclude is None else ~np.asarray(exclude, dtype=bool).ravel()
    used2 = np.concatenate([used, used])
    n_used = int(np.count_nonzero(used))

    def weights(v: np.ndarray) -> np.ndarray:
        """:func:`whitening` of the points used, 0 at the excluded ones."""
        return np.where(used2, whitening(np.where(used, v, 1.0)), 0.0)
    notes: list[str] = []
    p = 0 if benign is None else len(benign.lo)
    q = 0 if learned is None else learned.U.shape[0]
    U = learned.U if learned is not None else np.zeros((0, r.size), dtype=complex)
    model_form = benign.form if benign is not None else None
    if model_form is not None and model_form.what:
        notes.append(f"the benign prediction's own error is part of H0 as a Gaussian prior: {model_form.what}")
    nf = 0 if model_form is None else model_form.V.shape[0]
    V = model_form.V.reshape(nf, r.size) if model_form is not None else np.zeros((0, r.size), dtype=complex)
    f0 = p + 2 * q  # where the model-form coefficients start

    def model_ri(x: np.ndarray) -> np.ndarray:
        b = np.zeros_like(r)
        if p:
            assert benign is not None
            b = b + benign.predict(x[:p])
        if q:
            c = x[p:p + q] + 1j * x[p + q:f0]
            b = b + c @ U
        if nf:
            b = b + x[f0:] @ V
        return b

    # unknowns: the benign parameters, the learned coefficients' real and imaginary parts, the model-form ones
    c_max = learned.c_max if learned is not None else np.zeros(0)
    form_scale = np.asarray(model_form.scale, dtype=float) if model_form is not None else np.zeros(0)
    form_max = FORM_BOX * form_scale
    lo = np.concatenate([benign.lo if benign is not None else np.zeros(0), -c_max, -c_max, -form_max])
    hi = np.concatenate([benign.hi if benign is not None else np.zeros(0), c_max, c_max, form_max])
    x0 = np.zeros(lo.size)
    if benign is not None:
        x0[:p] = np.clip(0.0, benign.lo, benign.hi)
    kappa = benign.kappa if benign is not None else 0.0

    def jac_at(x: np.ndarray, w: np.ndarray) -> np.ndarray:
        J = np.zeros((2 * r.size + nf, x.size))
        if p:
            assert benign is not None
            b0 = benign.predict(x[:p])
            steps = np.broadcast_to(np.asarray(benign.step, dtype=float), (p,))
            for j in range(p):
                h = float(steps[j]) if x[j] + steps[j] <= hi[j] else -float(steps[j])
                xj = x[:p].copy()
                xj[j] += h
                J[:2 * r.size, j] = _ri((benign.predict(xj) - b0) / h) * w
        if q:
            J[:2 * r.size, p:p + q] = _ri(U).T * w[:, None]
            J[:2 * r.size, p + q:f0] = _ri(1j * U).T * w[:, None]
        if nf:
            J[:2 * r.size, f0:] = _ri(V).T * w[:, None]
            J[2 * r.size:, f0:] = -np.diag(1.0 / form_scale)  # the prior's rows: d(x / scale) = -d model
        return J

    def whitened(x: np.ndarray, ww: np.ndarray) -> np.ndarray:
        """The residual left by the nuisance at ``x``, whitened by ``ww`` (2n,), then the model-form prior's rows."""
        out = _ri(r - model_ri(x)) * ww
        return np.concatenate([out, x[f0:] / form_scale]) if nf else out

    def allowance_at(x: np.ndarray) -> np.ndarray:
        """kappa times the predicted (inexact) benign change at ``x`` (m/N per point)."""
        if not (kappa > 0 and p):
            return np.zeros(r.size)
        assert benign is not None
        b_all = benign.predict(x[:p])
        b_exact = np.zeros_like(b_all)
        if benign.exact is not None and np.any(benign.exact):
            inexact = np.where(benign.exact, 0.0, x[:p])
            b_exact = b_all - benign.predict(inexact)  # the exactly predicted part (a gain)
        return kappa * change_scale(b_all - b_exact, envelope=benign.envelope)

    def refine(x: np.ndarray, ww: np.ndarray) -> np.ndarray:
        return optimize.least_squares(whitened, x, bounds=(lo, hi), jac=lambda y, wv: -jac_at(y, wv),
                                      x_scale="jac", method="trf", max_nfev=60, args=(ww,)).x

    w = weights(var)
    theta = x0
    allowance = np.zeros(r.size)
    if lo.size:
        # start from the better of x0 and the bounded linear fit at x0 (a large change such as E at the
        # edge of its range is far outside the first-order region)
        def cost(x: np.ndarray) -> float:
            return float(np.sum(whitened(x, w) ** 2))
        start = x0
        if p and benign is not None and benign.cheap:
            # a cheap prediction (the modal anchor): scan each benign parameter over its range, twice round, so
            # that the fit starts in the right valley (E moves a mode by a half-power bandwidth over its range)
            for _ in range(2):
                for j in range(p):
                    trial = [start] + [np.where(np.arange(lo.size) == j, v, start)
                                       for v in np.linspace(lo[j], hi[j], 9)]
                    start = min(trial, key=cost)
        lin, _ = bounded_lsq(jac_at(start, w), whitened(start, w), lo - start, hi - start)
        x_lin = np.clip(start + lin, lo, hi)
        theta = min((x0, start, x_lin), key=cost)
        for _ in range(2 if kappa > 0 else 1):  # refit once with the model-error variance
            theta = refine(theta, w)
            allowance = allowance_at(theta)
            w = weights(var + allowance**2)
    res0 = whitened(theta, w)
    chi2_h0 = float(res0 @ res0)
    J = jac_at(theta, w)
    # a bounded nonlinear fit can stop short (a flat valley, a bound): where the linearized H0 still
    # gains more than one chi-square unit, restart from its step (up to 3 times, weights held), so that
    # a nuisance misfit is not read as crack evidence
    chi2_lin: float | None = None  # the bounded linear H0 fit's chi2 at the current theta, once solved
    for _ in range(3 if lo.size else 0):
        step, chi2_lin = bounded_lsq(J, res0, lo - theta, hi - theta)
        if chi2_h0 - chi2_lin <= 1.0:
            break
        cand = refine(np.clip(theta + step, lo, hi), w)
        rc = whitened(cand, w)
        if float(rc @ rc) >= chi2_h0 - 1e-9:
            break
        theta, res0, chi2_h0 = cand, rc, float(rc @ rc)
        J, chi2_lin = jac_at(theta, w), None
    at_bound = np.zeros(lo.size, dtype=bool)
    if lo.size:
        span = np.maximum(hi - lo, 1e-300)
        at_bound = (theta - lo <= 1e-6 * span) | (hi - theta <= 1e-6 * span)
    # free nuisance columns: the linearized H0 tangent space (bound-active ones held)
    Jf = J[:, ~at_bound]
    Sw = _ri(S) * w  # (n_e, 2n)
    if nf:
        Sw = np.concatenate([Sw, np.zeros((Sw.shape[0], nf))], axis=1)  # a crack is no model-form coefficient
    if Jf.shape[1]:
        Q, _ = np.linalg.qr(Jf)
        Sp = Sw - (Sw @ Q) @ Q.T
        rp = res0 - Q @ (Q.T @ res0)
    else:
        Sp, rp = Sw, res0
    nrm = np.linalg.norm(Sp, axis=1)
    ok = nrm > 1e-12 * np.maximum(np.linalg.norm(Sw, axis=1), 1e-300)
    z = np.where(ok, (Sp @ rp) / np.where(ok, nrm, 1.0), 0.0)
    t_el = np.maximum(z, 0.0) ** 2
    sev = np.where(ok, np.maximum(z, 0.0) / np.where(ok, nrm, 1.0), 0.0)
    se = np.where(ok, 1.0 / np.where(ok, nrm, 1.0), np.inf)
    # the nuisance's box: T_e from the bounded linear problem (a >= 0, every nuisance inside its box);
    # where the crack would need benign values outside the ranges this is what separates them
    if lo.size:
        # both hypotheses on the same linearization inside the box: H0's own linear gain is not crack evidence
        if chi2_lin is None:  # the restarts moved theta last (or none ran): solved here
            chi2_lin = bounded_lsq(J, res0, lo - theta, hi - theta)[1]
        chi2_h0_lin = min(chi2_h0, chi2_lin)
        for e in range(len(elements)):
            A = np.column_stack([J, Sw[e]])
            lb = np.concatenate([lo - theta, [0.0]])
            ub = np.concatenate([hi - theta, [np.inf]])
            x_e, chi2_e = bounded_lsq(A, res0, lb, ub)
            t_el[e] = max(0.0, chi2_h0_lin - chi2_e)
            sev[e] = float(x_e[-1])
    Un = Sp / np.where(ok, nrm, 1.0)[:, None]
    C = Un @ Un.T
    C[~ok, :] = 0.0
    C[:, ~ok] = 0.0
    C[np.diag_indices_from(C)] = 1.0
    null = _max_one_sided(C, draws, seed)
    stat = float(np.max(t_el)) if t_el.size else 0.0
    n_ge = int(np.count_nonzero(null >= stat))
    p_glr = float((n_ge + 1) / (null.size + 1))
    thr = float(np.quantile(null, 1.0 - (1.0 - GOF_SHARE) * false_alarm))
    # H0's goodness of fit: every residual row (the prior's too) less the free benign and learned unknowns
    fit_dof = max(1, 2 * n_used + nf - int(np.count_nonzero(~at_bound[:f0])))
    p_fit = float(special.gammaincc(0.5 * fit_dof, 0.5 * chi2_h0))
    p_value = min(1.0, p_glr / (1.0 - GOF_SHARE), p_fit / GOF_SHARE)
    detectable = np.where(ok, (np.sqrt(thr) + POWER_Z) / np.where(ok, nrm, 1.0), np.inf)
    best = int(np.argmax(t_el)) if np.any(t_el > 0) else int(np.argmin(detectable))
    edge_chi2 = np.zeros(p)
    if edge_evidence and np.any(at_bound[:p]) and benign is not None:
        # each parameter at an end freed beyond it (three spans), the rest as they are: the linearized chi2 it gains
        # over the linearized H0 in the box (chi2_h0_lin and span: set above whenever a parameter is at a bound)
        for i in np.flatnonzero(at_bound[:p]):
            lb, ub = lo - theta, hi - theta
            if hi[i] - theta[i] <= 1e-6 * span[i]:
                ub[i] = 3.0 * span[i]
            else:
                lb[i] = -3.0 * span[i]
            edge_chi2[i] = max(0.0, chi2_h0_lin - bounded_lsq(J, res0, lb, ub)[1])
        beyond = at_bound[:p] & (edge_chi2 >= EDGE_EVIDENCE)
        if np.any(beyond):
            names = ", ".join(f"{n} (chi2 {g:.3g} lower beyond it)" for n, b, g in zip(benign.names, beyond, edge_chi2)
                              if b)
            notes.append(f"benign parameters the data push beyond their range: {names}; the change may exceed the "
                         "range")
    loose = np.zeros(lo.size, dtype=bool)
    if edge_evidence:
        loose[:p] = at_bound[:p] & (edge_chi2 < EDGE_EVIDENCE)
    # the standard errors with every benign parameter free (those at an end as if free: how far the data leave them),
    # over every free nuisance column (learned and model-form coefficients, the prior's rows in J): a parameter
    # confounded with the model-form directions is as uncertain as they leave it, and one confounded with a
    # parameter the data push to its range end as uncertain as that one leaves it (measured on the light-damper
    # truth, 30 training sweeps: a bearing held at its end kept out of the others' errors left Young's modulus's
    # 95 % interval holding the truth in 10 of 20 healthy sweeps)
    free = ~at_bound
    free[:p] = True
    theta_se = linearized_se(J, free)[:p]
    if benign is not None and benign.relative_error is not None:
        # the farther from the anchor, the more the model's sensitivity error moves the estimate
        theta_se = np.hypot(theta_se, np.asarray(benign.relative_error, dtype=float) * np.abs(theta[:p]))
    if benign is not None:
        if np.any(loose):
            names = ", ".join(n for n, b in zip(benign.names, loose[:p]) if b)
            notes.append(f"benign parameters at the edge of their range that the data do not fix (freeing them beyond "
                         f"it lowers chi2 by less than {EDGE_EVIDENCE:.3g}, 95 %): {names}")
    return JointResult(
        statistic=stat, threshold=thr, p_value=p_value, false_alarm=false_alarm,
        damage=bool(p_value < false_alarm), elements=tuple(int(e) for e in elements), t_element=t_el,
        severity=sev, severity_se=se, detectable=detectable, best=best, theta=theta[:p],
        theta_se=theta_se, theta_names=benign.names if benign is not None else (),
        theta_at_bound=at_bound[:p], chi2_h0=chi2_h0, dof_h0=int(2 * n_used - int(np.count_nonzero(~at_bound))),
        learned=q, kappa=kappa, n_points=n_used, unexplained=r - model_ri(theta),
        point_statistic=res0[: r.size] ** 2 + res0[r.size:2 * r.size] ** 2,
        point_threshold=float(-2.0 * np.log(-np.expm1(np.log1p(-false_alarm) / max(n_used, 1)))),
        model_error=allowance, notes=notes, benign=benign, theta_edge_chi2=edge_chi2 if edge_evidence else None,
        glr_p_value=p_glr, fit_dof=fit_dof, fit_p_value=p_fit,
    )
