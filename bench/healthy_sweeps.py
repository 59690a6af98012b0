"""Power against the number of healthy sweeps (issue 29), per truth variant (:mod:`bench.truth_variants`).

For K = 1, 3, 10 (and more if asked) healthy training sweeps of the truth drifted uniformly inside the declared
ranges, the product's baseline (``validate --enclose measured``; ``--learn-drift`` from 3 sweeps on) and its joint
test at 1 % false alarms on new sweeps, drifted inside the ranges as well: healthy ones (false alarms) and open
cracks in element 4 (stiffness loss) at 0 rpm. Also the coverage of the fitted Young's modulus's 95 % interval on
the healthy sweeps. Seeded; prints a Markdown table, one row per variant and K.

``python -m bench.healthy_sweeps [--counts 1,3,10] [--healthy 20 --cracks 10] [--variants truth,dampers]
[--losses 0.02,0.05] [--no-learn-drift] [--around-baseline] [--speed 1000] [--one-random]`` (``--no-learn-drift``:
every K with the ranges about the kept sweep; ``--one-random``: K = 1 at a random state with the ranges doubled;
``--around-baseline``: new sweeps drift around the baseline's state, the ranges read as the change between two
sweeps; ``--speed``: every sweep at that speed, default 0 rpm)
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from bench.detection_limit import _inside, sweep_run
from bench.detection_power import _open_crack
from bench.truth_variants import VARIANTS, nominal, truth_variant
from rotorcheck import workflow
from rotorcheck.variability import pair_ranges


def run(name: str, count: int, n_healthy: int, n_cracks: int, losses: tuple[float, ...],
        learn: bool = True, around_baseline: bool = False, speed: float = 0.0, one_random: bool = False
        ) -> dict[str, str]:
    """``{column: value}`` for one variant and training-set size at ``speed`` rpm (0: at rest; at another speed
    the cracks are open cracks too, and the seeds differ from 0 rpm's); ``learn``: ``--learn-drift`` from 3
    sweeps on (else the default ``validate`` of every sweep); ``around_baseline``: the new sweeps drift inside
    the ranges around the baseline's own state (the ranges read as the change between two sweeps), else around
    the nominal state; ``one_random``: one training sweep at a random state inside the ranges too (not the nominal
    one), the product's rig then stating the change between two states (``variability.pair_ranges``: where the one
    sweep sits is unknown)."""
    nom = nominal()
    truth = truth_variant(name, nom)
    rng = np.random.default_rng([count, 2901])
    train_values = [_inside(rng) if count > 1 or one_random else {} for _ in range(count)]
    if count == 1 and one_random:
        nom = pair_ranges(nom, speed)
    if speed != 0.0:  # validate takes the training sweeps of one speed (within its tolerance): held at the nominal
        train_values = [{n: v for n, v in values.items() if n != "speed"} for values in train_values]
    shift = 10_000 * int(speed)  # 0 at rest: the seeds of the 0 rpm figures
    train = [sweep_run(truth, nom, speed, 1.0, 35_000_000 + shift + 100 * count + k, benign=v)
             for k, v in enumerate(train_values)]
    outcome = workflow.validate(nom, train, workflow.fit_noise(train[0]), enclose="measured",
                                learn_drift=learn and count >= 3)
    base = outcome.baseline
    # the healthy FRF is one sweep's (drift between them) or their mean: the truth's E relative to its state
    ref = outcome.healthy_run
    state = (train_values[ref] if ref is not None else
             {n: float(np.mean([v.get(n, 0.0) for v in train_values])) for n in train_values[0]})
    e_mean = float(state.get("youngs_modulus", 0.0))
    test_rng = np.random.default_rng([29, 0])

    def draw() -> dict[str, float]:
        d = _inside(test_rng)
        return {n: v + float(state.get(n, 0.0)) for n, v in d.items()} if around_baseline else d

    alarms = covered = 0
    for i in range(n_healthy):
        values = draw()
        out = workflow.detect(nom, base, sweep_run(truth, nom, speed, 1.0, 36_000_000 + shift + i, benign=values))
        alarms += out.verdict.verdict == "damage"
        j = out.joint
        k = j.theta_names.index("youngs_modulus")
        e_true = (1.0 + values["youngs_modulus"]) / (1.0 + e_mean) - 1.0
        half = 1.96 * float(j.theta_se[k])
        covered += bool(abs(float(j.theta[k]) - e_true) <= half)
    row = {"false alarms": f"{alarms}/{n_healthy}", "E interval covers": f"{covered}/{n_healthy}"}
    for loss in losses:
        cfg = _open_crack(truth, 1.0 - loss)
        found = sum(workflow.detect(nom, base, sweep_run(cfg, nom, speed, 1.0,
                                                         37_000_000 + shift + int(loss * 1e4) * 100 + i,
                                                         "open_crack", benign=draw())).verdict.verdict
                    == "damage" for i in range(n_cracks))
        row[f"{100 * loss:g} % loss found"] = f"{found}/{n_cracks}"
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--counts", default="1,3,10")
    ap.add_argument("--healthy", type=int, default=20)
    ap.add_argument("--cracks", type=int, default=10)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--losses", default="0.02,0.05")
    ap.add_argument("--no-learn-drift", action="store_true", help="every K through the default validate")
    ap.add_argument("--around-baseline", action="store_true", help="new sweeps drift around the baseline's state")
    ap.add_argument("--speed", type=float, default=0.0, help="rpm of every sweep (default 0: at rest)")
    ap.add_argument("--one-random", action="store_true", help="K = 1: the sweep at a random state, the ranges doubled")
    a = ap.parse_args(argv)
    losses = tuple(float(x) for x in a.losses.split(","))
    rows = []
    for name in a.variants.split(","):
        for count in (int(c) for c in a.counts.split(",")):
            t = time.perf_counter()
            r = run(name, count, a.healthy, a.cracks, losses, not a.no_learn_drift, a.around_baseline, a.speed,
                    a.one_random)
            print(f"{name} K={count}: {r} ({time.perf_counter() - t:.0f} s)", file=sys.stderr, flush=True)
            rows.append((name, count, r))
    cols = list(rows[0][2])
    print("| variant | healthy sweeps | " + " | ".join(cols) + " |")
    print("|---|---:|" + "---:|" * len(cols))
    for name, count, r in rows:
        print(f"| {name} | {count} | " + " | ".join(r[c] for c in cols) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
