"""Detection with x and y probes at two stations, with drift (issue 29's x/y row), per truth variant.

As :mod:`bench.independent_physics` (one healthy baseline sweep at the truth's nominal state, new sweeps drifted
uniformly inside the declared ranges, the product's default joint test at 1 % false alarms, the verdict alone), but
every sweep measured by the x/y pattern of :mod:`bench.location` (forces x and y at station 8; x and y probes at
stations 6 and 2: eight channel pairs) at 0 rpm: healthy sweeps (false alarms) and open cracks in element 4
(stiffness loss). limits.md section 3 gives the bounded-drift limit of that sensor set: 0.035 % loss (goal: within
2x, 0.07 %). With ``--speed 1000``: the same at 1000 rpm (the speed drifts too) with the truth's breathing crack in
element 4 at ``--depths``. Seeded; prints a Markdown table, one column per variant.

``python -m bench.xy_detection [--healthy 20 --cracks 10] [--variants truth,dampers] [--losses 0.005,0.02,0.05]
[--speed 1000 --depths 0.2,0.3]``
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from bench.detection_limit import _inside
from bench.detection_power import GRID, _open_crack
from bench.independent_physics import _called, arguments, log, print_columns
from bench.location import XY_ACTUATORS, XY_SENSORS
from bench.truth_variants import nominal, truth_variant
from rotorcheck import workflow
from rotorcheck.config import RigConfig
from rotorcheck.sim.rig_sim import simulate_rig_patterns, step_settings
from rotorcheck.variability import with_benign

LOSSES = (0.005, 0.02, 0.05)


def xy_run(truth: RigConfig, nom: RigConfig, seed: int, fault: str | None = None,
           benign: dict[str, float] | None = None, speed: float = 0.0) -> workflow.MeasuredRun:
    """One simulated x/y sweep of ``truth`` at ``speed`` rpm (benign values applied: the speed's at rest none; a
    turning shaft starts at a seeded angle), as read."""
    values = {k: v for k, v in (benign or {}).items() if not (k == "speed" and speed == 0.0)}
    cfg, d_rpm, g_s, g_a = with_benign(truth, values) if values else (truth, 0.0, 1.0, 1.0)
    angle = float(np.random.default_rng([seed, 99]).uniform(0.0, 2.0 * np.pi)) if speed else 0.0
    sw = simulate_rig_patterns(cfg, GRID, XY_ACTUATORS, XY_SENSORS, speed_rpm=speed + d_rpm, fault=fault, seed=seed,
                               settings=step_settings(cfg, keep_periods=False), shaft_angle_rad=angle)
    run = workflow.measured_run(sw, nom)
    g = g_s * g_a
    if g == 1.0:
        return run
    # the gain scales every pair (the first pair's phasors and the several pairs' FRFs alike)
    return dataclasses.replace(run, Zt=run.Zt * g, output_var=run.output_var * g**2,
                               frf_pairs=None if run.frf_pairs is None else run.frf_pairs * g,
                               var_pairs=None if run.var_pairs is None else run.var_pairs * g**2)


def run_variant(name: str, n_healthy: int, n_cracks: int, losses: tuple[float, ...], log: Any,
                speed: float = 0.0, depths: tuple[float, ...] = ()) -> dict[str, str]:
    """``{row label: 'k/n'}`` for one truth variant (at ``speed`` > 0 breathing cracks of ``depths``)."""
    nom = nominal()
    truth = truth_variant(name, nom)
    t0 = time.perf_counter()
    if speed:
        return _turning(name, truth, nom, n_healthy, n_cracks, depths, speed, log)
    h = xy_run(truth, nom, 41_000_000)
    base = workflow.validate(nom, [h], workflow.fit_noise(h), enclose="measured").baseline
    rng = np.random.default_rng([0, 41])
    out: dict[str, str] = {}
    k = sum(_called(nom, base, xy_run(truth, nom, 42_000_000 + i, benign=_inside(rng))) for i in range(n_healthy))
    out["false alarms, healthy drifted inside the ranges"] = f"{k}/{n_healthy}"
    log(f"{name} x/y healthy: {k}/{n_healthy} ({time.perf_counter() - t0:.0f} s)")
    for loss in losses:
        cfg = _open_crack(truth, 1.0 - loss)
        k = sum(_called(nom, base, xy_run(cfg, nom, 43_000_000 + int(loss * 1e5) * 100 + i, "open_crack",
                                          benign=_inside(rng))) for i in range(n_cracks))
        out[f"open crack element 4, {100 * loss:g} % loss: detected"] = f"{k}/{n_cracks}"
        log(f"{name} x/y open {loss}: {k}/{n_cracks}")
    return out


def _turning(name: str, truth: RigConfig, nom: RigConfig, n_healthy: int, n_cracks: int, depths: tuple[float, ...],
             speed: float, log: Any) -> dict[str, str]:
    """:func:`run_variant` at ``speed``: false alarms, then breathing cracks of element 4 at ``depths``."""
    t0 = time.perf_counter()
    s = int(speed)
    h = xy_run(truth, nom, 44_000_000 + s, speed=speed)
    base = workflow.validate(nom, [h], workflow.fit_noise(h), enclose="measured").baseline
    rng = np.random.default_rng([s, 41])
    out: dict[str, str] = {}
    k = sum(_called(nom, base, xy_run(truth, nom, 45_000_000 + s + i, benign=_inside(rng), speed=speed))
            for i in range(n_healthy))
    out["false alarms, healthy drifted inside the ranges"] = f"{k}/{n_healthy}"
    log(f"{name} x/y {speed:g} rpm healthy: {k}/{n_healthy} ({time.perf_counter() - t0:.0f} s)")
    for depth in depths:
        cfg = workflow.rig_with_crack_depth(truth, None, "breathing_crack", depth)
        k = sum(_called(nom, base, xy_run(cfg, nom, 46_000_000 + s + int(depth * 1e3) * 100 + i, "breathing_crack",
                                          benign=_inside(rng), speed=speed)) for i in range(n_cracks))
        out[f"breathing crack element 4, {100 * depth:g} % depth: detected"] = f"{k}/{n_cracks}"
        log(f"{name} x/y {speed:g} rpm breathing {depth}: {k}/{n_cracks}")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = arguments(__doc__ or "", LOSSES)
    ap.add_argument("--speed", type=float, default=0.0, help="rpm (0: open cracks; else breathing cracks)")
    ap.add_argument("--depths", default="0.2,0.3", help="breathing depths at --speed, of the diameter")
    a = ap.parse_args(argv)
    losses = tuple(float(x) for x in a.losses.split(","))
    depths = tuple(float(x) for x in a.depths.split(","))
    names = a.variants.split(",")
    print_columns(f"x/y probes at stations 6 and 2, {a.speed:g} rpm",
                  {n: run_variant(n, a.healthy, a.cracks, losses, log, a.speed, depths) for n in names})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
