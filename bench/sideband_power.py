"""The sideband test (``detect --rule sideband``) on five truths, with drift inside the ranges (seeded).

Every sweep is a fresh simulation of a truth variant (:mod:`bench.truth_variants`) at 1000 rpm with its benign
parameters drawn uniformly inside the bundled rig's ranges (E and G +-2 %, each bearing +-3 %, gain +-1 %, speed
+-20 rpm), a random shaft angle at the start, and the sidebands f + k x speed (k = -2, -1, 1, 2) measured on
the samples' 262-point grid (the least-squares fit of :mod:`rotorcheck.signal.sidebands`). The detector uses
neither the model nor a healthy sweep, so the number of healthy sweeps cannot change its power.

Cells: false alarms on healthy drifted sweeps (the stated rate: 1 %); breathing cracks (Mayes-Davies, the truth
rig's crack law) of depth 4 / 5 / 7.5 / 10 % of the diameter in elements 2-8 (``--per-element`` sweeps each).
Each sweep is read three ways: the test as ``detect --rule sideband`` runs it (the scan over windows, 1 %); as the
default runs it beside the joint test (the scan at half the rate, 0.5 %: the default calls damage at least then);
and the sum over every point alone (1 %, the first version, for comparison).
``python -m bench.sideband_power [--variants truth,dampers] [--healthy 100] [--per-element 3] [--xy]``
(``--xy``: forces 8x and 8y, x and y probes at stations 6 and 2: 8 channel pairs).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from typing import Any

import numpy as np

from bench.detection_limit import _inside
from bench.detection_power import GRID
from bench.location import XY_ACTUATORS, XY_SENSORS
from bench.truth_variants import VARIANTS, nominal, truth_variant
from rotorcheck import workflow
from rotorcheck.config import RigConfig
from rotorcheck.signal.sidebands import SCAN_WIDTHS, sideband_scan
from rotorcheck.sim.rig_sim import simulate_rig, simulate_rig_patterns, step_settings
from rotorcheck.variability import with_benign

ORDERS = (-2, -1, 1, 2)
DEPTHS = (0.04, 0.05, 0.075, 0.1)
ELEMENTS = (2, 3, 4, 5, 6, 7, 8)
#: the three readings of a sweep (columns): name, scan widths, false-alarm rate
READINGS = (("--rule sideband", SCAN_WIDTHS, 0.01), ("in the default (0.5 %)", SCAN_WIDTHS, 0.005),
            ("sum over every point", (0,), 0.01))
SPEED = 1000.0


def called(truth: RigConfig, nom: RigConfig, seed: int, fault: str | None, xy: bool = False) -> tuple[bool, ...]:
    """One drifted sweep (``xy``: forces 8x, 8y and x/y probes at stations 6 and 2, 8 channel pairs): called damage
    under each of :data:`READINGS`."""
    values = _inside(np.random.default_rng([seed, 17]))
    cfg, d_rpm, _, _ = with_benign(truth, values)  # a gain scales the sidebands and their noise alike
    st = dataclasses.replace(step_settings(cfg), sideband_orders=ORDERS)
    angle = float(np.random.default_rng([seed, 99]).uniform(0.0, 2.0 * np.pi))
    if xy:
        sw = simulate_rig_patterns(cfg, GRID, XY_ACTUATORS, XY_SENSORS, speed_rpm=SPEED + d_rpm, fault=fault,
                                   seed=seed, settings=st, shaft_angle_rad=angle)
    else:
        sw = simulate_rig(cfg, GRID, SPEED + d_rpm, fault=fault, seed=seed, settings=st, shaft_angle_rad=angle)
    sb = workflow.measured_run(sw, nom).sidebands
    assert sb is not None
    t, n = sb.statistic()
    return tuple(sideband_scan(t, n, widths).p_value < alpha for _, widths, alpha in READINGS)


def run_variant(name: str, healthy: int, per_element: int, log: Any, depths: tuple[float, ...] = DEPTHS,
                seed0: int = 0, xy: bool = False) -> dict[str, Any]:
    nom = nominal()
    truth = truth_variant(name, nom)
    out: dict[str, Any] = {}
    t = time.perf_counter()
    fa = np.array([called(truth, nom, seed0 + 7_000_000 + k, None, xy) for k in range(healthy)])
    out["healthy"] = (fa.sum(axis=0), healthy)
    log(f"{name}: healthy called damage {fa.sum(axis=0)}/{healthy} ({time.perf_counter() - t:.0f} s)")
    for depth in depths:
        rows = []
        for el in ELEMENTS:
            faults = dict(truth.faults)
            faults["loc"] = truth.faults["breathing_crack"].model_copy(  # type: ignore[union-attr]
                update={"element": el, "depth": depth})
            cfg = truth.model_copy(update={"faults": faults})
            rows += [called(cfg, nom, seed0 + 7_100_000 + int(depth * 1e4) * 100 + el * 10 + k, "loc", xy)
                     for k in range(per_element)]
        hits = np.array(rows)
        out[depth] = (hits.sum(axis=0), len(rows))
        log(f"{name}: depth {100 * depth:g} %: {hits.sum(axis=0)}/{len(rows)} ({time.perf_counter() - t:.0f} s)")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--healthy", type=int, default=100)
    ap.add_argument("--per-element", type=int, default=3)
    ap.add_argument("--depths", default=",".join(f"{d:g}" for d in DEPTHS), help="crack depths ('' for none)")
    ap.add_argument("--seed-by-variant", action="store_true",
                    help="other seeds per variant (a healthy rotor's sidebands are noise alone: with the same seeds "
                         "every variant draws the same healthy sweeps)")
    ap.add_argument("--xy", action="store_true", help="forces 8x, 8y and x/y probes at stations 6 and 2")
    args = ap.parse_args(argv)
    depths = tuple(float(x) for x in args.depths.split(",") if x.strip())

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    names = [v.strip() for v in args.variants.split(",") if v.strip()]
    res = {v: run_variant(v, args.healthy, args.per_element, log, depths,
                          100_000_000 * (1 + list(VARIANTS).index(v)) if args.seed_by_variant else 0, args.xy)
           for v in names}
    for i, (reading, _, alpha) in enumerate(READINGS):
        print(f"\n{reading} (false-alarm rate {alpha:g})\n")
        print("| | " + " | ".join(names) + " |")
        print("|---|" + "---:|" * len(names))
        print("| healthy, drift inside the ranges: called damage | " + " | ".join(
            f"{res[v]['healthy'][0][i]} / {res[v]['healthy'][1]}" for v in names) + " |")
        for depth in depths:
            print(f"| breathing {100 * depth:g} % depth, elements {ELEMENTS[0]}-{ELEMENTS[-1]}: detected | "
                  + " | ".join(f"{res[v][depth][0][i]} / {res[v][depth][1]}" for v in names) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
