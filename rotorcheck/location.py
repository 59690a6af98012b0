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

The candidates are ranked by :func:`rotorcheck.ranking.rank_elements` (their relative likelihoods, the
ranking ``detect`` reports too); the certificates add what is excluded (a certified exclusion drops a
candidate from the ranks, the others keep their order) and the certified intervals. The healthy
hypothesis (``s = 0``: benign change only, the same at every point) is certified the same way. Where
there is damage (the detector's verdict, else the healthy hypothesis excluded) the result always says
where as far as the data allow (:meth:`LocationResult.summary`): the most likely element when its
relative likelihood is at least :data:`LOCATED_LIKELIHOOD`, else the ranked candidates with theirs, or
"not locatable" when no element explains the change better than benign change alone by
:data:`MIN_EVIDENCE` chi-square units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck.config import Crack, RigConfig
from rotorcheck.faults.compliance import mayes_davies_compliances, open_crack_modulus_factor
from rotorcheck.faults.crack import crack_stiffness, delta_i_ratio
from rotorcheck.faults.harmonic_balance import HBSolver
from rotorcheck.nominal import ChannelPair, port_label
from rotorcheck.progress import Progress, report
from rotorcheck.ranking import (
    BENIGN_MODEL_ERROR,
    CRACK_MODEL_ERROR,
    INTERVAL_LEVEL,
    MAX_LOSS,
    MAX_MODEL_ERROR,
    Ranking,
    SweepChange,
    breathing_crack,
    loss_model,
    rank_elements,
    section_length,
)
from rotorcheck.robust.affine import AffineModel, coupled_blocks
from rotorcheck.robust.box_test import Points, point_receptances
from rotorcheck.robust.severity import SEVERITY_RULE, severity_interval
from rotorcheck.signatures import candidate_elements
from rotorcheck.sizing import POLE_SHIFTS

#: a located element: relative likelihood at least this (else the ranked candidates are the answer)
LOCATED_LIKELIHOOD = 0.5
#: chi-square units the best element's loss must remove over benign change alone to rank anything
MIN_EVIDENCE = 4.0

#: certificate points: the largest whitened changes and as many spread over the band (all channel pairs)
N_TOP, N_SPREAD = 24, 24
#: detect's diagnosis certifies the best ranked candidates in order until one is consistent, at most this many
BEST_CERTIFIED = 3
#: depth range of the strip relation (fraction of the diameter)
MAX_DEPTH = 0.5


def open_loss(depth: float, radius: float, length: float, poisson: float) -> float:
    """Element stiffness loss ``1 - E'/E`` of an open crack ``depth`` (fraction of the diameter) deep."""
    return 1.0 - open_crack_modulus_factor(2.0 * depth, radius, length, poisson)


def breathing_loss(depth: float, radius: float, section_length: float, poisson: float) -> float:
    """Equivalent element loss of a breathing (Mayes-Davies) crack ``depth`` deep: its revolution average
    ``(dI_xi + dI_eta) / (4 I)`` (eq. 5.25 per plane, steering ``(1 - cos theta)/2`` averaging to 1/2)."""
    f_xi, f_eta = mayes_davies_compliances(2.0 * depth)
    return 0.25 * (delta_i_ratio(f_xi, radius, section_length, poisson)
                   + delta_i_ratio(f_eta, radius, section_length, poisson))


def depth_of_loss(loss: float, relation: Any) -> float | None:
    """The depth (fraction of the diameter) whose loss under ``relation(depth)`` is ``loss`` (Brent's root
    bracketed in [1e-9, MAX_DEPTH] to 1e-10; the relation rises with depth); 0 for no loss, None beyond
    :data:`MAX_DEPTH`."""
    from scipy.optimize import brentq  # lazy: scipy.optimize only for a depth relation

    if not np.isfinite(loss) or loss <= 0.0:
        return 0.0
    top = relation(MAX_DEPTH)
    if loss > top:
        return None
    if loss == top:
        return float(MAX_DEPTH)
    shallow = 1e-9  # the relations need a positive depth
    if relation(shallow) >= loss:
        return shallow
    return float(brentq(lambda d: relation(d) - loss, shallow, MAX_DEPTH, xtol=1e-10, rtol=1e-12))


def depth_interval(lower: float, upper: float, relation: Any) -> tuple[float | None, float | None]:
    """The depths (fractions of the diameter) of the loss interval ``[lower, upper]`` under ``relation``: the
    upper end None beyond :data:`MAX_DEPTH` (not bounded), the lower end :data:`MAX_DEPTH` there (a loss beyond
    the relation's range means a depth of at least its deepest)."""
    lo = depth_of_loss(lower, relation)
    hi = lo if upper == lower else depth_of_loss(upper, relation)  # a best fit: one depth, found once
    return (float(MAX_DEPTH) if lo is None else lo), hi


def _basis_text(basis: str) -> str:
    """What an estimate's interval rests on, as the headline says it."""
    return "from the measured pole shifts" if basis == POLE_SHIFTS else "under the model's crack signature"


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
    loss_estimate: float | None = None  # the size estimate (:attr:`rotorcheck.ranking.ElementFit.size_estimate`)
    chi2: float | None = None  # the best fit's whitened residual sum at the fit points
    likelihood: float | None = None  # relative likelihood among the ranked candidates (None: excluded)
    estimate_interval: tuple[float, float] | None = None  # the best fit's profile interval (ranking.INTERVAL_RULE)
    estimate_depth_interval: tuple[float | None, float | None] | None = None  # its depths (fraction of diameter)
    estimate_basis: str = ""  # what the estimate's interval rests on: "pole shifts" | "FRF fit" (ranking)

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
                "loss_estimate": num(self.loss_estimate), "chi2": num(self.chi2),
                "relative_likelihood": num(self.likelihood),
                **({} if self.estimate_interval is None else
                   {"loss_estimate_interval": [num(x) for x in self.estimate_interval],
                    "depth_estimate_interval": [num(x) for x in self.estimate_depth_interval or (None, None)],
                    "estimate_interval_level": INTERVAL_LEVEL, "estimate_basis": self.estimate_basis})}


@dataclass
class LocationResult:
    """Candidates per element (:func:`locate`) and what they say together: the ranking (relative
    likelihoods), what the certificates exclude and their intervals (``certified``; without them, the
    ranking's best fits only: ``detect``'s diagnosis), and the detector's verdict where known."""

    hypothesis: str  # "open" (standstill) | "breathing" (rotating)
    healthy_excluded: bool | None  # the benign-only hypothesis is excluded at every point jointly (None: not tested)
    candidates: list[CandidateResult]
    channels: list[str]
    points_used: int
    z: float
    rule: str = SEVERITY_RULE
    notes: list[str] = field(default_factory=list)
    healthy_excluding_hz: tuple[float, ...] = ()  # points that excluded the healthy hypothesis
    single_channel: LocationResult | None = None  # the same from the rig's actuator -> sensor pair alone
    ranking: Ranking | None = None
    certified: bool = True  # the certificates were computed (locate); else the ranking alone (detect)
    damage: bool | None = None  # the detector's verdict is damage (None: not known; the certificate decides)
    sensor_advice: str = ""  # when not locatable: the sensor set that would locate it
    sensor_advice_detail: dict[str, Any] | None = None  # its figures (rotorcheck.sensor_advice.SensorAdvice)

    @property
    def damage_found(self) -> bool:
        """Damage to locate: the detector's verdict, else the healthy hypothesis certified excluded."""
        return bool(self.healthy_excluded) if self.damage is None else self.damage

    @property
    def ranked(self) -> list[CandidateResult]:
        """The ranked candidates, best first."""
        return sorted((c for c in self.candidates if c.rank is not None), key=lambda c: c.rank or 0)

    @property
    def best(self) -> CandidateResult | None:
        """The answer to where: the best ranked candidate the certificates keep, or the ranking's best fit when its
        certificate excludes it (:attr:`contradicted`: the model errs beyond its bounds, so the exclusions may not
        hold and the fit stays the best evidence; ``detect`` and ``locate`` name it alike, whichever pass excluded
        it)."""
        if not self.damage_found:
            return None
        bad = self.contradicted
        if bad is not None:
            return bad
        ranked = self.ranked
        return ranked[0] if ranked else None

    @property
    def locatable(self) -> bool:
        """Some element explains the change better than benign change alone (by :data:`MIN_EVIDENCE`)."""
        if self.ranking is None:  # a result without a ranking (made by hand): its ranks are its word
            return bool(self.ranked)
        return bool(self.ranked) and self.ranking.evidence_over_benign >= MIN_EVIDENCE

    @property
    def kind(self) -> str:
        """What the result says: "nothing" (no damage), "located" (one element, likelihood at least
        :data:`LOCATED_LIKELIHOOD`), "ranked" (candidates with likelihoods), "not locatable"."""
        if not self.damage_found:
            return "nothing"
        if not self.locatable:
            return "not locatable"
        b = self.ranked[0]
        if self.contradicted is not None:
            return "ranked"  # the best fit is certified excluded: the model errs beyond its bounds somewhere
        return "located" if b.likelihood is None or b.likelihood >= LOCATED_LIKELIHOOD else "ranked"

    @property
    def contradicted(self) -> CandidateResult | None:
        """The best fit of the ranking (relative likelihood over every candidate at least
        :data:`LOCATED_LIKELIHOOD`) when its certificate excludes it: the fit and the certificate disagree, so the
        model errs beyond its stated bounds at the excluding points (a support, a mode the model lacks); None
        when they agree."""
        if self.ranking is None or not self.ranking.fits or not self.damage_found:
            return None
        top = self.ranking.fits[0]
        c = next((x for x in self.candidates if x.element == top.element), None)
        if c is None or c.status != "excluded" or top.likelihood < LOCATED_LIKELIHOOD:
            return None
        return c

    def summary(self) -> str:
        """One line: where and how deep, how sure, and what is excluded."""
        excluded = [c.element for c in self.candidates if c.status == "excluded"]
        ex = ""
        if self.certified:
            ex = ((f"; element {excluded[0]} excluded" if len(excluded) == 1 else
                   f"; elements {_ranges(excluded)} excluded") if excluded else "; no element excluded")
        kind = self.kind
        if kind == "nothing":
            why = ("benign change inside the ranges explains every point" if self.damage is None
                   else "the detector's verdict is not damage")
            return f"no damage to locate: {why}" + ex
        ranked = self.ranked
        if not ranked:
            return ("damage, but every candidate element is excluded: the change is no stiffness loss of one "
                    "element" + ex)
        others = ", ".join(f"element {c.element} {c.likelihood:.2f}" for c in ranked[1:3] if c.likelihood is not None)
        if kind == "not locatable":
            advice = f"; {self.sensor_advice}" if self.sensor_advice else ""
            return ("damage not locatable with these sensors: no element's stiffness loss explains the change better "
                    f"than benign change alone (best: element {ranked[0].element}, " +
                    ", ".join(f"{c.element}" for c in ranked[1:4]) + " about as likely)" + advice + ex)
        b = ranked[0]
        lead = "crack most likely in element" if kind == "located" else "crack location uncertain: ranked, element"
        sure = "" if b.likelihood is None else f"; relative likelihood {b.likelihood:.2f}"
        head = (f"{lead} {b.element} ({b.z_start_m:.3f}-{b.z_end_m:.3f} m{sure}"
                + (f"; next: {others}" if others else "") + ")")
        bad = self.contradicted
        if bad is not None and self.ranking is not None:
            # the answer stays the best fit (best); what the certificate keeps is said beside it
            at = ", ".join(f"{x:.1f}" for x in bad.excluding_frequencies_hz[:4])
            lik = self.ranking.fits[0].likelihood
            head = (f"crack location uncertain: the best fit is element {bad.element} ({bad.z_start_m:.3f}-"
                    f"{bad.z_end_m:.3f} m; relative likelihood {lik:.2f} over every element) "
                    f"but its certificate excludes it at {at} Hz, so the model errs beyond its stated bounds there and "
                    f"the exclusions may not hold; of the elements the certificate keeps, element {b.element} ranks "
                    "first" + (f" ({b.likelihood:.2f})" if b.likelihood is not None else ""))
            b = bad
        certified = (f"{100 * b.loss_interval[0]:.1f}-{100 * b.loss_interval[1]:.1f} % certified"
                     if b.status == "consistent" else "")
        if b.status == "excluded":
            est = b.estimate_interval
            size = (f", stiffness loss about {100 * (b.loss_estimate or 0.0):.1f} % (best fit"
                    + (f"; {INTERVAL_LEVEL:.0%} interval {100 * est[0]:.1f}-{100 * est[1]:.1f} % "
                       + _basis_text(b.estimate_basis) if est is not None else "")
                    + "; no certified interval: its certificate excludes it)")
        elif self.certified and certified:
            mf = b.modulus_factor_interval
            size = f", stiffness loss {certified} (modulus factor {mf[0]:.3f}-{mf[1]:.3f}"
            size += f"; best fit {100 * b.loss_estimate:.1f} %)" if b.loss_estimate is not None else ")"
        elif b.estimate_interval is not None:  # detect: the estimate first, then what is certified
            lo_e, hi_e = b.estimate_interval
            size = (f", stiffness loss about {100 * (b.loss_estimate or 0.0):.1f} % ({INTERVAL_LEVEL:.0%} interval "
                    f"{100 * lo_e:.1f}-{100 * hi_e:.1f} % {_basis_text(b.estimate_basis)}"
                    + (f"; {certified}, rotorcheck locate narrows it)" if certified else
                       "; certified intervals: rotorcheck locate)"))
        else:
            size = (f", stiffness loss about {100 * (b.loss_estimate or 0.0):.1f} % (best fit; "
                    + (f"{certified}; rotorcheck locate narrows it)" if certified else
                       "certified intervals: rotorcheck locate)"))
        shown, whose = b.depth_interval, ""
        if not self.certified and b.estimate_depth_interval is not None:
            shown, whose = b.estimate_depth_interval, " (by the estimate's interval)"
        text = depth_text(*shown)
        depth = f", depth {text} of diameter{whose}" if text else ""
        caveat = ("; benign change alone is not certified excluded at the points the certificate uses"
                  if self.certified and self.healthy_excluded is False else "")
        return head + size + depth + caveat + ex

    def to_dict(self) -> dict[str, Any]:
        b = self.best
        return {"best_element": None if b is None else b.element, "kind": self.kind, "hypothesis": self.hypothesis,
                "healthy_excluded": self.healthy_excluded, "certified": self.certified,
                "healthy_excluding_frequencies_hz": list(self.healthy_excluding_hz), "summary": self.summary(),
                "channels": self.channels, "points_used": self.points_used, "point_quantile_z": self.z,
                "model_relative_error": CRACK_MODEL_ERROR, "rule": self.rule, "notes": list(self.notes),
                "candidates": [c.to_dict() for c in self.candidates],
                **({} if self.ranking is None else {"ranking": self.ranking.to_dict()}),
                **({} if self.contradicted is None else
                   {"contradicted_best_fit": {"element": self.contradicted.element,
                                              "excluding_frequencies_hz":
                                                  list(self.contradicted.excluding_frequencies_hz)}}),
                **({"sensor_advice": self.sensor_advice} if self.sensor_advice else {}),
                **({"sensor_advice_detail": self.sensor_advice_detail} if self.sensor_advice_detail else {}),
                **({} if self.single_channel is None else {"single_channel": self.single_channel.to_dict()})}


def depth_text(lo: float | None, hi: float | None) -> str:
    """A crack-depth interval (fractions of the diameter) as text: "34-45 %", "at least 50 %" (beyond the
    strip relation's range), "" when unknown."""
    if lo is None or (hi is None and lo <= 0.0):
        return ""  # nothing known (no relation, or not bounded either way)
    if hi is None:
        return f"at least {100 * lo:.0f} %"
    a, b = f"{100 * lo:.0f}", f"{100 * hi:.0f}"
    return f"about {a} %" if a == b else f"{a}-{b} %"  # a best-fit depth (no interval) reads as one figure


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


#: depths (fraction of the diameter) at which the harmonic-balance depth relation is computed
HB_DEPTHS = (0.05, 0.15, 0.25, 0.35, 0.45, 0.5)


def _hb_relation(config: RigConfig, sysm: Any, model: AffineModel, element: int, speed_rpm: float, pts: Any,
                 length: float | None) -> Any:
    """``depth -> loss`` of a breathing crack in ``element`` as the hypothesis sees it: at each of
    :data:`HB_DEPTHS`, the loss whose time-invariant model (``model``, benign parameters at 0) best
    reproduces (least squares of the relative change at the points ``pts`` of the pairs within one bending
    plane; with the cross pairs an x/y sweep read a 5 % deep crack as a 42 % loss) the model's own harmonic-balance
    response to a Mayes-Davies crack of that depth (sidebands to 4 x the spin frequency);
    interpolated linearly, 0 at depth 0, kept non-decreasing; ``sysm`` the assembled ``config``."""
    from scipy.optimize import minimize_scalar  # lazy: scipy.optimize only for the harmonic-balance relation

    f = pts.w / (2.0 * np.pi)
    in_dofs = [int(np.flatnonzero(b)[0]) for b in pts.b]
    out_dofs = [int(np.flatnonzero(c)[0]) for c in pts.c]
    p = len(model.parameters)
    g0 = pts.g0
    # the pairs within one bending plane (the planes the rotor has at rest): a cross pair (x force, y probe) answers
    # through the spin and through the breathing crack's own coupling of the planes, which a time-invariant loss
    # cannot make: near its small responses that relative change would decide the fit
    M, C, _, K = sysm.matrices(0.0)
    plane = np.empty(M.shape[0], dtype=int)
    for k, members in enumerate(coupled_blocks([M, C, K])):
        plane[members] = k
    use = np.array([plane[i] == plane[o] for i, o in zip(in_dofs, out_dofs)])
    if not np.any(use):
        use[:] = True
    losses = [0.0]
    for d in HB_DEPTHS:
        ck = crack_stiffness(sysm, breathing_crack(config, element, d, length))
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
            return float(np.sum(np.abs(point_receptances(model, pts, theta) / g0 - want)[use] ** 2))

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


def locate(config: RigConfig, box: Any, pairs: Sequence[ChannelPair], change: SweepChange, false_alarm: float = 0.01,
           elements: Sequence[int] | None = None, step: float = 0.01, coarse_step: float = 0.02, slices: int = 12,
           max_boxes: int = 8,
           refine: int = 1, refine_boxes: int = 48, crack_section_length: float | None = None,
           ranking: Ranking | None = None, certify: bool = True, damage: bool | None = None,
           progress: Progress | None = None, certify_best: bool = False) -> LocationResult:
    """Candidates per element (module docstring). ``box`` the benign parameters as a
    :class:`rotorcheck.signatures.BenignBox` (its model at the change's speed); ``change`` the new sweep
    against the healthy one (:func:`rotorcheck.ranking.sweep_change`, one column per pair of ``pairs``);
    ``elements`` default: every shaft element; ``ranking`` the candidates' ranking when the caller has it
    (else :func:`rotorcheck.ranking.rank_elements` here); ``certify``: the certificates too (else the
    ranking alone; with ``certify_best`` the best ranked candidate's certificate as in the first pass, the
    next ones only while it is excluded: ``detect``'s diagnosis); ``damage`` the detector's verdict where
    known. Certificates: ``step`` the width to which the severity's end slices are halved (loss, fraction)
    for the ``refine`` best ranked,
    ``coarse_step`` for every candidate's first pass; ``slices`` its first division;
    ``max_boxes`` the branch and bound's budget per slice for every candidate, ``refine_boxes`` for a
    second pass on the ``refine`` best ranked (a larger budget only narrows a certified interval or
    excludes); ``crack_section_length`` (m) the breathing crack's section length for the depth relation
    (:func:`rotorcheck.ranking.section_length`). ``false_alarm``: the chance that the true element is
    excluded when its hypothesis holds and the model errs within its stated bounds (Sidak over the points
    used). ``progress`` hears each element ranked and certified."""
    f = change.freq_hz
    nf, n_pairs = change.t_new.shape
    omega = change.omega
    hypothesis = change.hypothesis
    chosen = _select_points(np.where(change.trusted, change.change2, np.nan), N_TOP, N_SPREAD)
    m = chosen.size
    z = float(np.sqrt(-np.log1p(-(1.0 - false_alarm) ** (1.0 / max(m, 1)))))  # |r|^2/sigma^2 ~ Exp(1)
    ks, js = chosen // n_pairs, chosen % n_pairs
    pts = Points(omega[ks], change.g_zero[ks, js], change.t_new[ks, js], change.t_h[ks, js], change.var_new[ks, js],
                 change.var_h[ks, js], z, np.zeros(m), change.gain[0], change.gain[1], change.a[ks, js],
                 CRACK_MODEL_ERROR + change.err[ks, js], change.B.T[js], change.Cm.T[js])
    els = tuple(elements) if elements is not None else candidate_elements(config)
    models = {e: loss_model(config, box, e, change.speed_rpm, hypothesis) for e in els}
    if ranking is None:
        ranking = rank_elements(config, box, change, els, models, progress)
    notes = [f"ranking: {ranking.n_frequencies} frequencies ({ranking.n_residuals} real residuals) by the misfit of "
             "each element's best fit; relative likelihoods exp(-chi2/2) over the candidates"]
    lo_b = np.array([q.lo for q in box.model.parameters], dtype=float)
    hi_b = np.array([q.hi for q in box.model.parameters], dtype=float)
    p = lo_b.size
    lo, hi = np.r_[lo_b, 0.0], np.r_[hi_b, MAX_LOSS]
    results: dict[int, Any] = {}
    healthy = None
    at_zero = False
    if certify or (certify_best and damage is None):
        # the healthy hypothesis: no loss (the same model whatever the element), benign parameters in their box.
        # Not for detect's diagnosis of a damage verdict (certify_best, damage True): its one use there, a witness
        # at loss 0 that spares the best candidate's lower-end search, cost 4x that candidate's whole certificate
        # (0.8 of 1.05 s on the bundled breathing crack), and the interval is the same (a slice holding a witness is
        # never excluded); locate tests it
        healthy = severity_interval(models[els[0]], pts, lo, np.r_[hi_b, 0.0], p, step, 1, 4 * refine_boxes)
        # a witness of the healthy hypothesis (no loss) is one of every element's at loss 0: no lower-end search
        at_zero = healthy.status == "consistent" and bool(np.isfinite(healthy.witness_interval[0]))
    if certify:
        notes.append(f"{m} points of {nf * n_pairs} certified (the {N_TOP} largest whitened changes and the rest "
                     f"spread over the band, among the {int(change.trusted.sum())} where the model errs on the "
                     f"healthy FRF by at most {MAX_MODEL_ERROR:.0%}): a subset keeps every certificate sound, only "
                     "less sharp; "
                     f"the prediction's error bound there: {BENIGN_MODEL_ERROR:.0%} of the largest benign change the "
                     f"ranges allow, plus {CRACK_MODEL_ERROR:.0%} and the model's error on the healthy FRF times "
                     "the predicted change")
        notes.append(f"certified loss intervals to {coarse_step:.0%} (their ends halved to that width) for every "
                     f"candidate, to {step:.0%} with a {refine_boxes}-box budget per slice for the {refine} best "
                     "ranked")
        report(progress, 0, len(els), "certifying")
        for k, e in enumerate(els):
            results[e] = severity_interval(models[e], pts, lo, hi, p, coarse_step, slices, max_boxes, at_zero)
            report(progress, k + 1, len(els), f"certifying: element {e}")
        # the refine best ranked consistent ones: one the larger budget excludes makes way for the next (at most
        # BEST_CERTIFIED more tries: each costs the refined budget)
        refined = 0
        kept = [fit.element for fit in ranking.fits if results[fit.element].status == "consistent"]
        for e in kept[:refine + BEST_CERTIFIED - 1]:
            if refined >= refine:
                break
            results[e] = severity_interval(models[e], pts, lo, hi, p, step, slices, refine_boxes, at_zero, results[e])
            refined += results[e].status == "consistent"
    elif certify_best and damage is not False:
        # detect: the best ranked candidate's interval as locate's first pass has it (the next while one is excluded)
        for e in [f.element for f in ranking.fits[:BEST_CERTIFIED]]:
            results[e] = severity_interval(models[e], pts, lo, hi, p, coarse_step, slices, max_boxes, at_zero)
            if results[e].status == "consistent":
                break
        notes.append(f"the best ranked candidate's loss interval certified as locate's first pass has it (ends to "
                     f"{coarse_step:.0%}, {max_boxes} boxes per slice; the next candidate while one is excluded): "
                     "rotorcheck locate certifies every candidate and narrows the best one's")
    healthy_excluded = None if healthy is None else healthy.status == "excluded"
    damage_found = bool(healthy_excluded) if damage is None else damage
    order = [fit.element for fit in ranking.fits if fit.element not in results
             or results[fit.element].status == "consistent"]
    total = float(sum(f.likelihood for f in ranking.fits if f.element in order))
    cands = []
    for e in els:
        r = results.get(e)
        fit = ranking.of(e)
        assert fit is not None
        rel = _relation(config, e, hypothesis, crack_section_length)
        if hypothesis == "breathing" and rel is not None and e in order[:refine] and damage_found:
            rel = _hb_relation(config, box.system, models[e], e, change.speed_rpm, pts, crack_section_length)
        consistent = r is None or r.status == "consistent"
        if r is not None and consistent and rel is not None:
            depth: tuple[float | None, float | None] = depth_interval(r.lower, r.upper, rel)
        elif r is None and rel is not None:
            depth = depth_interval(fit.size_estimate, fit.size_estimate, rel)
        else:
            depth = (None, None)
        ranked = e in order and damage_found
        est_depth = (None if fit.loss_interval is None or rel is None else
                     depth_interval(fit.loss_interval[0], fit.loss_interval[1], rel))
        cands.append(CandidateResult(
            e, float(config.stations[e - 1]), float(config.stations[e]),
            "not certified" if r is None else r.status, order.index(e) + 1 if ranked else None,
            (float("nan"), float("nan")) if r is None else (r.lower, r.upper), depth,
            tuple(dict.fromkeys(float(f[ks[k]]) for k in r.excluding)) if r is not None and not consistent else (),
            (float("nan"), float("nan")) if r is None else r.witness_interval, False if r is None else r.witnessed,
            fit.size_estimate, fit.chi2, fit.likelihood / total if ranked and total > 0 else None, fit.loss_interval,
            est_depth, fit.size_basis))
    if hypothesis == "breathing" and order and damage_found and certify:
        notes.append(f"depths of the {min(refine, len(order))} best ranked: the loss that best reproduces the model's "
                     "harmonic-balance response to a breathing crack of each depth (its sidebands included: at 50 % "
                     "depth on the crack rig 15-20 % more than the revolution average); of the others: the average")
    if healthy_excluded is False:
        notes.append("the healthy hypothesis (no loss; benign parameters in their ranges, the same at every point) "
                     "is not excluded by the certificate" + ("" if damage else ": no candidate ranks"))
    channels = [port_label(q.output) + "<-" + port_label(q.input) for q in pairs]
    return LocationResult(hypothesis, healthy_excluded, cands, channels, m, z, notes=notes,
                          healthy_excluding_hz=() if healthy is None else
                          tuple(dict.fromkeys(float(f[ks[k]]) for k in healthy.excluding)),
                          ranking=ranking, certified=certify, damage=damage)
