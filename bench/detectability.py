"""Detectability predictions (issue 19) against Monte Carlo of the actual detector, and their cost.

Part M: for breathing cracks in elements 3, 4 and 6 at 1000 rpm, at 1x and 4x the truth rig's noise,
with noise only and with the bundled benign ranges, the predicted smallest depth
(:func:`rotorcheck.detectability.detectability` on the NOMINAL model, stated noise) against the
detector itself: fresh simulated sweeps of the TRUTH rig (``configs/crack_rig_truth.yaml``, the
samples' 262-point grid, 64 periods, random start angle, shaft harmonics removed), one healthy
baseline sweep and one cracked sweep per trial, the product's joint test (1 % false alarms). Depths
on a grid of ratio 1.25 around the prediction (k = -2 .. 2 steps); the smallest grid depth detected in
>= 90 % of the trials is compared with the prediction: within one step passes.

Part S: one probe against x and y probes at stations 6 and 2, per element (predictions).

Part T: the whole table of the bundled rig (9 elements, both crack kinds, both cases) from the rig's
truth noise, its time as a ratio to one ``detect`` run on the bundled breathing-crack sample in the
same process (issue 19: <= 30 s on this 2-core machine).

``python -m bench.detectability [--trials 10] [--part M|T|S] [--quick]``
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import numpy as np

from bench.detection_limit import _baseline, _called, _configs, sweep_run
from bench.detection_power import GRID
from rotorcheck import workflow
from rotorcheck.config import RigConfig
from rotorcheck.detectability import detectability, stated_noise_variance
from rotorcheck.nominal import primary_pair
from rotorcheck.signatures import io_frf

STEP = 1.25


def _predicted(nominal: RigConfig, noise: float, benign: bool, elements: tuple[int, ...]) -> dict[int, float | None]:
    cfg = nominal if benign else nominal.model_copy(update={"variability": []})
    v = stated_noise_variance(2e-7 * noise, 64, 64, 1.0)
    var = np.full(GRID.size, v)
    th = io_frf(cfg, GRID, 1000.0)
    bm = workflow.benign_model(cfg, GRID, 1000.0, th, workflow.KAPPA_NOMINAL)
    det = detectability(cfg, GRID, 1000.0, var, var, [primary_pair(cfg)], th, 0.01, bm, elements)
    return {e.element: e.breathing_depth_min for e in det.elements if e.element in elements}


def _power(truth: RigConfig, nominal: RigConfig, element: int, depth: float, noise: float, benign: bool,
           trials: int) -> float:
    t = truth.model_copy(update={"faults": {**truth.faults, "breathing_crack": truth.faults["breathing_crack"]
                                            .model_copy(update={"element": element})}})
    cfg = workflow.rig_with_crack_depth(t, None, "breathing_crack", depth)
    nom = nominal if benign else nominal.model_copy(update={"variability": []})
    hits = 0
    for k in range(trials):
        s0 = 30_000_000 + 1_000_000 * element + 100_000 * int(noise) + int(depth * 1e4) * 10 + 2 * k
        base = _baseline([sweep_run(truth, nom, 1000.0, noise, s0)], nom)
        hits += bool(_called(nom, base, sweep_run(cfg, nom, 1000.0, noise, s0 + 1, "breathing_crack"), 1000.0).damage)
    return hits / trials


def part_m(trials: int, log: Any, quick: bool) -> list[str]:
    truth, nominal = _configs()
    lines = ["| element | noise | case | predicted depth % | Monte Carlo power at k = -2..2 steps (ratio 1.25) | "
             "smallest >= 90 % | within one step |", "|---:|---:|---|---:|---|---:|---|"]
    elements = (4,) if quick else (3, 4, 6)
    for noise in ((1.0,) if quick else (1.0, 4.0)):
        for benign in (False, True):
            pred = _predicted(nominal, noise, benign, elements)
            for e in elements:
                d0 = pred[e]
                if d0 is None:
                    lines.append(f"| {e} | {noise:g}x | {'benign' if benign else 'noise only'} | none up to 50 % | "
                                 "- | - | - |")
                    continue
                powers: list[str] = []
                found = None
                for k in (-2, -1, 0, 1, 2):
                    d = d0 * STEP**k
                    if d > 0.5:
                        powers.append(f"k={k:+d}: over 50 %")
                        break
                    p = _power(truth, nominal, e, d, noise, benign, trials)
                    powers.append(f"{100 * d:.3g} %: {p:.2f}")
                    log(f"M e{e} {noise:g}x {'benign' if benign else 'noise'} depth {d:.4f}: power {p:.2f}")
                    if p >= 0.9:
                        found = k
                        break
                ok = found is not None and abs(found) <= 1
                best = "none" if found is None else f"{100 * d0 * STEP**found:.3g} % (k={found:+d})"
                lines.append(f"| {e} | {noise:g}x | {'benign' if benign else 'noise only'} | {100 * d0:.3g} | "
                             f"{'; '.join(powers)} | {best} | {'yes' if ok else 'NO'} |")
    return lines


def part_t(log: Any) -> list[str]:
    from rotorcheck.config import load_config
    from rotorcheck.resources import configs_dir, samples_dir

    nominal = load_config(configs_dir() / "crack_rig.yaml")
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    sample = samples_dir() / "crack_rig" / "breathing_crack_1000rpm.h5"
    healthy = samples_dir() / "crack_rig" / "healthy_1000rpm.h5"
    h = workflow.load_run(healthy, nominal)
    val = workflow.validate(nominal, [h], workflow.fit_noise(h))
    new = workflow.load_run(sample, nominal)
    t0 = time.perf_counter()
    workflow.detect(nominal, val.baseline, new)
    t_detect = time.perf_counter() - t0
    m = truth.measurement
    v = stated_noise_variance(m.output_noise_std, m.n_periods, m.samples_per_period, m.force_amplitude)
    var = np.full(GRID.size, v)
    t0 = time.perf_counter()
    th = io_frf(nominal, GRID, 1000.0)
    bm = workflow.benign_model(nominal, GRID, 1000.0, th, workflow.KAPPA_NOMINAL)
    det = detectability(nominal, GRID, 1000.0, var, var, [primary_pair(nominal)], th, 0.01, bm)
    t_table = time.perf_counter() - t0
    log(det.summary())
    return ["| task | seconds | ratio to one detect |", "|---|---:|---:|",
            f"| one `detect` (bundled breathing-crack sample, joint test and certificates) | {t_detect:.1f} | 1 |",
            f"| whole detectability table, 9 elements, both kinds, both cases (2 processes) | {t_table:.1f} | "
            f"{t_table / t_detect:.2f} |"]


def part_s(log: Any) -> list[str]:
    """One probe (6x) against x and y probes at stations 6 and 2 (force 8x), per element, predicted with
    the re-solved benign model, 1x noise, 1000 rpm."""
    from rotorcheck.config import Port, load_config
    from rotorcheck.nominal import ChannelPair
    from rotorcheck.resources import configs_dir
    from rotorcheck.signatures import stacked

    nominal = load_config(configs_dir() / "crack_rig.yaml")
    act = Port(station=8, direction="x")
    sets = {"one probe 6x": [Port(station=6, direction="x")],
            "x/y at 6 and 2": [Port(station=6, direction=d) for d in "xy"] + [Port(station=2, direction=d)
                                                                            for d in "xy"]}
    v = stated_noise_variance(2e-7, 64, 64, 1.0)
    rows: dict[str, Any] = {}
    for name, probes in sets.items():
        pairs = [ChannelPair(o, act, "") for o in probes]
        multi = pairs if len(pairs) > 1 else None
        th = io_frf(nominal, GRID, 1000.0, multi)
        bm = workflow.benign_model(nominal, GRID, 1000.0, stacked(th), workflow.KAPPA_NOMINAL, 0.0, None, multi)
        var = np.full(th.shape, v)
        t0 = time.perf_counter()
        rows[name] = detectability(nominal, GRID, 1000.0, var, var, pairs, th, 0.01, bm)
        log(f"S {name}: {time.perf_counter() - t0:.1f} s\n{rows[name].summary()}")

    def pct(x: float | None) -> str:
        return "none" if x is None else f"{100 * x:.3g}"

    lines = ["| element | breathing depth %, one probe: noise only / benign | x/y at 6 and 2: noise only / benign |",
             "|---:|---:|---:|"]
    one, four = rows["one probe 6x"], rows["x/y at 6 and 2"]
    for a, b in zip(one.elements, four.elements):
        lines.append(f"| {a.element} | {pct(a.breathing_depth_min_noise_only)} / {pct(a.breathing_depth_min)} | "
                     f"{pct(b.breathing_depth_min_noise_only)} / {pct(b.breathing_depth_min)} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--part", choices=("M", "T", "S"), default=None)
    ap.add_argument("--quick", action="store_true", help="element 4, 1x only")
    a = ap.parse_args(argv)

    def log(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    out: list[str] = []
    if a.part in (None, "T"):
        out += ["## Part T: cost", "", *part_t(log), ""]
    if a.part in (None, "S"):
        out += ["## Part S: one probe against x and y probes at two stations", "", *part_s(log), ""]
    if a.part in (None, "M"):
        out += ["## Part M: predictions against Monte Carlo of the detector", "", *part_m(a.trials, log, a.quick)]
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
