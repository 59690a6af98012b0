"""Where and how big: every shaft element a candidate for a local stiffness loss (``rotorcheck locate``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError
from rotorcheck.location import LocationResult, locate
from rotorcheck.signatures import benign_box
from rotorcheck.variability import benign_at
from rotorcheck.workflow.benign import KAPPA_NOMINAL, benign_model
from rotorcheck.workflow.detection import healthy_frf_of
from rotorcheck.workflow.measured import MeasuredRun, frf_estimate, per_pair, run_harmonics
from rotorcheck.workflow.rigs import baseline_updates, check_elements, updated_rig


def locate_damage(rig: RigConfig, baseline: Baseline, run: MeasuredRun, false_alarm: float = 0.01,
                  elements: tuple[int, ...] | None = None, section_length: float | None = None,
                  both: bool = True, **options: Any) -> LocationResult:
    """Where and how big (:func:`rotorcheck.location.locate`) against a baseline validated with
    ``--enclose measured``: :func:`locate_run` with its healthy FRF, speed and updated model."""
    if baseline.enclose != "measured" or healthy_frf_of(baseline) is None:
        raise InputError(None, "--baseline", "locating needs a baseline validated with --enclose measured "
                         f"(this one: {baseline.enclose!r})")
    return locate_run(updated_rig(rig, baseline_updates(baseline)), run, np.asarray(baseline.healthy_frf),
                      np.asarray(baseline.healthy_frf_var), baseline.speed_rpm, false_alarm, elements,
                      section_length, both, **options)


def locate_run(rig: RigConfig, run: MeasuredRun, healthy_frf: np.ndarray, healthy_var: np.ndarray,
               speed_rpm: float | None = None, false_alarm: float = 0.01, elements: tuple[int, ...] | None = None,
               section_length: float | None = None, both: bool = True, **options: Any) -> LocationResult:
    """Every shaft element (or ``elements``) as a candidate for a local stiffness loss
    (:func:`rotorcheck.location.locate`), ``run`` against the healthy FRF (f,) or (f, P) and the variance
    of its mean, the rig's benign parameters real in their ranges (at the healthy ``speed_rpm``; the run's
    offset from it moves the speed range). With several channel pairs and ``both``, the rig's own actuator
    -> sensor pair alone is located too (``result.single_channel``). ``section_length`` (m): the breathing
    crack's, for depths. ``options`` go to :func:`rotorcheck.location.locate`. Points on a shaft harmonic (at
    the run's or the healthy speed, :func:`~rotorcheck.workflow.measured.run_harmonics`) are not used."""

    if rig.kind != "rotor":
        raise InputError(None, "--rig", "locating needs a rotor's shaft elements; this rig is lumped")
    if not 0.0 < false_alarm < 1.0:
        raise InputError(None, "--false-alarm", f"must be in (0, 1), got {false_alarm}")
    elements = check_elements(rig, elements)
    f = run.frequency_hz
    est = frf_estimate(run)
    n_pairs = est.frf.shape[1]
    th, vh = per_pair(healthy_frf, f, n_pairs, run), per_pair(healthy_var, f, n_pairs, run)
    speed = run.speed_rpm if speed_rpm is None else speed_rpm
    params = benign_at(rig, speed) if rig.variability else ()
    box = benign_box(rig, speed, params, run.speed_rpm - speed)
    pairs = list(run.pairs)
    bm = benign_model(rig, f, speed, th, KAPPA_NOMINAL, run.speed_rpm - speed, None, pairs if n_pairs > 1 else None)
    env = np.zeros(f.size * n_pairs) if bm is None else np.asarray(bm.envelope, dtype=float)
    harmonics = run_harmonics([run], (speed,))
    out = harmonics.flagged
    res = locate(rig, box, pairs, f, speed, est.frf, est.var, th, vh, env, false_alarm, elements,
                 crack_section_length=section_length, exclude=out, **options)
    if both and n_pairs > 1:
        res.single_channel = locate(rig, box.for_pair(pairs[0]), pairs[:1], f, speed, est.frf[:, :1],
                                    est.var[:, :1], th[:, :1], vh[:, :1], env[:f.size], false_alarm, elements,
                                    crack_section_length=section_length, exclude=out, **options)
    if harmonics.n_flagged:
        res.notes.append(harmonics.warning("the points the location uses"))
    return res

