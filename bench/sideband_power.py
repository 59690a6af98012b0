"""The sideband test (``detect --rule sideband``) on five truths, with drift inside the ranges (seeded).

Every sweep is a fresh simulation of a truth variant (:mod:`bench.truth_variants`) at 1000 rpm with its benign
parameters drawn uniformly inside the bundled rig's ranges (E and G +-2 %, each bearing +-3 %, gain +-1 %, speed
+-20 rpm), a random shaft angle at the start, and the sidebands f + k x speed (k = -2, -1, 1, 2) measured on
the samples' 262-point grid (the least-squares fit of :mod:`rotorcheck.signal.sidebands`). The detector uses
neither the model nor a healthy sweep, so the number of healthy sweeps cannot change its power.

Cells: false alarms on healthy drifted sweeps (the stated rate: 1 %); breathing cracks (Mayes-Davies, the truth
rig's crack law) of depth 2.5 / 5 / 7.5 % of the diameter in elements 2, 4, 6 and 8 (``--per-element`` sweeps
each). ``python -m bench.sideband_power [--variants truth,dampers] [--healthy 100] [--per-element 5]``.
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
from bench.truth_variants import VARIANTS, nominal, truth_variant
from rotorcheck import workflow
from rotorcheck.config import RigConfig
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.variability import with_benign
from rotorcheck.workflow.detectors import DetectorSettings
from rotorcheck.workflow.detectors.sideband import SidebandDetector

ORDERS = (-2, -1, 1, 2)
DEPTHS = (0.025, 0.05, 0.075)
ELEMENTS = (2, 4, 6, 8)
SPEED = 1000.0


def called(truth: RigConfig, nom: RigConfig, seed: int, fault: str | None) -> tuple[bool, float]:
    """One drifted sweep: (called damage, T / threshold)."""
    values = _inside(np.random.default_rng([seed, 17]))
    cfg, d_rpm, _, _ = with_benign(truth, values)  # a gain scales the sidebands and their noise alike
    st = dataclasses.replace(step_settings(cfg), sideband_orders=ORDERS)
    angle = float(np.random.default_rng([seed, 99]).uniform(0.0, 2.0 * np.pi))
    sw = simulate_rig(cfg, GRID, SPEED + d_rpm, fault=fault, seed=seed, settings=st, shaft_angle_rad=angle)
    det = SidebandDetector(DetectorSettings()).detect(workflow.measured_run(sw, nom))
    assert det.statistic is not None and det.threshold is not None
    return det.verdict.verdict == "damage", det.statistic / det.threshold


def run_variant(name: str, healthy: int, per_element: int, log: Any) -> dict[str, Any]:
    nom = nominal()
    truth = truth_variant(name, nom)
    out: dict[str, Any] = {}
    t = time.perf_counter()
    fa = [called(truth, nom, 7_000_000 + k, None)[0] for k in range(healthy)]
    out["healthy"] = (sum(fa), healthy)
    log(f"{name}: healthy {sum(fa)}/{healthy} called damage ({time.perf_counter() - t:.0f} s)")
    for depth in DEPTHS:
        hits = n = 0
        per: dict[int, int] = {}
        for el in ELEMENTS:
            faults = dict(truth.faults)
            faults["loc"] = truth.faults["breathing_crack"].model_copy(  # type: ignore[union-attr]
                update={"element": el, "depth": depth})
            cfg = truth.model_copy(update={"faults": faults})
            h = sum(called(cfg, nom, 7_100_000 + int(depth * 1e4) * 100 + el * 10 + k, "loc")[0]
                    for k in range(per_element))
            per[el] = h
            hits += h
            n += per_element
        out[depth] = (hits, n, per)
        log(f"{name}: depth {100 * depth:g} %: {hits}/{n} {per} ({time.perf_counter() - t:.0f} s)")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--healthy", type=int, default=100)
    ap.add_argument("--per-element", type=int, default=5)
    args = ap.parse_args(argv)

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    names = [v.strip() for v in args.variants.split(",") if v.strip()]
    res = {v: run_variant(v, args.healthy, args.per_element, log) for v in names}
    print("| | " + " | ".join(names) + " |")
    print("|---|" + "---:|" * len(names))
    print("| healthy, drift inside the ranges: called damage | " + " | ".join(
        f"{res[v]['healthy'][0]} / {res[v]['healthy'][1]}" for v in names) + " |")
    for depth in DEPTHS:
        print(f"| breathing {100 * depth:g} % depth, elements {', '.join(map(str, ELEMENTS))}: detected | "
              + " | ".join(f"{res[v][depth][0]} / {res[v][depth][1]}" for v in names) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
