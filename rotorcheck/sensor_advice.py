"""Which sensors would locate it: when a damage is not locatable with the sensors measured, the smallest set of
candidate probes under which the change the ranking estimates would be located.

The damage to locate is the one the ranking estimates: its best candidate element with that element's best-fit
loss (a hypothesis; the functions take several, every one to be located).

A sensor set locates a hypothesis "loss ``a`` of element ``e``" when, at the expected data of that crack, the
ranking (:mod:`rotorcheck.ranking`) would name ``e`` with 90 % power. Predicted with detectability's scoring
(:mod:`rotorcheck.detectability`: the joint test run on the noise-free change ``a s_e``, benign model
linearized at the healthy state) on the points and weights the ranking uses: its fit frequencies
(:func:`rotorcheck.ranking.fit_indices` of the predicted whitened change, among the frequencies the measured
channels trust) and its misfit variance, both sweeps' noise plus ``BENIGN_MODEL_ERROR`` of the benign
envelope plus ``CRACK_MODEL_ERROR`` of the predicted change (that of the true hypothesis for every candidate:
an approximation). The joint test's ``T_j`` is then the chi-square each element's loss removes over benign
change alone, so that (normal approximation of a non-central statistic, as detectability's rule)

- the evidence over benign change ``T_e`` reaches :data:`rotorcheck.location.MIN_EVIDENCE` at its lower
  10 % quantile ``(sqrt(T_e) - z_0.9)^2``, and
- the relative likelihood ``1 / (1 + sum_j exp(-D_j / 2))`` reaches
  :data:`rotorcheck.location.LOCATED_LIKELIHOOD` with each separation ``D_j = T_e - T_j`` at its lower
  10 % quantile ``D_j - 2 z_0.9 sqrt(D_j)`` (``D ~ N(mu, 4 mu)``).

Candidate probes: x and y at every station (the rig file does not say where a probe can sit), unless given;
each with every measured actuator; FRF noise per point the median over the measured pairs (a probe's noise is
about that of another). A set is the measured sensors (a sweep holds the rig's own pair) and up to
:data:`MAX_ADDED` more. Receptances, signatures and the benign model are solved once for every candidate pair;
each set is a selection of their columns (every set costs joint tests only). Sets are tried by the number of
probes added (every set of a size while there are at most ``exhaustive_limit``, else greedily one probe at a
time); the first size with a locating set gives the advice, the set with the largest worst relative likelihood
first. The advice quotes the smallest loss the set detects in the element
(:func:`rotorcheck.detectability.detectability` for that set, benign ranges): detection with the joint test's
benign model and its model-error allowance, often larger than what the ranking locates.

Measured (tests/test_sensor_advice.py's case: the crack rig at standstill, 80 points, probe 6x <- 8x, a 10 %
loss in element 4 simulated on the nominal rig with the truth rig's noise): not locatable (evidence 3.1 chi2,
element 4 at 0.37); the advice adds an x probe at station 3 (predicted relative likelihood at least 0.77);
simulated with 6x and 3x the ranking locates element 4 at 0.93-0.99 over three seeds (6x, 2x, 4x: 0.91-0.97);
0.2 s of CPU (19 sets, greedy over x and y at the 10 stations) on top of the ranking's 0.6 s.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np

from rotorcheck.config import Port, RigConfig
from rotorcheck.detectability import detectability, linearized
from rotorcheck.location import LOCATED_LIKELIHOOD, MIN_EVIDENCE, LocationResult, _ranges
from rotorcheck.nominal import ChannelPair, port_label
from rotorcheck.ranking import BENIGN_MODEL_ERROR, CRACK_MODEL_ERROR, fit_indices
from rotorcheck.robust.joint import POWER_Z, BenignModel, joint_test
from rotorcheck.signatures import candidate_elements, crack_signatures, io_frf, stacked

#: most probes added to the measured ones
MAX_ADDED = 3
#: Monte-Carlo draws of the joint test's null in a prediction (its threshold is not used: few)
_DRAWS = 200


@dataclass(frozen=True)
class Hypothesis:
    """A crack the ranking left open: a loss (fraction of the element's E) of one element."""

    element: int
    loss: float


@dataclass(frozen=True)
class SetPrediction:
    """One sensor set's predicted location of the hypotheses: the worst hypothesis's evidence over benign
    change (chi-square units) and relative likelihood, both at their lower 10 % quantiles."""

    sensors: tuple[str, ...]
    evidence: float
    likelihood: float

    @property
    def located(self) -> bool:
        """Every hypothesis located with 90 % power (predicted)."""
        return self.evidence >= MIN_EVIDENCE and self.likelihood >= LOCATED_LIKELIHOOD

    def to_dict(self) -> dict[str, Any]:
        return {"sensors": list(self.sensors), "evidence_over_benign": self.evidence,
                "relative_likelihood": self.likelihood, "located": self.located}


@dataclass(frozen=True)
class SensorAdvice:
    """The advice (module docstring): the hypotheses, the measured set's prediction, the smallest set that
    locates them (the measured sensors and at most ``max_added`` more; None: none), its detectable loss and
    what was tried."""

    hypotheses: tuple[Hypothesis, ...]
    current: SetPrediction | None
    best: SetPrediction | None
    closest: SetPrediction | None  # the best set tried when none locates
    candidates: tuple[str, ...]
    actuators: tuple[str, ...]
    detectable_loss: float | None  # the best set's smallest detectable loss in ``detectable_element`` (benign)
    detectable_element: int | None
    n_sets: int
    method: str  # "exhaustive" | "greedy"
    max_added: int

    def text(self) -> str:
        """The sentence the location summary carries."""
        if not self.hypotheses:
            return "no element's best fit has a loss: no set of sensors can locate this change"
        hyp = self.hypotheses
        what = (f"a loss of {_pct(hyp[0].loss)} in element {hyp[0].element}" if len(hyp) == 1 else
                "a loss in any of elements " + ", ".join(f"{h.element} ({_pct(h.loss)})" for h in hyp))
        if self.current is not None and self.current.located:
            return (f"these sensors should locate {what} (predicted relative likelihood at least "
                    f"{self.current.likelihood:.2f} with 90 % power): the change may be no stiffness loss of one "
                    "element")
        if self.best is None:
            near = "" if self.closest is None else (
                f" (closest: {describe_ports(self.closest.sensors)}, relative likelihood at least "
                f"{self.closest.likelihood:.2f})")
            return (f"no {self.max_added} or fewer more probes (of {describe_ports(self.candidates)}) would locate "
                    f"{what}{near}")
        det = ("" if self.detectable_element is None else
               f"; smallest detectable loss there {_pct(self.detectable_loss)} in element {self.detectable_element} "
               "(the joint test with the benign ranges, 90 % power)" if self.detectable_loss is not None else
               f"; element {self.detectable_element} not detectable there up to 80 % loss with the benign ranges")
        added = [s for s in self.best.sensors if self.current is None or s not in self.current.sensors]
        return (f"{describe_ports(self.best.sensors)} (adding {', '.join(added)}) would locate {what} (predicted "
                f"relative likelihood at least {self.best.likelihood:.2f} with 90 % power){det}")

    def to_dict(self) -> dict[str, Any]:
        """JSON (location.json, report.json's location: ``sensor_advice_detail``)."""
        return {"hypotheses": [{"element": h.element, "loss": h.loss} for h in self.hypotheses],
                "current": None if self.current is None else self.current.to_dict(),
                "best": None if self.best is None else self.best.to_dict(),
                "closest": None if self.closest is None else self.closest.to_dict(),
                "candidate_sensors": list(self.candidates), "actuators": list(self.actuators),
                "detectable_loss": self.detectable_loss, "detectable_element": self.detectable_element,
                "sets_tried": self.n_sets, "method": self.method, "max_added": self.max_added,
                "text": self.text()}


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.2g} %"


def describe_ports(labels: Sequence[str]) -> str:
    """Port labels in words: ``("s6.x", "s6.y", "s2.x", "s2.y")`` -> "x and y probes at stations 2 and 6";
    ``("s6.x", "s2.y")`` -> "an x probe at station 6 and a y probe at station 2"."""
    dirs: dict[int, set[str]] = {}
    other: list[str] = []
    for lab in labels:
        head, _, direction = lab.partition(".")
        if head.startswith("s") and head[1:].isdigit() and direction in ("x", "y"):
            dirs.setdefault(int(head[1:]), set()).add(direction)
        else:
            other.append(lab)
    groups: dict[str, list[int]] = {}
    for st in sorted(dirs):
        groups.setdefault(" and ".join(sorted(dirs[st])), []).append(st)
    parts = []
    for d, sts in groups.items():
        many = len(sts) > 1 or " and " in d
        where = (f"station {sts[0]}" if len(sts) == 1 else f"stations {_ranges(sts)}" if len(sts) > 3 else
                 f"stations {', '.join(map(str, sts[:-1]))} and {sts[-1]}")
        parts.append(f"{d} probes at {where}" if many else f"{'an' if d == 'x' else 'a'} {d} probe at {where}")
    parts += [f"a sensor at {o}" for o in other]
    return " and ".join(parts) if len(parts) <= 2 else ", ".join(parts[:-1]) + " and " + parts[-1]


def hypotheses_of(result: LocationResult) -> tuple[Hypothesis, ...]:
    """The damage a not-locatable result estimates: its best ranked candidate with its best-fit loss (none
    when that fit has no loss)."""
    ranked = result.ranked
    if not ranked or ranked[0].loss_estimate is None or not ranked[0].loss_estimate > 0.0:
        return ()
    return (Hypothesis(ranked[0].element, float(ranked[0].loss_estimate)),)


def candidate_ports(config: RigConfig, sensors: Sequence[Port]) -> list[Port]:
    """x and y probes at the stations of ``sensors`` (first, in their order) and at every other station."""
    stations = [p.station for p in sensors if p.station is not None]
    stations += list(range(1, len(config.stations) + 1))
    return [Port(station=s, direction=d) for s in dict.fromkeys(stations) for d in ("x", "y")]


@dataclass(frozen=True)
class _Model:
    """Every candidate pair's model solved once: healthy receptance, signatures, benign model (stacked)."""

    n_f: int
    ports: tuple[str, ...]
    n_act: int
    elements: tuple[int, ...]
    th: np.ndarray  # (f, P)
    S: np.ndarray  # (n_e, P f)
    var: np.ndarray  # (f,) both sweeps' noise per point and pair
    trusted: np.ndarray  # (f,) bool
    benign: BenignModel | None  # linearized, over every pair (P f,)

    def columns(self, ports: Sequence[int]) -> np.ndarray:
        """The pairs (columns of ``th``) of the probes ``ports`` (indices), every actuator each."""
        return np.array([i * self.n_act + k for i in ports for k in range(self.n_act)], dtype=int)

    def predict(self, ports: Sequence[int], hyp: Hypothesis) -> tuple[float, float]:
        """``(evidence, likelihood)`` of ``hyp`` with the probes ``ports``, both at their lower 10 % quantile."""
        if hyp.element not in self.elements:
            return 0.0, 0.0
        cols = self.columns(ports)
        P = self.th.shape[1]
        s_e = self.S[self.elements.index(hyp.element)].reshape(P, self.n_f).T[:, cols]  # (f, p)
        change = hyp.loss * s_e
        a2 = 0.0 if self.benign is None or self.benign.envelope is None else (
            (BENIGN_MODEL_ERROR * self.benign.envelope.reshape(P, self.n_f).T[:, cols]) ** 2)
        var = self.var[:, None] + a2 + (CRACK_MODEL_ERROR * np.abs(change)) ** 2
        fit = fit_indices(np.abs(change) ** 2 / (self.var[:, None] + a2),
                          np.broadcast_to(self.trusted[:, None], change.shape))
        flat = (cols[None, :] * self.n_f + fit[:, None]).T.ravel()  # stacked: pair after pair
        sig = self.S.reshape(len(self.elements), P, self.n_f)[:, cols][:, :, fit].reshape(len(self.elements), -1)
        bm = None if self.benign is None else _restricted(self.benign, flat)
        jt = joint_test(stacked(change[fit]), stacked(var[fit]), sig, self.elements, bm, None, draws=_DRAWS,
                        edge_evidence=False)
        t = np.asarray(jt.t_element, dtype=float)
        i = self.elements.index(hyp.element)
        evidence = max(math.sqrt(t[i]) - POWER_Z, 0.0) ** 2
        d = np.maximum(t[i] - np.delete(t, i), 0.0)
        low = d - 2.0 * POWER_Z * np.sqrt(d)
        return evidence, float(1.0 / (1.0 + np.sum(np.exp(-0.5 * low))))


def candidate_model(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, ports: Sequence[Port],
                    actuators: Sequence[Port], var: np.ndarray,
                    benign_for: Callable[[list[ChannelPair], np.ndarray], BenignModel | None],
                    trusted: np.ndarray | None = None) -> _Model:
    """Every pair of ``ports`` (each with every actuator) solved once: the model's receptance, every shaft
    element's signature (the ranking's candidates: an element no pair sees has none, it still competes as
    benign change alone) and the linearized benign model; ``var`` (f,) both sweeps' noise per point."""

    f = np.asarray(freq_hz, dtype=float)
    pairs = [ChannelPair(o, i, "") for o in ports for i in actuators]
    th = io_frf(config, f, speed_rpm, pairs)
    seen, S_seen = crack_signatures(config, f, speed_rpm, th, pairs=pairs, model_frf=th, modal=False)
    els = candidate_elements(config)
    S = np.zeros((len(els), th.size), dtype=complex)
    for e, row in zip(seen, S_seen):
        S[els.index(e)] = row
    bm = benign_for(pairs, th)
    return _Model(f.size, tuple(port_label(p) for p in ports), len(actuators), els, th, S,
                  np.asarray(var, dtype=float).reshape(f.size),
                  np.ones(f.size, dtype=bool) if trusted is None else np.asarray(trusted, dtype=bool).reshape(f.size),
                  None if bm is None else linearized(bm))


def _restricted(bm: BenignModel, idx: np.ndarray) -> BenignModel:
    """``bm`` at the stacked points ``idx`` only, its model-error allowance off (the ranking's weights carry
    the benign error as :data:`rotorcheck.ranking.BENIGN_MODEL_ERROR` of the envelope instead)."""
    return dataclasses.replace(bm.at(idx), kappa=0.0)


def advise_sensors(
    config: RigConfig,
    freq_hz: np.ndarray,
    speed_rpm: float,
    var_new: np.ndarray,
    var_base: np.ndarray,
    sensors: Sequence[Port],
    actuators: Sequence[Port],
    hypotheses: Sequence[Hypothesis],
    benign_for: Callable[[list[ChannelPair], np.ndarray], BenignModel | None],
    candidates: Sequence[Port] | None = None,
    trusted: np.ndarray | None = None,
    false_alarm: float = 0.01,
    max_added: int = MAX_ADDED,
    exhaustive_limit: int = 64,
) -> SensorAdvice:
    """The smallest set of ``candidates`` (default :func:`candidate_ports`) that locates every hypothesis
    (module docstring). ``var_new``, ``var_base`` (f,): one FRF point's variance of the new sweep and of the
    healthy mean (m^2/N^2), the same on every pair; ``sensors``, ``actuators``: the measured ones;
    ``benign_for(pairs, healthy_frf)`` the benign model (re-solved; linearized here); ``trusted`` (f,) the
    frequencies the location may use (default all)."""
    f = np.asarray(freq_hz, dtype=float)
    cand = list(candidates) if candidates is not None else candidate_ports(config, sensors)
    labels = tuple(dict.fromkeys(port_label(p) for p in [*sensors, *cand]))
    ports = [next(p for p in [*sensors, *cand] if port_label(p) == lab) for lab in labels]
    acts = tuple(port_label(a) for a in actuators)
    hyps = tuple(hypotheses)
    current_idx = tuple(labels.index(port_label(p)) for p in sensors)
    cand_idx = [labels.index(port_label(p)) for p in cand]
    empty = SensorAdvice(hyps, None, None, None, tuple(port_label(p) for p in cand), acts, None, None, 0,
                         "exhaustive", max_added)
    if not hyps:
        return empty
    var_new, var_base = _floored(var_new, f.size), _floored(var_base, f.size)
    model = candidate_model(config, f, speed_rpm, ports, actuators, var_new + var_base, benign_for, trusted)

    def score(idx: tuple[int, ...]) -> SetPrediction:
        got = [model.predict(idx, h) for h in hyps]
        return SetPrediction(tuple(labels[i] for i in idx), min(g[0] for g in got), min(g[1] for g in got))

    def key(s: SetPrediction) -> tuple[bool, float, float]:
        return (not s.located, -s.likelihood, -s.evidence)

    current = score(current_idx)
    tried: list[SetPrediction] = []
    best: SetPrediction | None = None
    extra = [i for i in cand_idx if i not in current_idx]
    k = min(max_added, len(extra))
    n_subsets = sum(math.comb(len(extra), r) for r in range(1, k + 1))
    method = "exhaustive" if n_subsets <= exhaustive_limit else "greedy"
    chosen: tuple[int, ...] = current_idx
    for r in range(1, k + 1):
        if method == "exhaustive":
            sets = [(*current_idx, *c) for c in combinations(extra, r)]
        else:
            sets = [(*chosen, c) for c in extra if c not in chosen]
        got = [score(c) for c in sets]
        tried += got
        if not got:
            continue
        top = min(range(len(got)), key=lambda i: key(got[i]))
        chosen = sets[top]
        if got[top].located:
            best = got[top]
            break
    closest = None if best is not None or not tried else min(tried, key=key)
    det_loss, det_el = None, None
    if best is not None and not current.located:
        det_el = hyps[0].element
        det_loss = detectable_loss(config, f, speed_rpm, var_new, var_base, best.sensors, ports, labels, actuators,
                                   det_el, benign_for, false_alarm)
    return dataclasses.replace(empty, current=current, best=best, closest=closest, detectable_loss=det_loss,
                               detectable_element=det_el, n_sets=len(tried), method=method)


def _floored(var: np.ndarray, n: int) -> np.ndarray:
    """A variance per point (n,) with its zeros (a point without a noise estimate) at its least positive value."""
    v = np.asarray(var, dtype=float).reshape(n)
    positive = v[v > 0.0]
    return np.where(v > 0.0, v, positive.min() if positive.size else 1.0)


def detectable_loss(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, var_new: np.ndarray,
                    var_base: np.ndarray, sensors: Sequence[str], ports: Sequence[Port], labels: Sequence[str],
                    actuators: Sequence[Port], element: int,
                    benign_for: Callable[[list[ChannelPair], np.ndarray], BenignModel | None],
                    false_alarm: float = 0.01) -> float | None:
    """The smallest open-crack loss of ``element`` the sensors ``sensors`` (labels of ``ports``) detect with
    the benign ranges (:func:`rotorcheck.detectability.detectability`, the benign model linearized)."""
    f = np.asarray(freq_hz, dtype=float)
    prs = [ChannelPair(ports[list(labels).index(s)], a, "") for s in sensors for a in actuators]
    th = io_frf(config, f, speed_rpm, prs)
    bm = benign_for(prs, th)
    vn = np.broadcast_to(np.asarray(var_new, dtype=float).reshape(f.size, 1), th.shape)
    vb = np.broadcast_to(np.asarray(var_base, dtype=float).reshape(f.size, 1), th.shape)
    det = detectability(config, f, speed_rpm, vn, vb, prs, th, false_alarm, None if bm is None else linearized(bm),
                        [element], workers=1, model_frf=th)
    return next(e.open_loss_min for e in det.elements if e.element == element)
