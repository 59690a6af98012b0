"""Before the crack: what this rig, these sensors and this noise can detect, element by element.

For every shaft element the smallest open-crack stiffness loss (fraction of the element's E) and the
smallest breathing-crack depth (fraction of the diameter) that rotorcheck's default detector (the
joint test, :mod:`rotorcheck.robust.joint`, at the stated false-alarm rate) finds with 90 % power,

(a) with noise only (no benign change in H0): the joint test's own linear prediction, exact for this
    test (one-sided normal statistic): ``a = (sqrt(t_alpha) + z_0.9) / ||s_e||_w`` with ``t_alpha``
    its threshold (max over the candidate elements, by Monte Carlo over their correlation) and
    ``||s_e||_w`` the whitened norm of the element's signature (FRF change per unit loss);
(b) with the rig's benign variability ranges: the joint test run on the noise-free change ``a s_e``
    (the model re-solved at the benign parameters, their box, the model-error allowance kappa), whose
    statistic is the non-centrality: detected with 90 % power where ``sqrt(T(a)) >= sqrt(t_alpha(a)) +
    z_0.9`` (the normal approximation of the test's statistic about its noise-free value, stated).

Beside them the likelihood-ratio limit for the same case (limits.md 1: the best any detector could do,
knowing the element and the shape, noise only): ``a = (z_(1-alpha) + z_0.9) / ||s_e||_w``.

A breathing crack of depth ``d`` enters as the open-crack loss that its revolution-averaged stiffness
equals (:func:`rotorcheck.location.breathing_loss`, the Mayes-Davies crack, eq. 5.25): depths from
losses by that relation (a hollow element has none: null). On the crack rig's element 4 the relation
puts limits.md's breathing limits (1.3 / 2.3 / 4.0 % at 1x / 4x / 16x) at 1.14x its open-crack limits.

Noise: per point and channel pair, the variance of one sweep's FRF (m^2/N^2) -- from a baseline (its
healthy variance, the new sweep taken as one sweep of the same noise) or from stated figures:
``4 sigma^2 / (M N F^2)`` for output noise ``sigma`` (m) averaged over ``N`` periods of ``M`` samples at
force amplitude ``F`` (N). Both sweeps' noise counts (new and baseline).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import combinations
from typing import Any

import numpy as np

from rotorcheck.config import RigConfig
from rotorcheck.location import _relation, depth_of_loss
from rotorcheck.nominal import ChannelPair, model_pairs
from rotorcheck.progress import Progress, report
from rotorcheck.robust.joint import POWER_Z, BenignModel, joint_test
from rotorcheck.signatures import crack_signatures, io_frf, stacked, unstacked

#: largest stiffness loss searched (fraction); beyond it an element counts as undetectable (None)
MAX_LOSS = 0.8
#: Monte-Carlo draws of the joint test's null in the predictions (threshold to about 1 %)
DRAWS = 20_000
#: relative precision of the smallest detectable loss with benign ranges (bracket ratio; the Monte-Carlo
#: check of the predictions uses a depth grid of ratio 1.25)
PRECISION = 1.05


def z_upper(alpha: float) -> float:
    """Standard normal upper quantile z with P(Z > z) = alpha: ``-ndtri(alpha)``, which is what
    ``scipy.stats.norm.isf`` computes (the same bits; ``+ 0.0`` turns its -0 at 0.5 into 0)."""
    # lazy import, and scipy.special rather than scipy.stats: importing scipy.stats costs ~0.3 s of every
    # ``detect`` (issue 28); scipy.special is loaded with scipy.optimize anyway
    from scipy.special import ndtri  # lazy: scipy.special only for this quantile (see above)

    return float(-ndtri(alpha)) + 0.0


def stated_noise_variance(sigma_m: float, periods: int, samples_per_period: int, force_n: float) -> float:
    """Variance of one stepped-sine FRF point (m^2/N^2): ``4 sigma^2 / (M N F^2)`` (averaged phasor of
    N periods of M samples, output noise sigma, force amplitude F)."""
    return 4.0 * sigma_m**2 / (samples_per_period * periods * force_n**2)


@dataclass(frozen=True)
class ElementDetectability:
    """One element's smallest detectable cracks (losses and depths as fractions; None: not detected up
    to :data:`MAX_LOSS` loss, or no depth relation for a hollow element)."""

    element: int
    z_start_m: float
    z_end_m: float
    open_loss_min: float | None
    open_loss_min_noise_only: float | None
    limit_open_loss_noise_only: float | None
    breathing_depth_min: float | None
    breathing_depth_min_noise_only: float | None
    limit_breathing_depth_noise_only: float | None

    def to_dict(self) -> dict[str, Any]:
        """The JSON entry (cli: ``rotorcheck detectability --json``)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass
class Detectability:
    """The detectability table of a rig at one speed, with its sensors, noise and false-alarm rate."""

    rig_id: str
    speed_rpm: float
    false_alarm: float
    sensors: tuple[str, ...]
    actuators: tuple[str, ...]
    noise_source: str
    benign: bool  # benign ranges present (case b differs from a)
    elements: list[ElementDetectability]
    kappa: float
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The ``rotorcheck detectability --json`` document."""
        return {
            "rig_id": self.rig_id, "speed_rpm": self.speed_rpm, "false_alarm": self.false_alarm,
            "sensors": list(self.sensors), "actuators": list(self.actuators), "noise_source": self.noise_source,
            "power": 0.9, "benign_ranges": self.benign, "benign_model_error_kappa": self.kappa,
            "rule": RULE, "elements": [e.to_dict() for e in self.elements], "notes": list(self.notes),
        }

    def summary(self) -> str:
        """Plain lines for the terminal."""
        def pct(x: float | None) -> str:
            return "-" if x is None else f"{100 * x:.3g}"

        lines = [f"{self.rig_id} at {self.speed_rpm:g} rpm; sensors {', '.join(self.sensors)}; actuator(s) "
                 f"{', '.join(self.actuators)}; {self.noise_source}; 90 % power at {self.false_alarm:g} false alarms",
                 "element  z (m)          open loss %: benign / noise / LR limit   breathing depth %: benign / "
                 "noise / LR limit"]
        for e in self.elements:
            lines.append(f"{e.element:>7}  {e.z_start_m:.3f}-{e.z_end_m:.3f}    {pct(e.open_loss_min):>8} / "
                         f"{pct(e.open_loss_min_noise_only):>8} / {pct(e.limit_open_loss_noise_only):>8}       "
                         f"{pct(e.breathing_depth_min):>6} / {pct(e.breathing_depth_min_noise_only):>6} / "
                         f"{pct(e.limit_breathing_depth_noise_only):>6}")
        return "\n".join(lines + self.notes)


RULE = ("smallest loss (depth) the joint test detects with 90 % power at the false-alarm rate: noise only, "
        "sqrt(threshold) + z_0.9 over the whitened signature norm; with benign ranges, the joint test on the "
        "noise-free change reaching sqrt(threshold) + z_0.9 (normal approximation); LR limit (z_(1-alpha) + "
        "z_0.9) / norm: known element and shape, noise only; depths by the Mayes-Davies revolution average")


def _smallest(g: Any, start: float) -> float | None:
    """Smallest ``a`` in [start, MAX_LOSS] with ``g(a) >= 0`` for increasing ``g`` (bracketing by doubling
    in log a, then bisection to :data:`PRECISION`); None when ``g(MAX_LOSS) < 0``."""
    lo, hi = start, start
    if g(lo) >= 0.0:
        return lo
    while True:
        hi = min(hi * 2.0, MAX_LOSS)
        if g(hi) >= 0.0:
            break
        if hi >= MAX_LOSS:
            return None
        lo = hi
    while hi / lo > PRECISION:
        mid = math.sqrt(lo * hi)
        if g(mid) >= 0.0:
            hi = mid
        else:
            lo = mid
    return hi


@dataclass(frozen=True)
class _BenignSearch:
    """The benign-case search of one element (picklable for a worker process)."""

    var: np.ndarray
    S: np.ndarray
    elements: tuple[int, ...]
    benign: Any
    false_alarm: float

    def margin(self, a: float, i: int) -> float:
        """``sqrt(T(a)) - sqrt(threshold) - z_0.9`` of the joint test on the noise-free change ``a s_i``."""
        j = joint_test(a * self.S[i], self.var, self.S, self.elements, self.benign, None, self.false_alarm,
                       draws=DRAWS, edge_evidence=False)
        return math.sqrt(float(np.max(j.t_element))) - math.sqrt(j.threshold) - POWER_Z

    def __call__(self, task: tuple[int, float]) -> float | None:
        i, start = task
        return _smallest(lambda a: self.margin(a, i), start)


def _map(job: Any, tasks: list[Any], workers: int | None, progress: Progress | None = None,
         labels: Sequence[str] | None = None) -> list[Any]:
    """``[job(t) for t in tasks]``, over ``workers`` forked processes where that helps (Linux; default:
    up to 2, one per core); in order, deterministic (every task is). ``progress`` hears of each task
    done (``labels[k]`` names task k)."""
    import multiprocessing  # lazy: multiprocessing only for the searches' process pool

    names = list(labels) if labels is not None else [f"task {k + 1}" for k in range(len(tasks))]
    n = min(len(tasks), workers if workers is not None else min(2, os.cpu_count() or 1))
    out: list[Any] = []
    if n <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        for k, task in enumerate(tasks):
            out.append(job(task))
            report(progress, k + 1, len(tasks), names[k])
        return out
    global _FORKED_JOB
    _FORKED_JOB = job  # inherited by the forked workers (the job holds closures: not picklable)
    try:
        with multiprocessing.get_context("fork").Pool(n) as pool:
            for k, result in enumerate(pool.imap(_run_forked, tasks, chunksize=1)):  # in order, as they finish
                out.append(result)
                report(progress, k + 1, len(tasks), names[k])
        return out
    finally:
        _FORKED_JOB = None


_FORKED_JOB: Any = None


def _run_forked(task: Any) -> Any:
    return _FORKED_JOB(task)


def detectability(
    config: RigConfig,
    freq_hz: np.ndarray,
    speed_rpm: float,
    var_new: np.ndarray,
    var_base: np.ndarray,
    pairs: Sequence[ChannelPair],
    healthy_frf: np.ndarray | None = None,
    false_alarm: float = 0.01,
    benign: BenignModel | None = None,
    elements: Sequence[int] | None = None,
    section_length: float | None = None,
    noise_source: str = "",
    workers: int | None = None,
    candidates: Sequence[int] | None = None,
    model_frf: np.ndarray | None = None,
    progress: Progress | None = None,
) -> Detectability:
    """The detectability table (module docstring). ``var_new``, ``var_base``: (f, P) or (f,) variances of
    one FRF point of the new sweep and of the baseline (m^2/N^2), P = len(pairs); ``healthy_frf`` (f, P):
    the level the signatures are anchored at (default: the model's own receptance); ``benign``: the joint
    test's benign model at these points, stacked like the signatures (None: noise only; see
    :func:`rotorcheck.workflow.benign_model`); ``workers``: processes for the benign-case searches
    (default: up to 2); ``elements``: the elements reported (default: all); ``candidates``: the joint test's
    candidate elements (default: every element the channels see, as ``detect`` has); ``model_frf``: the
    model's own receptance (:func:`rotorcheck.signatures.io_frf`) when the caller has it; ``progress``
    hears of each element's benign-case search done."""

    f = np.asarray(freq_hz, dtype=float)
    P = len(pairs)
    multi = model_pairs(config, pairs)  # a single pair other than the rig's own is that pair
    if model_frf is None and healthy_frf is None:
        model_frf = io_frf(config, f, speed_rpm, multi)
    th = np.asarray(healthy_frf) if healthy_frf is not None else np.asarray(model_frf)
    th = unstacked(th, (f.size, P)) if P > 1 else th.reshape(f.size)

    def as_th(x: np.ndarray) -> np.ndarray:
        a = np.asarray(x, dtype=float)
        return unstacked(a, th.shape) if a.size == th.size else np.broadcast_to(a, th.shape)

    var = stacked(as_th(var_new) + as_th(var_base))
    # the detector's candidates are every element the channels see (or ``candidates``); ``elements`` only
    # chooses which of them are reported (the threshold is that of the whole candidate set)
    # the model's own FRF (stated noise) is re-solved; a measured healthy FRF anchors its fitted modes
    els, S = crack_signatures(config, f, speed_rpm, th, candidates, pairs=multi, model_frf=model_frf,
                              modal=model_frf is None, healthy_var=None if model_frf is not None else as_th(var_base))
    notes: list[str] = []
    wanted = set(els) if elements is None else set(elements)
    if elements is not None and not wanted <= set(els):
        unseen = sorted(wanted - set(els))
        notes.append(f"elements {unseen}: not seen by these channels (no bending moment there): undetectable")
    bm = benign
    k = float(bm.kappa) if bm is not None else 0.0
    if bm is None:
        notes.append("no benign variability ranges at this speed: the benign case equals noise only")
    rows: list[ElementDetectability] = []
    stations = config.stations
    if not els:  # e.g. y probes of an x force at standstill (the planes decouple): every element undetectable
        notes.append("these channels see no shaft element: no crack is detectable with them")
    else:
        zero = np.zeros(var.size, dtype=complex)
        noise_only = joint_test(zero, var, S, els, None, None, false_alarm, edge_evidence=False)
        # without a nuisance the test's standard error of a loss is 1 / ||s_e||_w (the whitened signature norm)
        lr = (z_upper(false_alarm) + POWER_Z) * noise_only.severity_se
        # the benign search starts at the test's linear prediction with the benign tangent projected out (the
        # box and the model-error allowance only make it harder)
        start = (joint_test(zero, var, S, els, bm, None, false_alarm, draws=DRAWS, edge_evidence=False).detectable
                 if bm is not None else None)
        a_noise_all = [float(x) if np.isfinite(x) else None for x in noise_only.detectable]
        a_benign_all: list[float | None] = list(a_noise_all)
        if bm is not None and start is not None:
            todo = [i for i, a in enumerate(a_noise_all) if a is not None and els[i] in wanted]
            job = _BenignSearch(var, S, els, bm, false_alarm)
            starts = [max(float(a_noise_all[i] or 0.0), float(min(start[i], MAX_LOSS))) for i in todo]
            found = _map(job, list(zip(todo, starts)), workers, progress, [f"element {els[i]}" for i in todo])
            for i, a in zip(todo, found):
                a_benign_all[i] = a
        for i, e in enumerate(els):
            if e not in wanted:
                continue
            a_noise, a_benign = a_noise_all[i], a_benign_all[i]
            relation = _relation(config, e, "breathing", section_length)

            def depth(loss: float | None, rel: Any = relation) -> float | None:
                return None if loss is None or rel is None else depth_of_loss(loss, rel)

            a_lr = float(lr[i]) if np.isfinite(lr[i]) else None
            rows.append(ElementDetectability(
                element=int(e), z_start_m=float(stations[e - 1]), z_end_m=float(stations[e]),
                open_loss_min=a_benign, open_loss_min_noise_only=a_noise, limit_open_loss_noise_only=a_lr,
                breathing_depth_min=depth(a_benign), breathing_depth_min_noise_only=depth(a_noise),
                limit_breathing_depth_noise_only=depth(a_lr)))
    seen = {r.element for r in rows}
    for e in (elements if elements is not None else range(1, len(stations))):
        if e not in seen:
            rows.append(ElementDetectability(int(e), float(stations[e - 1]), float(stations[e]),
                                             None, None, None, None, None, None))
    rows.sort(key=lambda r: r.element)
    sensors = tuple(dict.fromkeys(p.key()[0] for p in pairs))
    actuators = tuple(dict.fromkeys(p.key()[1] for p in pairs))
    return Detectability(config.rig_id, float(speed_rpm), float(false_alarm), sensors, actuators, noise_source,
                         bm is not None, rows, k, notes)


DETECTABILITY_RULE_SETS = ("sensor sets ranked by the worst element's smallest breathing depth detected with 90 % "
                           "power with the benign ranges (benign model linearized at the healthy state), then its "
                           "open-crack loss; each sensor with every actuator is one channel pair")


def linearized(benign: BenignModel) -> BenignModel:
    """``benign`` with its prediction linearized at the start of its range (0 where inside): one model
    solve per parameter, then ``b0 + J (theta - x0)``. On the crack rig its detectability figures are
    within 3 % of the re-solved model's (15 % on element 6): fast enough to rank sensor sets and to state
    in every detect report."""
    p = len(benign.lo)
    x0 = np.clip(np.zeros(p), benign.lo, benign.hi)
    b0 = benign.predict(x0)
    steps = np.broadcast_to(np.asarray(benign.step, dtype=float), (p,))
    J = np.array([(benign.predict(x0 + np.eye(p)[k] * steps[k]) - b0) / steps[k] for k in range(p)])

    def predict(theta: np.ndarray) -> np.ndarray:
        return b0 + (np.asarray(theta, dtype=float) - x0) @ J

    return dataclasses.replace(benign, predict=predict)


@dataclass(frozen=True)
class SensorSetScore:
    """A sensor set and its worst element: the largest smallest-detectable breathing depth with the benign
    ranges (None: an element it cannot watch up to 50 % depth), and the worst open-crack loss."""

    sensors: tuple[str, ...]
    worst_element: int
    worst_depth: float | None
    worst_loss: float | None

    def key(self) -> tuple[float, float]:
        """Sort key: worst depth, then worst loss (undetectable as infinity)."""
        inf = float("inf")
        return (inf if self.worst_depth is None else self.worst_depth,
                inf if self.worst_loss is None else self.worst_loss)

    def to_dict(self) -> dict[str, Any]:
        """JSON entry."""
        return {"sensors": list(self.sensors), "worst_element": self.worst_element,
                "worst_breathing_depth_min": self.worst_depth, "worst_open_loss_min": self.worst_loss}


def _score(det: Detectability, elements: Sequence[int]) -> SensorSetScore:
    rows = [e for e in det.elements if e.element in elements]
    worst = max(rows, key=lambda e: (e.breathing_depth_min is None, e.breathing_depth_min or 0.0,
                                     e.open_loss_min is None, e.open_loss_min or 0.0))
    return SensorSetScore(det.sensors, worst.element, worst.breathing_depth_min, worst.open_loss_min)


def visible_elements(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, sensors: Sequence[Any],
                     actuators: Sequence[Any]) -> tuple[int, ...]:
    """The shaft elements that at least one sensor-actuator pair sees (a crack there changes an FRF)."""
    prs = [ChannelPair(o, i, "") for o in sensors for i in actuators]
    multi = model_pairs(config, prs)
    th = io_frf(config, freq_hz, speed_rpm, multi)
    return crack_signatures(config, freq_hz, speed_rpm, th, pairs=multi, model_frf=th, modal=False)[0]


def score_sensor_set(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, variance: float,
                     sensors: Sequence[Any], actuators: Sequence[Any], benign_for: Any, false_alarm: float,
                     elements: Sequence[int]) -> SensorSetScore:
    """The worst of ``elements`` for one sensor set (every sensor with every actuator), the benign model
    ``benign_for(pairs, healthy_frf)`` linearized; an element the set cannot see counts as undetectable."""
    prs = [ChannelPair(o, i, "") for o in sensors for i in actuators]
    multi = model_pairs(config, prs)
    th = io_frf(config, freq_hz, speed_rpm, multi)
    bm = benign_for(prs, th)
    det = detectability(config, freq_hz, speed_rpm, np.full(th.shape, variance), np.full(th.shape, variance), prs,
                        th, false_alarm, None if bm is None else linearized(bm), elements, workers=1, model_frf=th)
    return _score(det, elements)


def rank_sensor_sets(
    config: RigConfig,
    freq_hz: np.ndarray,
    speed_rpm: float,
    variance: float,
    candidates: Sequence[Any],
    actuators: Sequence[Any],
    max_sensors: int,
    benign_for: Any,
    false_alarm: float = 0.01,
    exhaustive_limit: int = 64,
    workers: int | None = None,
) -> tuple[list[SensorSetScore], str, tuple[int, ...]]:
    """Sensor sets of up to ``max_sensors`` ports from ``candidates`` (rotor ports), each with every
    actuator, ranked by their worst element (:class:`SensorSetScore`), the benign model linearized
    (:func:`linearized`; ``benign_for(pairs, healthy_frf)`` builds the re-solved one). Every subset when
    there are at most ``exhaustive_limit`` of them ("exhaustive"), else greedy: add the port that most
    improves the worst element, one at a time ("greedy"). Elements no candidate can see are left out of
    the score (returned third). ``variance``: one FRF point of one sweep, m^2/N^2, the same on every pair."""
    f = np.asarray(freq_hz, dtype=float)
    cand = list(candidates)
    if not cand or max_sensors < 1:
        raise ValueError("need candidate sensors and max_sensors >= 1")

    seen = visible_elements(config, f, speed_rpm, cand, actuators)
    if not seen:
        raise ValueError("no candidate sensor sees any shaft element with these actuators (at standstill the x and "
                         "y planes decouple: a y probe sees nothing of an x force); add candidates in the "
                         "actuator's plane or an actuator in theirs")

    def evaluate(ports: tuple[Any, ...]) -> SensorSetScore:
        return score_sensor_set(config, f, speed_rpm, variance, ports, actuators, benign_for, false_alarm, seen)

    k = min(max_sensors, len(cand))
    subsets = [c for r in range(1, k + 1) for c in combinations(cand, r)]
    scores: list[SensorSetScore] = []
    if len(subsets) <= exhaustive_limit:
        scores = _map(evaluate, subsets, workers)
        method = "exhaustive"
    else:
        chosen: tuple[Any, ...] = ()
        method = "greedy"
        for _ in range(k):
            trial = [(*chosen, c) for c in cand if c not in chosen]
            got = _map(evaluate, trial, workers)
            scores += got
            best = min(range(len(got)), key=lambda i: got[i].key())
            chosen = trial[best]
    ranked = sorted(scores, key=lambda s: (s.key(), len(s.sensors), s.sensors))
    return ranked, method, seen
