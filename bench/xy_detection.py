"""Detection with x and y probes at two stations, with drift (issue 29's x/y row), per truth variant.

As :mod:`bench.independent_physics` (one healthy baseline sweep at the truth's nominal state, new sweeps drifted
uniformly inside the declared ranges, the product's default joint test at 1 % false alarms, the verdict alone), but
every sweep measured by the x/y pattern of :mod:`bench.location` (forces x and y at station 8; x and y probes at
stations 6 and 2: eight channel pairs) at 0 rpm: healthy sweeps (false alarms) and open cracks in element 4
(stiffness loss). limits.md section 3 gives the bounded-drift limit of that sensor set: 0.035 % loss (goal: within
2x, 0.07 %). Seeded; prints a Markdown table, one column per variant.

``python -m bench.xy_detection [--healthy 20 --cracks 10] [--variants truth,dampers] [--losses 0.005,0.02,0.05]``
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
           benign: dict[str, float] | None = None) -> workflow.MeasuredRun:
    """One simulated x/y sweep at rest of ``truth`` (benign values applied; speed has none at rest), as read."""
    values = {k: v for k, v in (benign or {}).items() if k != "speed"}
    cfg, _, g_s, g_a = with_benign(truth, values) if values else (truth, 0.0, 1.0, 1.0)
    sw = simulate_rig_patterns(cfg, GRID, XY_ACTUATORS, XY_SENSORS, speed_rpm=0.0, fault=fault, seed=seed,
                               settings=step_settings(cfg, keep_periods=False))
    run = workflow.measured_run(sw, nom)
    g = g_s * g_a
    if g == 1.0:
        return run
    return dataclasses.replace(run, Zt=run.Zt * g, output_var=run.output_var * g**2)


def run_variant(name: str, n_healthy: int, n_cracks: int, losses: tuple[float, ...], log: Any) -> dict[str, str]:
    """``{row label: 'k/n'}`` for one truth variant."""
    nom = nominal()
    truth = truth_variant(name, nom)
    t0 = time.perf_counter()
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


def main(argv: list[str] | None = None) -> int:
    a = arguments(__doc__ or "", LOSSES).parse_args(argv)
    losses = tuple(float(x) for x in a.losses.split(","))
    names = a.variants.split(",")
    print_columns("x/y probes at stations 6 and 2, 0 rpm",
                  {n: run_variant(n, a.healthy, a.cracks, losses, log) for n in names})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
