"""Detectability and sensor ranking from a baseline or from stated noise (``rotorcheck detectability``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.detectability import (
    DETECTABILITY_RULE_SETS,
    Detectability,
    detectability,
    rank_sensor_sets,
    score_sensor_set,
    stated_noise_variance,
)
from rotorcheck.errors import InputError
from rotorcheck.nominal import ChannelPair, model_pairs, parse_port
from rotorcheck.progress import Progress
from rotorcheck.signatures import io_frf
from rotorcheck.workflow.benign import benign_model
from rotorcheck.workflow.rigs import baseline_rig, check_elements

DETECTABILITY_POINTS = 262  # grid of a prediction from stated noise without analysis.n_points


def _prediction_ports(config: RigConfig, sensors: Sequence[str] | None, actuators: Sequence[str] | None,
                      source: str, candidates: Sequence[str] = ()) -> tuple[list[Any], list[Any], list[Any]]:
    """``(sensors, actuators, candidates)`` as ports (``6x``, ``s2.y``; default: the rig's sensor and actuator),
    every station checked against the rig; no actuator is an InputError."""

    ports = config.ports
    acts = [parse_port(a, "--actuators") for a in actuators] if actuators else (
        [ports.actuator] if ports is not None else [])
    sens = [parse_port(s, "--sensors") for s in sensors] if sensors else (
        [ports.sensor] if ports is not None else [])
    cand = [parse_port(c, "--candidate-sensors") for c in candidates]
    if not acts:
        raise InputError(source or None, "ports", "the rig has no ports: give --sensors and --actuators")
    n = len(config.stations)
    for option, ports_ in (("--sensors/--actuators", (*acts, *sens)), ("--candidate-sensors", cand)):
        for p in ports_:
            if p.station is None or not 1 <= p.station <= n:
                raise InputError(None, option, f"station {p.station} out of range 1..{n}")
    return sens, acts, cand


def _stated_prediction(config: RigConfig, speed_rpm: float | None, noise_std_m: float | None, periods: int | None,
                       source: str, hint: str = "no noise to predict from: give --baseline or --noise-std (m)"
                       ) -> tuple[np.ndarray, float, float, str]:
    """``(grid Hz, speed rpm, FRF variance per point and sweep m^2/N^2, its description)`` from stated noise
    (``noise_std_m`` over ``periods``, defaults the rig's ``measurement``) on the rig's analysis grid
    (``n_points`` or :data:`DETECTABILITY_POINTS`) at ``speed_rpm`` (default: its first speed)."""

    m = config.measurement
    sigma = noise_std_m if noise_std_m is not None else (m.output_noise_std or None)
    if sigma is None or sigma <= 0:
        raise InputError(source or None, "measurement.output_noise_std", hint)
    n_per = int(periods) if periods is not None else m.n_periods
    if n_per < 1:
        raise InputError(None, "--periods", "must be >= 1")
    f = np.linspace(*config.analysis.band_hz, config.analysis.n_points or DETECTABILITY_POINTS)
    v = stated_noise_variance(float(sigma), n_per, m.samples_per_period, m.force_amplitude)
    speed = float(config.analysis.speeds_rpm[0]) if speed_rpm is None else float(speed_rpm)
    noise = (f"stated noise: output sigma {sigma:.3g} m, {n_per} periods of {m.samples_per_period} samples at "
             f"{m.force_amplitude:g} N (FRF variance {v:.3g} m^2/N^2 per point and sweep)")
    return f, speed, v, noise


def detectability_for_rig(
    config: RigConfig,
    speed_rpm: float | None = None,
    baseline: Baseline | None = None,
    noise_std_m: float | None = None,
    periods: int | None = None,
    sensors: Sequence[str] | None = None,
    actuators: Sequence[str] | None = None,
    false_alarm: float = 0.01,
    elements: Sequence[int] | None = None,
    workers: int | None = None,
    source: str = "",
    progress: Progress | None = None,
) -> Detectability:
    """:func:`rotorcheck.detectability.detectability` with its inputs resolved the way the CLI does. Grid and speed: the
    baseline's (``baseline``, a :class:`rotorcheck.baseline.Baseline`), else the rig's ``analysis``
    (band, ``n_points`` or 262 points; its first speed). Noise: the baseline's healthy variance (the
    new sweep taken as one sweep like those it averaged), else ``noise_std_m`` over ``periods`` (default:
    the rig's ``measurement``), else the rig's own ``measurement.output_noise_std``; none of them: an
    :class:`~rotorcheck.errors.InputError`. Sensors and actuators: ports as ``6x``, ``s2.y`` (default: the
    rig's); every sensor with every actuator is one channel pair."""
    elements = check_elements(config, elements)

    sens, acts, _ = _prediction_ports(config, sensors, actuators, source)
    if not sens:
        raise InputError(source or None, "ports", "the rig has no ports: give --sensors and --actuators")
    pairs = [ChannelPair(o, i, "") for o in sens for i in acts]
    if baseline is not None:
        if baseline.frequency_hz is None or baseline.healthy_frf_var is None or baseline.healthy_frf is None:
            raise InputError(source or None, "healthy_frf_var", "the baseline holds no healthy FRF and variance "
                             "(run rotorcheck validate)")
        if sensors or actuators:
            raise InputError(None, "--sensors", "with --baseline the channels are the baseline's; give stated noise "
                             "(--noise-std) to try other sensors")
        f = np.asarray(baseline.frequency_hz, dtype=float)
        var_b = np.asarray(baseline.healthy_frf_var, dtype=float)
        var_n = var_b * max(int(baseline.n_healthy), 1)
        th = np.asarray(baseline.healthy_frf)
        if th.ndim == 2 and th.shape[1] != len(pairs):
            raise InputError(source or None, "healthy_frf", f"the baseline has {th.shape[1]} channel pairs; "
                             "detectability from a baseline takes the rig's own pair only")
        speed = float(baseline.speed_rpm) if speed_rpm is None else float(speed_rpm)
        noise = (f"noise from the baseline {source} (healthy variance per point, {baseline.n_healthy} healthy "
                 "sweep(s); the new sweep as one)")
        th = th.reshape(f.size, -1)
        kappa = None if baseline.benign_kappa is None else float(baseline.benign_kappa)
        vh = None if baseline.healthy_frf_var is None else np.asarray(baseline.healthy_frf_var).reshape(f.size, -1)
        config = baseline_rig(config, baseline)
        bm = benign_model(config, f, speed, th[:, 0], kappa, modal=baseline.drift.on_anchor,
                          healthy_var=None if vh is None else vh[:, 0])
        return detectability(config, f, speed, var_n.reshape(f.size, -1), var_b.reshape(f.size, -1), pairs,
                             th, false_alarm, bm, elements, None, noise, workers, progress=progress)
    f, speed, v, noise = _stated_prediction(config, speed_rpm, noise_std_m, periods, source)
    var = np.full((f.size, len(pairs)), v)
    multi = model_pairs(config, pairs)
    th = io_frf(config, f, speed, multi)
    bm = benign_model(config, f, speed, th, None, 0.0, None, multi, modal=False)  # the model's own FRF: re-solved
    return detectability(config, f, speed, var, var, pairs, th, false_alarm, bm, elements, None, noise, workers,
                         model_frf=th, progress=progress)


def sensor_ranking_for_rig(
    config: RigConfig,
    candidates: Sequence[str],
    max_sensors: int,
    speed_rpm: float | None = None,
    noise_std_m: float | None = None,
    periods: int | None = None,
    sensors: Sequence[str] | None = None,
    actuators: Sequence[str] | None = None,
    false_alarm: float = 0.01,
    source: str = "",
) -> dict[str, Any]:
    """Sensor sets from ``candidates`` (ports like ``2x``) ranked by their worst element's detectable
    breathing depth with the benign ranges (:func:`rotorcheck.detectability.rank_sensor_sets`; stated
    noise as :func:`detectability_for_rig`), with the current set (``sensors`` or the rig's) scored the
    same way. Returns the JSON section ``sensor_sets``."""

    if max_sensors < 1:
        raise InputError(None, "--max-sensors", "must be >= 1")
    current, acts, cand = _prediction_ports(config, sensors, actuators, source, candidates)
    f, speed, v, _ = _stated_prediction(config, speed_rpm, noise_std_m, periods, source,
                                        "ranking sensors needs stated noise: give --noise-std (m)")

    def benign_for(pairs: list[ChannelPair], th: np.ndarray) -> Any:
        return benign_model(config, f, speed, th, None, 0.0, None, model_pairs(config, pairs), modal=False)

    try:
        ranked, method, seen = rank_sensor_sets(config, f, speed, v, cand, acts, max_sensors, benign_for, false_alarm)
    except ValueError as exc:  # no candidate sees any element: the user's choice of ports, said as such
        raise InputError(source or None, "--candidate-sensors", str(exc)) from None
    now = score_sensor_set(config, f, speed, v, current, acts, benign_for, false_alarm, seen) if current else None
    best = ranked[0]

    def ratio(a: float | None, b: float | None) -> float | None:
        """How many times smaller the best set's figure is (inf: the current set cannot watch it at all)."""
        if b is None or b <= 0:
            return None
        return float("inf") if a is None else a / b

    return {"method": method, "max_sensors": max_sensors, "rule": DETECTABILITY_RULE_SETS,
            "elements_scored": list(seen), "best": [s.to_dict() for s in ranked[:5]],
            "current": None if now is None else now.to_dict(),
            "gain_worst_depth": None if now is None else ratio(now.worst_depth, best.worst_depth),
            "gain_worst_loss": None if now is None else ratio(now.worst_loss, best.worst_loss)}

