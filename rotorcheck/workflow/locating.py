"""Where and how big: every shaft element a candidate for a local stiffness loss, ranked by one machinery
(:func:`rotorcheck.ranking.rank_elements`) for ``detect``'s diagnosis and ``rotorcheck locate`` (which adds
the certificates: exclusions and certified intervals)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import Port, RigConfig
from rotorcheck.errors import InputError
from rotorcheck.location import LocationResult, locate
from rotorcheck.nominal import ChannelPair, model_pairs, port_label
from rotorcheck.progress import Progress
from rotorcheck.ranking import Ranking, SweepChange, sweep_change
from rotorcheck.sensor_advice import SensorAdvice, advise_sensors, hypotheses_of
from rotorcheck.signatures import BenignBox, benign_box, modal_anchor
from rotorcheck.variability import benign_at
from rotorcheck.workflow.benign import benign_model
from rotorcheck.workflow.detectors import DetectorSettings, make_detector
from rotorcheck.workflow.measured import MeasuredRun, frf_estimate, healthy_frf_of, per_pair, run_harmonics
from rotorcheck.workflow.rigs import baseline_rig, check_elements


@dataclass(frozen=True)
class LocationInputs:
    """What a location reads, made once per run: the benign box, the channel pairs and the sweep's change."""

    rig: RigConfig
    box: BenignBox
    pairs: list[ChannelPair]
    change: SweepChange
    harmonics_warning: str = ""  # the points left out on a shaft harmonic ('' when none)


def location_inputs(rig: RigConfig, run: MeasuredRun, healthy_frf: np.ndarray, healthy_var: np.ndarray,
                    speed_rpm: float | None = None) -> LocationInputs:
    """``run`` against the healthy FRF (f,) or (f, P) and the variance of its mean, the rig's benign
    parameters real in their ranges (at the healthy ``speed_rpm``; the run's offset from it moves the
    speed range). Points on a shaft harmonic (at the run's or the healthy speed,
    :func:`~rotorcheck.workflow.measured.run_harmonics`) are not used."""
    if rig.kind != "rotor":
        raise InputError(None, "--rig", "locating needs a rotor's shaft elements; this rig is lumped")
    f = run.frequency_hz
    est = frf_estimate(run)
    n_pairs = est.frf.shape[1]
    th, vh = per_pair(healthy_frf, f, n_pairs, run), per_pair(healthy_var, f, n_pairs, run)
    speed = run.speed_rpm if speed_rpm is None else speed_rpm
    params = benign_at(rig, speed) if rig.variability else ()
    box = benign_box(rig, speed, params, run.speed_rpm - speed)
    pairs = list(run.pairs)
    bm = benign_model(rig, f, speed, th, None, run.speed_rpm - speed, None, pairs if n_pairs > 1 else None,
                      healthy_var=vh)
    env = np.zeros(f.size * n_pairs) if bm is None else np.asarray(bm.envelope, dtype=float)
    harmonics = run_harmonics([run], (speed,))
    anchor = (modal_anchor(rig, f, speed, th, pairs if n_pairs > 1 else None, vh)
              if speed == 0.0 and run.speed_rpm == 0.0 else None)  # standstill: sized by the pole shifts
    change = sweep_change(box, pairs, f, speed, est.frf, est.var, th, vh, env, harmonics.flagged, anchor)
    warning = harmonics.warning("the points the location uses") if harmonics.n_flagged else ""
    return LocationInputs(rig, box, pairs, change, warning)


def locate_run(rig: RigConfig, run: MeasuredRun, healthy_frf: np.ndarray, healthy_var: np.ndarray,
               speed_rpm: float | None = None, false_alarm: float = 0.01, elements: tuple[int, ...] | None = None,
               section_length: float | None = None, both: bool = False, certify: bool = True,
               damage: bool | None = None, ranking: Ranking | None = None, progress: Progress | None = None,
               **options: Any) -> LocationResult:
    """Every shaft element (or ``elements``) as a candidate for a local stiffness loss
    (:func:`rotorcheck.location.locate` on :func:`location_inputs`): ranked, and with ``certify`` excluded or
    given certified intervals. ``damage``: the detector's verdict where known; ``ranking`` one already made
    for this run (``detect``'s). With several channel pairs and ``both``, the rig's own actuator -> sensor
    pair alone is located too (``result.single_channel``; twice the time). ``section_length`` (m): the
    breathing crack's, for depths. ``progress`` hears each element done; ``options`` go to
    :func:`rotorcheck.location.locate`."""
    if not 0.0 < false_alarm < 1.0:
        raise InputError(None, "--false-alarm", f"must be in (0, 1), got {false_alarm}")
    elements = check_elements(rig, elements)
    inp = location_inputs(rig, run, healthy_frf, healthy_var, speed_rpm)
    res = locate(rig, inp.box, inp.pairs, inp.change, false_alarm, elements, crack_section_length=section_length,
                 ranking=ranking, certify=certify, damage=damage, progress=progress, **options)
    if both and len(inp.pairs) > 1:
        one = inp.change
        cols = ("t_new", "var_new", "t_h", "var_h", "a", "err", "g_zero", "trusted", "change2", "B", "Cm")
        first = {k: getattr(one, k)[:, :1] for k in cols}
        single = dataclasses.replace(one, **first, anchor=None)
        res.single_channel = locate(rig, inp.box.for_pair(inp.pairs[0]), inp.pairs[:1], single, false_alarm, elements,
                                    crack_section_length=section_length, certify=certify, damage=damage, **options)
    if res.kind == "not locatable":
        advice = sensor_advice(inp, run, res, speed_rpm, false_alarm)
        res.sensor_advice, res.sensor_advice_detail = advice.text(), advice.to_dict()
    if inp.harmonics_warning:
        res.notes.append(inp.harmonics_warning)
    return res


def sensor_advice(inp: LocationInputs, run: MeasuredRun, result: LocationResult, speed_rpm: float | None = None,
                  false_alarm: float = 0.01, candidates: list[Port] | None = None) -> SensorAdvice:
    """The smallest set of probes that would locate what ``result`` (not locatable) left open
    (:func:`rotorcheck.sensor_advice.advise_sensors`): the run's actuators, its FRF noise per point (the
    median over its pairs), the frequencies every measured pair trusts, the benign ranges at the healthy
    ``speed_rpm`` (default the run's) moved by the run's offset from it; ``candidates`` default: x and y
    probes at every station."""
    rig, ch = inp.rig, inp.change
    f = ch.freq_hz
    speed = run.speed_rpm if speed_rpm is None else speed_rpm

    def benign_for(pairs: list[ChannelPair], th: np.ndarray) -> Any:
        return benign_model(rig, f, speed, th, None, run.speed_rpm - speed, None, model_pairs(rig, pairs),
                            modal=False)  # candidate channels have no measured FRF: the model's own, re-solved

    sensors = list({port_label(p.output): p.output for p in inp.pairs}.values())
    actuators = list({port_label(p.input): p.input for p in inp.pairs}.values())
    trusted = np.all(ch.trusted, axis=1, keepdims=False).astype(bool)  # by every measured pair
    return advise_sensors(rig, f, speed, np.median(ch.var_new, axis=1), np.median(ch.var_h, axis=1), sensors,
                          actuators, hypotheses_of(result), benign_for, candidates, trusted, false_alarm)


def detector_says_damage(rig: RigConfig, baseline: Baseline, run: MeasuredRun, false_alarm: float = 0.01) -> bool:
    """The default detector's verdict on ``run`` (as ``detect`` with its defaults and ``false_alarm``) is damage."""
    settings = DetectorSettings(false_alarm=false_alarm, verdict_only=True)
    found = make_detector(rig, baseline, None, settings).detect(run)
    return found.verdict.verdict == "damage"


def locate_damage(rig: RigConfig, baseline: Baseline, run: MeasuredRun, false_alarm: float = 0.01,
                  elements: tuple[int, ...] | None = None, section_length: float | None = None,
                  both: bool = False, certify: bool = True, damage: bool | None = None,
                  ranking: Ranking | None = None, progress: Progress | None = None, **options: Any) -> LocationResult:
    """Where and how big (:func:`locate_run`) against a baseline validated with ``--enclose measured``: its
    healthy FRF, speed and updated model. ``damage`` None: the default detector decides first (so that
    ``locate`` never says "no damage" where ``detect`` says damage)."""
    if baseline.enclose != "measured" or healthy_frf_of(baseline) is None:
        raise InputError(None, "--baseline", "locating needs a baseline validated with --enclose measured "
                         f"(this one: {baseline.enclose!r})")
    if damage is None:
        damage = detector_says_damage(rig, baseline, run, false_alarm)
    return locate_run(baseline_rig(rig, baseline), run, np.asarray(baseline.healthy_frf),
                      np.asarray(baseline.healthy_frf_var), baseline.speed_rpm, false_alarm, elements,
                      section_length, both, certify, damage, ranking, progress, **options)
