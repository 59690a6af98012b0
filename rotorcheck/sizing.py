"""How big: an element's stiffness loss from how far the measured poles moved (issue 30's estimate interval).

The ranking (:mod:`rotorcheck.ranking`) fits the whole FRF change with the model's own ``G(theta, a) / G(0)``. Its
resonances sit where the model has them, not where the machine has them, and the fit trades the loss against the
benign parameters to make up the difference: on the independent-physics truths its 95 % interval held the true loss
in about half the cases (an open 10 % loss of element 2 read 19 %, interval 14-24 %). The poles are what a
stiffness loss moves, and the machine's own poles can be measured: the healthy sweep's modal fit
(:class:`rotorcheck.modal_anchor.ModalAnchor`) and the same fit of the new sweep (:func:`~rotorcheck.modal_anchor.\
refit_poles`) give each mode's shift ``m_r = |lambda_new|^2 / |lambda_healthy|^2 - 1``. A loss ``a`` of the element
moves the model's pole by ``c_r(a)`` (exact: the model's eigenvalues re-solved on a grid of losses, tracked mode by
mode), the benign parameters by ``S_r theta`` (first order, ``theta`` in its box). The model's pole shift per loss
is right to a stiffness's share of a mode's strain energy, which the model gets nearly right where it misplaces the
resonance itself: on the five truth variants of ``bench/truth_variants.py`` (elements 2-8, every mode below 600 Hz,
both planes) the truths' ``c_r(0.1) / 0.1`` differ from the model's by at most 0.040 (element 8), 0.007-0.028
elsewhere. So per mode

    chi2(a) = min over theta in its box of  sum_r (m_r - c_r(a) - S_r theta)^2 / sd_r^2,
    sd_r^2 = se_r^2 + (SHIFT_ERROR a)^2 + (FORM_SHARE c_r(a))^2 + (2 POLE_SENSITIVITY_ERROR sum |theta ranges|)^2

(``se_r`` the two fits' standard error of the shift). The estimate is the loss of least ``chi2``; its interval the
losses whose ``chi2`` exceeds the least by at most the chi2(1 dof) quantile at the level, times ``chi2_min / dof``
where that exceeds 1 (``dof`` the modes less two): a model error beyond the stated one, seen in this sweep's own
misfit, widens the interval.

Used for the standstill (open-crack) hypothesis: at speed a breathing crack's parametric coupling moves the
response at the sidebands, which a pole shift does not describe (the ranking's profile stays there).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rotorcheck.lazy import lazy_module
from rotorcheck.modal_anchor import POLE_SENSITIVITY_ERROR, ModalAnchor, PoleRefit, refit_poles
from rotorcheck.robust.affine import AffineModel
from rotorcheck.robust.bounded import box_lsq

linalg = lazy_module("scipy.linalg")
interpolate = lazy_module("scipy.interpolate")
special = lazy_module("scipy.special")

#: the model's error in a mode's relative pole shift ``|lambda|^2`` per unit loss, one standard deviation: the five
#: truth variants differ from the model by at most 0.040 per unit loss (element 8), 0.007-0.028 for elements 2-7; at
#: 0.02 the worst is two standard deviations
SHIFT_ERROR = 0.02
#: and a share of the predicted shift itself (a mode whose shape the model gets wrong: 0.27-0.42 of a small shift at
#: a node of elements 6-8)
FORM_SHARE = 0.1
#: the loss grid on which the model's poles are re-solved (the curve between is a cubic spline), and the step of the
#: profile (fraction)
CURVE_STEP, PROFILE_STEP = 0.02, 0.0025
#: a refit that moves the estimate by more than this is done again from the poles the new estimate predicts
REFIT_MOVE = 0.03

#: losses (fraction) whose predicted poles start the new sweep's fit when the first estimate's do not fit it
START_LOSSES = (0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
#: what an estimate's interval rests on when this module sized it (report.json ``interval_basis``)
POLE_SHIFTS = "pole shifts"
#: how the size and its interval are made (report.json)
POLE_SIZE_RULE = ("the loss whose pole shifts (the model's eigenvalues re-solved at each loss, benign parameters in "
                  "their box, first order) best match the measured shifts of the fitted modes between the healthy and "
                  "the new sweep; interval: every loss whose chi2 exceeds the least by at most the chi2(1 dof) "
                  "quantile at the level, times chi2_min / (modes - 2) when that exceeds 1; assumes the model's pole "
                  f"shift per loss right to {SHIFT_ERROR} per unit loss and {FORM_SHARE:.0%} of the shift (one "
                  "standard deviation, measured on five independent-physics truths) and the fits' errors Gaussian")


@dataclass(frozen=True)
class PoleShiftSize:
    """An element's loss (fraction) from the measured pole shifts: ``estimate`` and ``interval`` at ``level``,
    ``inflation`` (``sqrt(chi2_min / dof)`` when above 1), per mode the measured ``shift``, its standard deviation
    ``sd`` at the estimate and the ``predicted`` shift there (benign parameters fitted), ``chi2`` and ``dof``."""

    estimate: float
    interval: tuple[float, float]
    level: float
    inflation: float
    shift: np.ndarray
    sd: np.ndarray
    predicted: np.ndarray
    chi2: float
    dof: int
    rule: str = POLE_SIZE_RULE


def model_poles(model: AffineModel, theta: np.ndarray) -> np.ndarray:
    """The poles (rad/s, positive imaginary part) of ``model`` at ``theta`` (state space of M, D, K)."""
    M, D, K = model.matrices_at(theta)
    n = K.shape[0]
    Minv = np.linalg.inv(M)
    S = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])
    lam = linalg.eigvals(S)
    return np.asarray(lam[lam.imag > 0])


def _nearest(lam: np.ndarray, ref: np.ndarray) -> np.ndarray:
    return np.array([lam[np.argmin(np.abs(lam - p))] for p in ref])


def shift_curves(model: AffineModel, reference: np.ndarray, step: float = CURVE_STEP
                 ) -> tuple[np.ndarray, np.ndarray]:
    """``(losses (g,), c (g, k))``: the relative ``|lambda|^2`` shift of each mode when the last parameter of
    ``model`` (the loss) takes each value of a grid over its range, the others at 0; each mode followed step by
    step from the model's pole nearest ``reference`` (k,) rad/s (the poles an anchor started from)."""
    top = float(model.parameters[-1].hi)
    grid = np.linspace(0.0, top, round(top / step) + 1)
    theta = np.zeros(len(model.parameters))
    prev = _nearest(model_poles(model, theta), np.asarray(reference))
    ref = prev
    out = [np.zeros(ref.size)]
    for a in grid[1:]:
        theta[-1] = a
        prev = _nearest(model_poles(model, theta), prev)
        out.append(np.abs(prev) ** 2 / np.abs(ref) ** 2 - 1.0)
    return grid, np.array(out)


def benign_shifts(model: AffineModel, reference: np.ndarray, h: float = 1e-3) -> np.ndarray:
    """(k, p): each mode's (the model's pole nearest each of ``reference`` (k,) rad/s) relative ``|lambda|^2``
    shift per unit of each benign parameter (all but the last), by central differences at 0."""
    p = len(model.parameters) - 1
    ref = _nearest(model_poles(model, np.zeros(p + 1)), np.asarray(reference))
    out = np.zeros((ref.size, p))
    for i in range(p):
        th = np.zeros(p + 1)
        th[i] = h
        up = _nearest(model_poles(model, th), ref)
        th[i] = -h
        down = _nearest(model_poles(model, th), ref)
        out[:, i] = (np.abs(up) ** 2 - np.abs(down) ** 2) / (2.0 * h * np.abs(ref) ** 2)
    return out


def shift_sd(se: np.ndarray, loss: float | np.ndarray, shift: np.ndarray, lo: np.ndarray, hi: np.ndarray
             ) -> np.ndarray:
    """(k,): each mode's standard deviation of the measured less the predicted shift at ``loss`` (predicted
    ``shift`` (k,)): the fits' ``se``, the model's error per loss and per shift, and the benign sensitivities'
    error over the box ``[lo, hi]`` (module docstring). Broadcasts: losses (n, 1) and shifts (n, k) give (n, k)."""
    reach = 2.0 * POLE_SENSITIVITY_ERROR * float(np.sum(np.maximum(np.abs(lo), np.abs(hi))))
    return np.asarray(np.sqrt(se**2 + (SHIFT_ERROR * loss) ** 2 + (FORM_SHARE * shift) ** 2 + reach**2))


def profile(measured: np.ndarray, se: np.ndarray, losses: np.ndarray, curves: np.ndarray, S: np.ndarray,
            lo: np.ndarray, hi: np.ndarray, step: float = PROFILE_STEP) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(a (n,), chi2 (n,), predicted (n, k))``: the misfit of the measured shifts (k,) (standard errors ``se``)
    at every loss of a grid of ``step`` (module docstring), the benign parameters (shifts ``S`` (k, p)) in
    ``[lo, hi]`` fitted at each loss by bounded linear least squares (:func:`box_lsq`, all losses at once)."""
    spline = interpolate.CubicSpline(losses, curves, axis=0)
    a = np.linspace(losses[0], losses[-1], round((losses[-1] - losses[0]) / step) + 1)
    c = spline(a)  # (n, k)
    sd = shift_sd(se, a[:, None], c, lo, hi)
    theta = (box_lsq(S[None, :, :] / sd[:, :, None], (measured - c) / sd, lo, hi) if S.shape[1]
             else np.zeros((a.size, 0)))
    pred = c + theta @ S.T
    r = (measured - pred) / sd
    return a, np.sum(r**2, axis=1), pred


def _first_fit(anchor: ModalAnchor, spline: Callable[[float], np.ndarray], frf: np.ndarray, var: np.ndarray | None,
               healthy_frf: np.ndarray, healthy_var: np.ndarray | None, guess: float, losses: np.ndarray
               ) -> PoleRefit | None:
    """The new sweep's poles fitted from those a loss predicts: ``guess`` first, then the grid's losses nearest it
    (:data:`START_LOSSES`) until a fit describes the sweep (None when none does)."""
    others = sorted((x for x in START_LOSSES if losses[0] <= x <= losses[-1]), key=lambda x: abs(x - guess))
    for x in [guess, *others]:
        fit = refit_poles(anchor, frf, var, healthy_frf, healthy_var, anchor.poles * np.sqrt(1.0 + spline(x)))
        if fit.ok:
            return fit
    return None


def size_from_poles(model: AffineModel, anchor: ModalAnchor, frf: np.ndarray, var: np.ndarray | None,
                    healthy_frf: np.ndarray, healthy_var: np.ndarray | None, start: float, level: float = 0.95
                    ) -> PoleShiftSize | None:
    """The loss of ``model``'s last parameter that explains the shift of the anchor's poles from the healthy sweep
    (``healthy_frf``, the anchor's) to the new one (``frf`` (f, P) m/N, variance ``var``); ``start`` a first
    estimate (the ranking's), from whose predicted poles the new sweep is fitted. None where the new sweep's modal
    fit fails (misfit beyond the anchor's limit or a pole at its bound)."""
    losses, curves = shift_curves(model, anchor.fe_poles)
    spline = interpolate.CubicSpline(losses, curves, axis=0)
    S = benign_shifts(model, anchor.fe_poles)
    lo = np.array([q.lo for q in model.parameters[:-1]], dtype=float)
    hi = np.array([q.hi for q in model.parameters[:-1]], dtype=float)
    guess = float(np.clip(start, losses[0], losses[-1]))
    fit: PoleRefit | None = None
    for _ in range(3):
        fit = _first_fit(anchor, spline, frf, var, healthy_frf, healthy_var, guess, losses)
        if fit is None:
            return None
        a, chi, pred = profile(fit.shift, fit.se_shift, losses, curves, S, lo, hi)
        best = int(np.argmin(chi))
        if abs(float(a[best]) - guess) <= REFIT_MOVE:
            break
        guess = float(a[best])
    assert fit is not None
    dof = max(fit.shift.size - 2, 1)
    inflation = float(max(1.0, np.sqrt(chi[best] / dof)))
    allowed = float(special.chdtri(1.0, 1.0 - level)) * inflation**2
    inside = a[chi - chi[best] <= allowed]
    sd = shift_sd(fit.se_shift, float(a[best]), spline(a[best]), lo, hi)
    return PoleShiftSize(float(a[best]), (float(inside.min()), float(inside.max())), level, inflation, fit.shift, sd,
                         pred[best], float(chi[best]), dof)
