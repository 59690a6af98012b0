"""Detection on physics the model does not share (issue 29), per truth variant (:mod:`bench.truth_variants`).

For each variant: one healthy baseline sweep of the truth at its nominal state (the product's default path:
``fit-noise``, ``validate --enclose measured``, ``detect``, 1 % false alarms), then new sweeps with the truth
drifted uniformly inside the ranges the rig file declares (E +-2 %, each bearing +-3 %, sensor gain +-1 %,
speed +-20 rpm): healthy (false alarms) at 0 and 1000 rpm, open cracks in element 4 (stiffness loss) at 0 rpm
and a breathing crack at 1000 rpm. Seeded; prints a Markdown table, one column per variant.

``python -m bench.independent_physics [--healthy 20 --cracks 10] [--variants truth,dampers] [--losses 0.05,0.1,0.2]
[--depths 0.2,0.3,0.4]``
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import numpy as np

from bench.detection_limit import _inside, sweep_run
from bench.detection_power import _open_crack
from bench.truth_variants import VARIANTS, nominal, truth_variant
from rotorcheck import workflow
from rotorcheck.workflow.detectors.base import DetectorSettings
from rotorcheck.workflow.detectors.registry import make_detector

LOSSES = (0.02, 0.05)
DEPTHS = (0.20,)


def _baseline(truth: Any, nom: Any, speed: float, seed: int) -> Any:
    h = sweep_run(truth, nom, speed, 1.0, seed)
    return workflow.validate(nom, [h], workflow.fit_noise(h), enclose="measured").baseline


def _called(nom: Any, base: Any, run: Any) -> bool:
    """The verdict of the product's default detector on ``run`` (the verdict alone: what follows it, the
    certificates and the diagnosis, does not change it)."""
    detector = make_detector(nom, base, None, DetectorSettings(verdict_only=True))
    return detector.detect(run).verdict.verdict == "damage"


def run_variant(name: str, n_healthy: int, n_cracks: int, log: Any, losses: tuple[float, ...] = LOSSES,
                depths: tuple[float, ...] = DEPTHS) -> dict[str, str]:
    """``{row label: 'k/n'}`` for one variant (open-crack ``losses`` at 0 rpm, breathing ``depths`` at 1000 rpm)."""
    nom = nominal()
    truth = truth_variant(name, nom)
    out: dict[str, str] = {}
    for speed in (0.0, 1000.0):
        t0 = time.perf_counter()
        base = _baseline(truth, nom, speed, 31_000_000 + int(speed))
        rng = np.random.default_rng([int(speed), 29])
        k = sum(_called(nom, base, sweep_run(truth, nom, speed, 1.0, 32_000_000 + int(speed) * 1000 + i,
                                             benign=_inside(rng))) for i in range(n_healthy))
        out[f"false alarms, healthy drifted inside the ranges, {speed:g} rpm"] = f"{k}/{n_healthy}"
        log(f"{name} {speed:g} rpm healthy: {k}/{n_healthy} ({time.perf_counter() - t0:.0f} s)")
        if speed == 0.0:
            for loss in losses:
                cfg = _open_crack(truth, 1.0 - loss)
                k = sum(_called(nom, base, sweep_run(cfg, nom, 0.0, 1.0, 33_000_000 + int(loss * 1e4) * 100 + i,
                                                     "open_crack", benign=_inside(rng))) for i in range(n_cracks))
                out[f"open crack element 4, {100 * loss:g} % loss, drift, 0 rpm: detected"] = f"{k}/{n_cracks}"
                log(f"{name} open {loss}: {k}/{n_cracks}")
        else:
            for depth in depths:
                cfg = workflow.rig_with_crack_depth(truth, None, "breathing_crack", depth)
                k = sum(_called(nom, base, sweep_run(cfg, nom, 1000.0, 1.0, 34_000_000 + int(depth * 1e3) * 100 + i,
                                                     "breathing_crack", benign=_inside(rng)))
                        for i in range(n_cracks))
                out[f"breathing crack {100 * depth:g} % depth, drift, 1000 rpm: detected"] = f"{k}/{n_cracks}"
                log(f"{name} breathing {depth}: {k}/{n_cracks}")
    return out


def arguments(doc: str, losses: tuple[float, ...]) -> argparse.ArgumentParser:
    """The drift benches' options: sweeps per cell (healthy, cracked), truth variants, open-crack losses."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--healthy", type=int, default=20)
    ap.add_argument("--cracks", type=int, default=10)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--losses", default=",".join(f"{x:g}" for x in losses), help="open-crack losses, fractions")
    return ap


def main(argv: list[str] | None = None) -> int:
    ap = arguments(__doc__ or "", LOSSES)
    ap.add_argument("--depths", default=",".join(f"{x:g}" for x in DEPTHS), help="breathing depths, of the diameter")
    a = ap.parse_args(argv)
    losses = tuple(float(x) for x in a.losses.split(","))
    depths = tuple(float(x) for x in a.depths.split(","))
    names = a.variants.split(",")
    print_columns("case", {n: run_variant(n, a.healthy, a.cracks, log, losses, depths) for n in names})
    return 0


def log(msg: str) -> None:
    """A progress line on stderr."""
    print(msg, file=sys.stderr, flush=True)


def print_columns(head: str, cols: dict[str, dict[str, str]]) -> None:
    """A Markdown table on stdout: one row per label of the first column's dict, one column per key of ``cols``."""
    names = list(cols)
    print(f"| {head} | " + " | ".join(names) + " |")
    print("|---|" + "---:|" * len(names))
    for r in next(iter(cols.values())):
        print(f"| {r} | " + " | ".join(cols[n][r] for n in names) + " |")


if __name__ == "__main__":
    raise SystemExit(main())
