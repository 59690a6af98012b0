"""Does the evidence grow with the loss? Issue 29's "a statistic grows with the severity (within noise) for a
fixed element", per truth variant (:mod:`bench.truth_variants`).

For each variant: one healthy baseline sweep of the truth at its nominal state (``fit-noise``, ``validate --enclose
measured``), then open cracks in element 4 at 0 rpm with losses 1-40 %, ``--seeds`` noise draws each, with drift
inside the declared ranges (the same draw for every loss of one seed, so that only the loss changes along a row) and
without. Per loss: the sweep's verdicts, the median of -log10 of the sweep's p-value (the verdict's rule: GLR and
H0's goodness of fit, Bonferroni), of the GLR statistic T and of H0's chi2 per dof. One probe (the rig's own pair)
or ``--xy`` (forces x and y at station 8, x and y probes at stations 6 and 2). Seeded; prints Markdown tables.

``python -m bench.severity_series [--seeds 3] [--variants truth,dampers] [--losses 0.01,0.02,0.05,0.1,0.2,0.4]
[--xy]``
"""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

import numpy as np

from bench.detection_limit import _inside, sweep_run
from bench.detection_power import _open_crack
from bench.independent_physics import log
from bench.truth_variants import VARIANTS, nominal, truth_variant
from bench.xy_detection import xy_run
from rotorcheck import workflow
from rotorcheck.config import RigConfig
from rotorcheck.workflow.detectors.base import DetectorSettings
from rotorcheck.workflow.detectors.registry import make_detector

LOSSES = (0.01, 0.02, 0.05, 0.1, 0.2, 0.4)


def _run(truth: RigConfig, nom: RigConfig, seed: int, xy: bool, fault: str | None,
         benign: dict[str, float] | None) -> workflow.MeasuredRun:
    if xy:
        return xy_run(truth, nom, seed, fault, benign=benign)
    return sweep_run(truth, nom, 0.0, 1.0, seed, fault, benign=benign)


def series(name: str, seeds: int, losses: tuple[float, ...], xy: bool, drift: bool) -> dict[str, str]:
    """``{loss label: 'called k/n; -log10 p; T; chi2/dof'}`` (medians over the seeds) for one variant."""
    nom = nominal()
    truth = truth_variant(name, nom)
    h = _run(truth, nom, 51_000_000, xy, None, None)
    base = workflow.validate(nom, [h], workflow.fit_noise(h), enclose="measured").baseline
    detector = make_detector(nom, base, None, DetectorSettings(verdict_only=True))
    draws = [_inside(np.random.default_rng([52, s])) if drift else None for s in range(seeds)]
    out: dict[str, str] = {}
    for loss in (0.0, *losses):
        rows: list[tuple[bool, float, float, float]] = []
        for s in range(seeds):
            cfg = _open_crack(truth, 1.0 - loss) if loss > 0 else truth
            run = _run(cfg, nom, 53_000_000 + 1000 * s + int(loss * 1e4), xy, "open_crack" if loss > 0 else None,
                       draws[s])
            found = detector.detect(run)
            j = found.joint
            assert j is not None
            rows.append((found.verdict.verdict == "damage", -math.log10(max(j.p_value, 1e-300)), j.statistic,
                         j.chi2_h0 / max(j.fit_dof, 1)))
        a = np.array(rows, dtype=float)
        label = "healthy" if loss == 0 else f"{100 * loss:g} %"
        out[label] = (f"{int(a[:, 0].sum())}/{seeds}; {np.median(a[:, 1]):.3g}; {np.median(a[:, 2]):.3g}; "
                      f"{np.median(a[:, 3]):.3g}")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--losses", default=",".join(f"{x:g}" for x in LOSSES))
    ap.add_argument("--xy", action="store_true")
    a = ap.parse_args(argv)
    losses = tuple(float(x) for x in a.losses.split(","))
    names = a.variants.split(",")
    for drift in (False, True):
        cols: dict[str, dict[str, Any]] = {}
        for n in names:
            t0 = time.perf_counter()
            cols[n] = series(n, a.seeds, losses, a.xy, drift)
            log(f"{n} drift={drift}: {time.perf_counter() - t0:.0f} s")
        print(f"\n### {'x/y probes at two stations' if a.xy else 'one probe'}, 0 rpm, open crack element 4, "
              f"{'drift inside the ranges' if drift else 'no drift'}: called / median -log10 p / median T / "
              "median chi2_H0 per dof\n")
        print("| loss | " + " | ".join(names) + " |")
        print("|---|" + "---:|" * len(names))
        for r in next(iter(cols.values())):
            print(f"| {r} | " + " | ".join(cols[n][r] for n in names) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
