"""Where the shaft changed and by how much: candidate elements with certified severity intervals.

For every candidate shaft element the hypothesis is "a real, local loss of the element's bending
stiffness (severity ``s`` in ``[0, s_max]``), together with benign parameters inside their ranges and a
gain in its range, explains the new data at every point used, within both sweeps' noise and the stated
bounds on the model's error": :data:`BENIGN_MODEL_ERROR` of the largest benign change the ranges allow
at the point, plus :data:`CRACK_MODEL_ERROR` and the model's own error on the healthy FRF there times the
predicted change. The parameters are the same at every point; :func:`rotorcheck.robust.severity.severity_interval`
certifies the interval of ``s`` (branch and bound with small-gain bounds) or excludes the candidate,
naming the frequencies that excluded it. The certificates hold at the stated false-alarm rate *if* the
model errs within those bounds (an assumption, checked on the simulated cases of bench/location.py).

The loss's shape: at standstill an open crack lowers the element's E (``s = 1 - modulus factor``:
``K - s K_e``, exact); in a rotating shaft a breathing crack (Mayes-Davies) acts at the excitation
frequency through its revolution average, ``K - <K_c>``, which is linear in ``(dI_xi + dI_eta) / I``:
``s = (dI_xi + dI_eta) / (4 I)`` (the element's equivalent loss), ``<K_c> = s A_e`` with ``A_e`` from the
crack model (:func:`rotorcheck.faults.crack.crack_stiffness`). Depth intervals follow from the
depth-to-compliance relations of :mod:`rotorcheck.faults.compliance` (strip method; solid shaft); for the
best ranked breathing candidates the relation is the model's own harmonic-balance response (sidebands
included) seen through the time-invariant hypothesis.

Before locating, the healthy hypothesis (``s = 0``: benign change only, the same at every point) is
tested the same way; while it is not excluded there is "no damage to locate" and no candidate ranks.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck.config import Crack, RigConfig
from rotorcheck.nominal import ChannelPair, port_label
from rotorcheck.robust.real_box import AffineModel, AffineParameter
from rotorcheck.robust.severity import SEVERITY_RULE

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
#: points used: the largest whitened changes and as many spread over the band (all channel pairs)
N_TOP, N_SPREAD = 24, 24
#: depth range of the strip relation (fraction of the diameter)
MAX_DEPTH = 0.5


def open_loss(depth: float, radius: float, length: float, poisson: float) -> float:
    """Element stiffness loss ``1 - E'/E`` of an open crack ``depth`` (fraction of the diameter) deep."""
    from rotorcheck.faults.compliance import open_crack_modulus_factor

    return 1.0 - open_crack_modulus_factor(2.0 * depth, radius, length, poisson)


def breathing_loss(depth: float, radius: float, section_length: float, poisson: float) -> float:
    """Equivalent element loss of a breathing (Mayes-Davies) crack ``depth`` deep: its revolution average
    ``(dI_xi + dI_eta) / (4 I)`` (eq. 5.25 per plane, steering ``(1 - cos theta)/2`` averaging to 1/2)."""
    from rotorcheck.faults.compliance import mayes_davies_compliances
    from rotorcheck.faults.crack import delta_i_ratio

    f_xi, f_eta = mayes_davies_compliances(2.0 * depth)
    return 0.25 * (delta_i_ratio(f_xi, radius, section_length, poisson)
                   + delta_i_ratio(f_eta, radius, section_length, poisson))


def depth_of_loss(loss: float, relation: Any) -> float | None:
    """The depth (fraction of the diameter) whose loss under ``relation(depth)`` is ``loss`` (bisection;
    the relation rises with depth); 0 for no loss, None beyond :data:`MAX_DEPTH`."""
    if not np.isfinite(loss) or loss <= 0.0:
        return 0.0
    if loss > relation(MAX_DEPTH):
        return None
    a, b = 0.0, MAX_DEPTH
    for _ in range(60):
        m = 0.5 * (a + b)
        if relation(m) < loss:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


@dataclass(frozen=True)
class CandidateResult:
    """One candidate element's certificate (severities as the element's stiffness loss, fraction)."""

    element: int
    z_start_m: float
    z_end_m: float
    status: str  # "excluded" | "consistent"
    rank: int | None
    loss_interval: tuple[float, float]  # certified (nan, nan) when excluded
    depth_interval: tuple[float | None, float | None]  # fraction of the diameter (None: beyond the relation)
    excluding_frequencies_hz: tuple[float, ...]
    witness_interval: tuple[float, float] = (float("nan"), float("nan"))  # losses that explain every point
    witnessed: bool = False  # witnesses at both ends: the interval is attained (within the step)
    loss_estimate: float | None = None  # the best fit's loss (consistent candidates)
    chi2: float | None = None  # the best fit's whitened residual sum over every point and pair

    @property
    def modulus_factor_interval(self) -> tuple[float, float]:
        return (1.0 - self.loss_interval[1], 1.0 - self.loss_interval[0])

    def to_dict(self) -> dict[str, Any]:
        def num(x: float | None) -> float | None:
            return None if x is None or not np.isfinite(x) else float(x)

        return {"element": self.element, "z_start_m": self.z_start_m, "z_end_m": self.z_end_m,
                "status": self.status, "rank": self.rank,
                "modulus_factor_interval": [num(x) for x in self.modulus_factor_interval],
                "loss_interval": [num(x) for x in self.loss_interval],
                "depth_interval": [num(x) for x in self.depth_interval],
                "excluding_frequencies_hz": [float(x) for x in self.excluding_frequencies_hz],
                "loss_witness_interval": [num(x) for x in self.witness_interval], "witnessed": self.witnessed,
                "loss_estimate": num(self.loss_estimate), "chi2": num(self.chi2)}


@dataclass
class LocationResult:
    """Candidates per element (:func:`locate`) and what they say together."""

    hypothesis: str  # "open" (standstill) | "breathing" (rotating)
    healthy_excluded: bool  # the benign-only hypothesis is excluded at every point jointly
    candidates: list[CandidateResult]
    channels: list[str]
    points_used: int
    z: float
    rule: str = SEVERITY_RULE
    notes: list[str] = field(default_factory=list)
    healthy_excluding_hz: tuple[float, ...] = ()  # points that excluded the healthy hypothesis
    single_channel: LocationResult | None = None  # the same from the rig's actuator -> sensor pair alone

    @property
    def best(self) -> CandidateResult | None:
        ranked = [c for c in self.candidates if c.rank == 1]
        return ranked[0] if ranked else None

    def summary(self) -> str:
        """One line: where and how deep, and what is excluded."""
        excluded = [c.element for c in self.candidates if c.status == "excluded"]
        ex = f"; elements {_ranges(excluded)} excluded" if excluded else "; no element excluded"
        if not self.healthy_excluded:
            return "no damage to locate: benign change inside the ranges explains every point" + ex
        b = self.best
        if b is None:
            return "every candidate element is excluded: the change is no stiffness loss of one element" + ex
        text = depth_text(*b.depth_interval)
        depth = f", depth {text} of diameter" if text else ""
        mf = b.modulus_factor_interval
        return (f"crack most likely in element {b.element} ({b.z_start_m:.3f}-{b.z_end_m:.3f} m), stiffness loss "
                f"{100 * b.loss_interval[0]:.1f}-{100 * b.loss_interval[1]:.1f} % (modulus factor "
                f"{mf[0]:.3f}-{mf[1]:.3f}){depth}" + ex)

    def to_dict(self) -> dict[str, Any]:
        b = self.best
        return {"best_element": None if b is None else b.element, "hypothesis": self.hypothesis,
                "healthy_excluded": self.healthy_excluded,
                "healthy_excluding_frequencies_hz": list(self.healthy_excluding_hz), "summary": self.summary(),
                "channels": self.channels, "points_used": self.points_used, "point_quantile_z": self.z,
                "model_relative_error": CRACK_MODEL_ERROR, "rule": self.rule, "notes": list(self.notes),
                "candidates": [c.to_dict() for c in self.candidates],
                **({} if self.single_channel is None else {"single_channel": self.single_channel.to_dict()})}


def depth_text(lo: float | None, hi: float | None) -> str:
    """A crack-depth interval (fractions of the diameter) as text: "34-45 %", "at least 50 %" (beyond the
    strip relation's range), "" when unknown."""
    if lo is None:
        return ""
    if hi is None:
        return f"at least {100 * lo:.0f} %"
    return f"{100 * lo:.0f}-{100 * hi:.0f} %"


def _ranges(xs: Sequence[int]) -> str:
    """1, 2, 3, 6, 8, 9 -> '1-3, 6, 8-9'."""
    out: list[str] = []
    xs = sorted(xs)
    i = 0
    while i < len(xs):
        j = i
        while j + 1 < len(xs) and xs[j + 1] == xs[j] + 1:
            j += 1
        out.append(str(xs[i]) if i == j else f"{xs[i]}-{xs[j]}")
        i = j + 1
    return ", ".join(out)


def _loss_shape(config: RigConfig, sys0: Any, element: int, speed_rpm: float, hypothesis: str
                ) -> tuple[np.ndarray, np.ndarray | None]:
    """``(A_K, A_D)``: the change of K (and of C where damping follows K affinely) per unit loss of
    ``element`` (N/m per 1), to be subtracted; A_D None where the damping is held (modal damping);
    ``sys0`` the assembled ``config``."""
    from rotorcheck.fe.assembly import build_system

    _, C0, _, K0 = sys0.matrices(speed_rpm)
    if hypothesis == "breathing":
        from rotorcheck.faults.crack import crack_stiffness

        ref = _breathing_crack(config, element, 0.25)
        ck = crack_stiffness(sys0, ref)
        s_ref = 0.25 * (ck.delta_xi + ck.delta_eta)
        return ck.scatter(ck.mean(), sys0.n_dof) / s_ref, None
    _, C1, _, K1 = build_system(config, modulus_factors={element: 0.5}).matrices(speed_rpm)
    _, Cq, _, _ = build_system(config, modulus_factors={element: 0.75}).matrices(speed_rpm)
    dC = (C0 - C1) / 0.5
    affine = np.allclose(0.5 * (C0 + C1), Cq, rtol=0.0, atol=1e-9 * max(np.abs(C0).max(), 1e-300))
    return (K0 - K1) / 0.5, (dC if affine and np.abs(dC).max() > 0 else None)


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


def _breathing_crack(config: RigConfig, element: int, depth: float, length: float | None = None) -> Crack:
    """A Mayes-Davies crack ``depth`` (fraction of the diameter) deep in ``element`` (section length by
    :func:`section_length`; Poisson ratio the rig's crack's, else the material's)."""
    own = next((f for f in config.faults.values() if isinstance(f, Crack) and f.model == "mayes_davies"), None)
    return Crack(element=element, model="mayes_davies", depth_ratio=2.0 * depth,
                 section_length=section_length(config, element, length),
                 poisson=None if own is None else own.poisson)


def _relation(config: RigConfig, element: int, hypothesis: str, length: float | None = None) -> Any:
    """``depth -> loss`` for ``element`` (None for a hollow element: the strip relation needs a solid one)."""
    sh = next(e for e in config.shaft if e.start == element)
    if sh.inner_diameter > 0:
        return None
    radius = 0.5 * sh.outer_diameter
    l_e = config.stations[element] - config.stations[element - 1]
    nu = config.materials[sh.material].nu
    if hypothesis == "breathing":
        l_c = section_length(config, element, length)
        own = next((f for f in config.faults.values() if isinstance(f, Crack) and f.model == "mayes_davies"), None)
        nu_c = own.poisson if own is not None and own.poisson is not None else nu
        return lambda d: breathing_loss(d, radius, l_c, nu_c)
    own = next((f for f in config.faults.values() if isinstance(f, Crack) and f.model == "open"), None)
    l_o = own.section_length if own is not None and own.section_length is not None else l_e
    return lambda d: open_loss(d, radius, l_o, nu)


def natural_frequencies_hz(model: AffineModel) -> np.ndarray:
    """The undamped-equivalent natural frequencies |lambda| / 2 pi (Hz) of ``model`` at its parameters'
    zero (state space of M, D, K; each conjugate pair once)."""
    from scipy.linalg import eig

    n = model.K.shape[0]
    Minv = np.linalg.inv(model.M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ model.K, -Minv @ model.D]])
    lam = eig(A, right=False)
    lam = lam[lam.imag > 0]
    return np.sort(np.abs(lam)) / (2.0 * np.pi)


def _near_sideband(model: AffineModel, freq_hz: np.ndarray, speed_rpm: float) -> np.ndarray:
    """(f,) bool: a sideband f +- Omega, f +- 2 Omega within :data:`SIDEBAND_GUARD` of a natural frequency."""
    fn = natural_frequencies_hz(model)
    spin = abs(speed_rpm) / 60.0
    out = np.zeros(np.asarray(freq_hz).size, dtype=bool)
    for k in (-2, -1, 1, 2):
        side = np.abs(np.asarray(freq_hz, dtype=float) + k * spin)
        out |= np.any(np.abs(side[:, None] - fn[None, :]) <= SIDEBAND_GUARD * fn[None, :], axis=1)
    return out


#: depths (fraction of the diameter) at which the harmonic-balance depth relation is computed
HB_DEPTHS = (0.05, 0.15, 0.25, 0.35, 0.45, 0.5)


def _hb_relation(config: RigConfig, sysm: Any, model: AffineModel, element: int, speed_rpm: float, pts: Any,
                 length: float | None) -> Any:
    """``depth -> loss`` of a breathing crack in ``element`` as the hypothesis sees it: at each of
    :data:`HB_DEPTHS`, the loss whose time-invariant model (``model``, benign parameters at 0) best
    reproduces (least squares of the relative change at the points ``pts``) the model's own harmonic-
    balance response to a Mayes-Davies crack of that depth (sidebands to 4 x the spin frequency);
    interpolated linearly, 0 at depth 0, kept non-decreasing; ``sysm`` the assembled ``config``."""
    from scipy.optimize import minimize_scalar

    from rotorcheck.faults.crack import crack_stiffness
    from rotorcheck.faults.harmonic_balance import HBSolver
    from rotorcheck.robust.severity import point_receptances

    f = pts.w / (2.0 * np.pi)
    in_dofs = [int(np.flatnonzero(b)[0]) for b in pts.b]
    out_dofs = [int(np.flatnonzero(c)[0]) for c in pts.c]
    p = len(model.parameters)
    g0 = pts.g0
    losses = [0.0]
    for d in HB_DEPTHS:
        ck = crack_stiffness(sysm, _breathing_crack(config, element, d, length))
        hb = np.zeros(f.size, dtype=complex)
        for dof in sorted(set(in_dofs)):
            at = np.array([i == dof for i in in_dofs])
            outs = sorted({o for o, a in zip(out_dofs, at) if a})
            res = HBSolver(sysm, ck, speed_rpm, dof, outs, 4).solve(f[at]).fundamental[:, :, 0]
            hb[at] = res[np.arange(int(at.sum())), [outs.index(o) for o, a in zip(out_dofs, at) if a]]
        target = hb / g0

        def cost(x: float, want: np.ndarray = target) -> float:
            theta = np.zeros(p)
            theta[-1] = x
            return float(np.sum(np.abs(point_receptances(model, pts, theta) / g0 - want) ** 2))

        losses.append(float(minimize_scalar(cost, bounds=(0.0, MAX_LOSS), method="bounded",
                                            options={"xatol": 1e-4}).x))
    depths = np.r_[0.0, HB_DEPTHS]
    table = np.maximum.accumulate(np.array(losses))
    return lambda d: float(np.interp(d, depths, table))


def _select_points(change2: np.ndarray, n_top: int, n_spread: int) -> np.ndarray:
    """Flat indices into (f, P): the ``n_top`` largest whitened changes and ``n_spread`` more spread evenly
    over the rest (frequency-major)."""
    flat = np.asarray(change2).reshape(-1)
    ok = np.flatnonzero(np.isfinite(flat))
    top = ok[np.argsort(flat[ok])[::-1][:n_top]]
    rest = np.setdiff1d(ok, top)
    spread = rest[np.linspace(0, rest.size - 1, min(n_spread, rest.size)).round().astype(int)] if rest.size else rest
    return np.unique(np.r_[top, spread])


def locate(config: RigConfig, box: Any, pairs: Sequence[ChannelPair], freq_hz: np.ndarray, speed_rpm: float,
           t_new: np.ndarray, var_new: np.ndarray, t_healthy: np.ndarray, var_healthy: np.ndarray,
           benign_envelope: np.ndarray, false_alarm: float = 0.01, elements: Sequence[int] | None = None,
           step: float = 0.01, slices: int = 12, max_boxes: int = 8, refine: int = 2,
           refine_boxes: int = 48, crack_section_length: float | None = None,
           exclude: np.ndarray | None = None) -> LocationResult:
    """Candidates per element (module docstring). ``box`` the benign parameters as a
    :class:`rotorcheck.signatures.BenignBox` (its model at ``speed_rpm``); ``t_*``, ``var_*`` (f, P) the
    new and healthy FRFs (m/N) and the variances of their means (m^2/N^2), one column per pair of
    ``pairs``; ``benign_envelope`` (P f,) m/N the largest benign change the ranges allow at each point;
    ``elements`` default: every shaft element; ``step`` the width to which the severity's end slices are
    halved (loss, fraction); ``slices`` its first division; ``max_boxes`` the branch and bound's budget
    per slice for every candidate, ``refine_boxes`` for a second pass on the ``refine`` best ranked (a
    larger budget only narrows a certified interval); ``crack_section_length`` (m) the breathing crack's
    section length for the depth relation (:func:`section_length`); ``exclude`` (f,) bool: points never used
    (on a shaft harmonic).
    ``false_alarm``: the chance that the true element is excluded when its hypothesis holds and the model
    errs within its stated bounds (Sidak over the points used)."""
    from rotorcheck.robust.measured import io_model_error
    from rotorcheck.robust.severity import Points, severity_interval
    from rotorcheck.signatures import candidate_elements

    f = np.asarray(freq_hz, dtype=float)
    nf, n_pairs = np.asarray(t_new).reshape(f.size, -1).shape
    t_new, var_new, t_h, var_h = (np.asarray(x).reshape(nf, n_pairs) for x in (t_new, var_new, t_healthy,
                                                                                 var_healthy))
    a = BENIGN_MODEL_ERROR * np.asarray(benign_envelope, dtype=float).reshape(n_pairs, nf).T
    hypothesis = "breathing" if speed_rpm != 0.0 else "open"
    views = [box.for_pair(p) if n_pairs > 1 else box for p in pairs]
    omega = 2.0 * np.pi * f
    lo_b = np.array([q.lo for q in box.model.parameters], dtype=float)
    hi_b = np.array([q.hi for q in box.model.parameters], dtype=float)
    B = np.stack([v.model.b for v in views], axis=1)
    Cm = np.stack([v.model.c for v in views], axis=1)
    g_zero = _receptances(box.model, omega, np.zeros(lo_b.size), B, Cm)
    err = np.stack([io_model_error(g_zero[:, j], t_h[:, j], HALFWIDTH) for j in range(n_pairs)], axis=1)
    change2 = np.abs(t_new - t_h) ** 2 / (var_new + var_h + a**2)
    trusted = err <= MAX_MODEL_ERROR
    if hypothesis == "breathing":
        trusted &= ~_near_sideband(box.model, f, speed_rpm)[:, None]
    if exclude is not None:
        trusted &= ~np.asarray(exclude, dtype=bool).reshape(nf, 1)
    chosen = _select_points(np.where(trusted, change2, np.nan), N_TOP, N_SPREAD)
    m = chosen.size
    z = float(np.sqrt(-np.log1p(-(1.0 - false_alarm) ** (1.0 / max(m, 1)))))  # |r|^2/sigma^2 ~ Exp(1)
    ks, js = chosen // n_pairs, chosen % n_pairs
    pts = Points(omega[ks], g_zero[ks, js], t_new[ks, js], t_h[ks, js], var_new[ks, js], var_h[ks, js], z,
                 np.zeros(m), float(box.gain[0]), float(box.gain[1]), a[ks, js], CRACK_MODEL_ERROR + err[ks, js],
                 B.T[js], Cm.T[js])
    notes = [f"{m} points of {nf * n_pairs} used (the {N_TOP} largest whitened changes and the rest spread over "
             f"the band, among the {int(trusted.sum())} where the model errs on the healthy FRF by at most "
             f"{MAX_MODEL_ERROR:.0%}): a subset keeps every certificate sound, only less sharp; the prediction's "
             f"error bound there: {BENIGN_MODEL_ERROR:.0%} of the largest benign change the ranges allow, plus "
             f"{CRACK_MODEL_ERROR:.0%} and the model's error on the healthy FRF times the predicted change"]
    els = tuple(elements) if elements is not None else candidate_elements(config)

    def model_with(element: int) -> AffineModel:
        A_K, A_D = _loss_shape(config, box.system, element, speed_rpm, hypothesis)
        terms: tuple[tuple[str, np.ndarray], ...] = (("K", -A_K),) + ((("D", -A_D),) if A_D is not None else ())
        return AffineModel(box.model.M, box.model.D, box.model.K, box.model.b, box.model.c,
                           (*box.model.parameters, AffineParameter(f"loss_{element}", terms, 0.0, MAX_LOSS)))

    p = lo_b.size
    lo, hi = np.r_[lo_b, 0.0], np.r_[hi_b, MAX_LOSS]
    models = {e: model_with(e) for e in els}
    # the healthy hypothesis: no loss (the same model whatever the element), benign parameters in their box
    healthy = severity_interval(models[els[0]], pts, lo, np.r_[hi_b, 0.0], p, step, 1, 4 * refine_boxes)
    healthy_excluded = healthy.status == "excluded"
    results = {e: severity_interval(models[e], pts, lo, hi, p, step, slices, max_boxes) for e in els}
    fits = {e: _fit(models[e], B, Cm, g_zero, omega, t_new, t_h, var_new, var_h, a, CRACK_MODEL_ERROR + err,
                    trusted, box.gain, (r.lower, r.upper))
            for e, r in results.items() if r.status == "consistent" and healthy_excluded}
    order = sorted(fits, key=lambda e: fits[e][1])
    for e in order[:refine]:
        results[e] = severity_interval(models[e], pts, lo, hi, p, step, slices, refine_boxes)
    order = [e for e in order if results[e].status == "consistent"]
    cands = []
    for e, r in results.items():
        rel = _relation(config, e, hypothesis, crack_section_length)
        if hypothesis == "breathing" and rel is not None and e in order[:refine]:
            rel = _hb_relation(config, box.system, models[e], e, speed_rpm, pts, crack_section_length)
        d0, d1 = ((depth_of_loss(r.lower, rel), depth_of_loss(r.upper, rel)) if r.status == "consistent"
                  and rel is not None else (None, None))
        freqs = tuple(dict.fromkeys(float(f[ks[k]]) for k in r.excluding))
        fit = fits.get(e) if r.status == "consistent" else None
        cands.append(CandidateResult(e, float(config.stations[e - 1]), float(config.stations[e]), r.status,
                                     order.index(e) + 1 if e in order else None, (r.lower, r.upper), (d0, d1),
                                     freqs if r.status == "excluded" else (), r.witness_interval, r.witnessed,
                                     None if fit is None else fit[0], None if fit is None else fit[1]))
    if hypothesis == "breathing" and order:
        notes.append(f"depths of the {min(refine, len(order))} best ranked: the loss that best reproduces the model's "
                     "harmonic-balance response to a breathing crack of each depth (its sidebands included: at 50 % "
                     "depth on the crack rig 15-20 % more than the revolution average); of the others: the average")
    if not healthy_excluded:
        notes.append("the healthy hypothesis (no loss; benign parameters in their ranges, the same at every point) "
                     "is not excluded: no candidate ranks")
    channels = [port_label(q.output) + "<-" + port_label(q.input) for q in pairs]
    return LocationResult(hypothesis, healthy_excluded, cands, channels, m, z, notes=notes,
                          healthy_excluding_hz=tuple(dict.fromkeys(float(f[ks[k]]) for k in healthy.excluding)))


def _fit(model: AffineModel, B: np.ndarray, Cm: np.ndarray, g0: np.ndarray, omega: np.ndarray, t_new: np.ndarray,
         t_h: np.ndarray, var_new: np.ndarray, var_h: np.ndarray, a: np.ndarray, rel: np.ndarray, used: np.ndarray,
         gain: tuple[float, float], loss: tuple[float, float]) -> tuple[float, float]:
    """``(loss, chi2)``: the bounded least-squares fit of the benign parameters, the loss (inside its
    certified interval) and the gain at the points ``used`` (f, P) of every pair (inputs and outputs the
    columns of ``B``, ``Cm``; ``g0`` (f, P) their receptances at no change), each residual over its
    standard deviation with the model's error bounds in it: ``var_new + var_h + a^2 + (rel |T_h| |gain
    rho - 1|)^2``; two starts along the loss interval."""
    from scipy.optimize import least_squares

    p = len(model.parameters)
    lo = np.array([q.lo for q in model.parameters[:-1]] + [loss[0], gain[0]])
    hi = np.array([q.hi for q in model.parameters[:-1]] + [loss[1], gain[1]])
    hi = np.where(hi > lo, hi, lo + 1e-12)  # least_squares needs lo < hi (a fixed gain)

    def resid(x: np.ndarray) -> np.ndarray:
        g = _receptances(model, omega, x[:p], B, Cm)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rho = np.where(np.abs(g0) > 0, g / g0, 1.0)
            pred = x[p] * t_h * rho
            sd = np.sqrt(var_new + var_h + a**2 + (rel * np.abs(t_h) * np.abs(x[p] * rho - 1.0)) ** 2)
            r = ((t_new - pred) / sd)[used]
        return np.r_[r.real, r.imag]

    best: tuple[float, float] | None = None
    for start in (1.0 / 3.0, 2.0 / 3.0):  # the loss moves resonances: two starts along its interval
        x0 = 0.5 * (lo + hi)
        x0[p - 1] = lo[p - 1] + start * (hi[p - 1] - lo[p - 1])
        sol = least_squares(resid, x0, bounds=(lo, hi), x_scale=hi - lo, max_nfev=20)
        if best is None or 2.0 * sol.cost < best[1]:
            best = (float(sol.x[p - 1]), float(2.0 * sol.cost))
    assert best is not None
    return best


def _receptances(model: AffineModel, omega: np.ndarray, theta: np.ndarray, B: np.ndarray, Cm: np.ndarray
                 ) -> np.ndarray:
    """(f, P) receptances ``c_j^T Z(w, theta)^-1 b_j`` of each pair j (columns of B, Cm), batched over w."""
    Z = model.dynamic_stiffness_stack(omega, theta)
    X = np.linalg.solve(Z, np.broadcast_to(B, (omega.size, *B.shape)).astype(complex))
    return np.einsum("nj,fnj->fj", Cm, X)
