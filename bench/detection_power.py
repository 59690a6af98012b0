"""Detection power and false alarms of rotorcheck's default against model-free tests (seeded).

Every trial simulates a fresh healthy baseline sweep and a fresh new sweep of the truth rig
(``configs/crack_rig_truth.yaml``, the samples' 262-point grid, 64 periods), both with a random
shaft angle at the start (a free-running analyser), and asks four detectors for a verdict:

- ``default``: rotorcheck's default (``validate --enclose measured`` + ``detect``, 99 % family-wise;
  shaft harmonics removed from the stored per-period phasors);
- ``system``: the previous default (``--enclose system``: against the nominal model with gamma_h,
  pooled uniform V, the old verdict rule);
- ``model-free``: the certified comparison of the two sweeps' averaged FRFs within both pooled
  noise bounds, ``|T_new - T_h| > V_new/|W_new| + V_h/|W_h|`` at any point (V from
  ``fit-noise``'s default, 99 % family-wise);
- ``chi2``: a per-point chi-square test on the stored variances, ``|d|^2/(a + b) > -ln(miss)``,
  Sidak over the points at 1 % family-wise (the files' plain means and variances).

Cells: healthy repeats at 0, 1000 and 2000 rpm (false-alarm rate), breathing cracks at 1000 rpm
(depth as a fraction of the diameter) and open cracks at 0 rpm (modulus factor of element 4), each
at 1x, 4x and 16x the rig's noise. ``python -m bench.detection_power [--seeds 10 --healthy 30]``;
prints a Markdown table (rate = sweeps called damage / sweeps).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from rotorcheck import workflow
from rotorcheck.config import RigConfig, load_config
from rotorcheck.resources import configs_dir
from rotorcheck.robust.noise import point_miss
from rotorcheck.sim.rig_sim import simulate_rig, step_settings

GRID = np.linspace(30.0, 600.0, 262)
NOISE = (1.0, 4.0, 16.0)
DEPTHS = (0.01, 0.015, 0.025, 0.035, 0.05, 0.075, 0.10, 0.20, 0.30, 0.50)
MODULUS = (0.9995, 0.999, 0.998, 0.995, 0.99, 0.98, 0.95, 0.90, 0.80, 0.46)
DETECTORS = ("default", "system", "model-free", "chi2")


def _truth() -> tuple[RigConfig, RigConfig]:
    return load_config(configs_dir() / "crack_rig_truth.yaml"), load_config(configs_dir() / "crack_rig.yaml")


def _open_crack(cfg: RigConfig, factor: float) -> RigConfig:
    faults = dict(cfg.faults)
    faults["open_crack"] = faults["open_crack"].model_copy(update={"modulus_factor": factor})
    return cfg.model_copy(update={"faults": faults})


def _sweep(cfg: RigConfig, speed: float, fault: str | None, noise: float, seed: int) -> Any:
    st = step_settings(cfg, keep_periods=True)
    st = dataclasses.replace(st, output_noise_std=st.output_noise_std * noise)
    angle = float(np.random.default_rng([seed, 99]).uniform(0.0, 2.0 * np.pi))
    return simulate_rig(cfg, GRID, speed, fault=fault, seed=seed, settings=st, shaft_angle_rad=angle)


def _raw(sweep: Any, nominal: RigConfig) -> Any:
    return workflow.measured_run(sweep, nominal, shaft_orders=0)


def verdicts(nominal: RigConfig, healthy: Any, new: Any) -> dict[str, bool]:
    """``{detector: called damage}`` for one baseline sweep and one new sweep."""
    out: dict[str, bool] = {}
    h, n = workflow.measured_run(healthy, nominal), workflow.measured_run(new, nominal)
    nb = workflow.fit_noise(h)
    val = workflow.validate(nominal, [h], nb, enclose="measured")
    out["default"] = workflow.detect(nominal, val.baseline, n).verdict.verdict == "damage"
    hr, nr = _raw(healthy, nominal), _raw(new, nominal)
    nb_r = workflow.fit_noise(hr)
    val_s = workflow.validate(nominal, [hr], nb_r, enclose="system")
    out["system"] = workflow.detect(nominal, val_s.baseline, nr).verdict.verdict == "damage"
    v_new = workflow.fit_noise(nr).value_m
    d = np.abs(nr.frf - hr.frf)
    out["model-free"] = bool(np.any(d > v_new / np.abs(nr.W) + nb_r.value_m / np.abs(hr.W)))
    s = nr.output_var / np.abs(nr.W) ** 2 + hr.output_var / np.abs(hr.W) ** 2
    thr = -np.log(point_miss(0.99, d.size))
    out["chi2"] = bool(np.any(d**2 / s > thr))
    return out


def _cell(trials: Callable[[int], tuple[Any, Any]], n: int, nominal: RigConfig) -> dict[str, float]:
    hits = dict.fromkeys(DETECTORS, 0)
    for k in range(n):
        h, new = trials(k)
        for name, hit in verdicts(nominal, h, new).items():
            hits[name] += int(hit)
    return {name: hits[name] / n for name in DETECTORS}


def run(seeds: int = 10, healthy: int = 30, quick: bool = False) -> dict[str, Any]:
    truth, nominal = _truth()
    rows: list[tuple[str, str, float, dict[str, float]]] = []
    noise_levels = NOISE[:1] if quick else NOISE
    for noise in noise_levels:
        for speed in (0.0, 1000.0, 2000.0):
            def pair(k: int, sp: float = speed, nz: float = noise) -> tuple[Any, Any]:
                base = 10_000 + int(sp) * 10 + int(nz) * 1_000_000 + 2 * k
                return _sweep(truth, sp, None, nz, base), _sweep(truth, sp, None, nz, base + 1)
            rows.append((f"healthy {speed:g} rpm", "false alarms", noise, _cell(pair, healthy, nominal)))
            print(rows[-1], file=sys.stderr, flush=True)
        for depth in DEPTHS[: 3 if quick else None]:
            cfg = workflow.rig_with_crack_depth(truth, None, "breathing_crack", depth)

            def cpair(k: int, c: RigConfig = cfg, nz: float = noise, dp: float = depth) -> tuple[Any, Any]:
                base = 20_000 + int(dp * 1000) * 100 + int(nz) * 1_000_000 + 2 * k
                return _sweep(truth, 1000.0, None, nz, base), _sweep(c, 1000.0, "breathing_crack", nz, base + 1)
            rows.append((f"breathing {depth:.1%} depth", "detection", noise, _cell(cpair, seeds, nominal)))
            print(rows[-1], file=sys.stderr, flush=True)
        for mf in MODULUS[: 3 if quick else None]:
            cfg = _open_crack(truth, mf)

            def opair(k: int, c: RigConfig = cfg, nz: float = noise, m: float = mf) -> tuple[Any, Any]:
                base = 30_000 + round(m * 1000) * 100 + int(nz) * 1_000_000 + 2 * k
                return _sweep(truth, 0.0, None, nz, base), _sweep(c, 0.0, "open_crack", nz, base + 1)
            rows.append((f"open crack E x {mf:g}", "detection", noise, _cell(opair, seeds, nominal)))
            print(rows[-1], file=sys.stderr, flush=True)
    return {"rows": rows, "seeds": seeds, "healthy": healthy}


def table(result: dict[str, Any]) -> str:
    """Markdown: one row per case, one column per detector and noise level."""
    rows = result["rows"]
    cases: dict[str, dict[float, dict[str, float]]] = {}
    kinds: dict[str, str] = {}
    for case, kind, noise, rates in rows:
        cases.setdefault(case, {})[noise] = rates
        kinds[case] = kind
    noises = sorted({r[2] for r in rows})
    head = "| case | rate | " + " | ".join(f"{d} {n:g}x" for n in noises for d in DETECTORS) + " |"
    lines = [head, "|---|---|" + "---:|" * (len(noises) * len(DETECTORS))]
    for case, by_noise in cases.items():
        cells = []
        for n in noises:
            r = by_noise.get(n, {})
            cells += [f"{r[d]:.2f}" if d in r else "" for d in DETECTORS]
        lines.append(f"| {case} | {kinds[case]} | " + " | ".join(cells) + " |")
    lines += ["", "smallest severity detected in >= 90 % of the sweeps (and every larger one):", ""]
    lines.append("| crack | " + " | ".join(f"{d} {n:g}x" for n in noises for d in DETECTORS) + " |")
    lines.append("|---|" + "---:|" * (len(noises) * len(DETECTORS)))
    for prefix, label, key in (("breathing", "breathing, depth of diameter", _depth),
                               ("open crack", "open crack, stiffness loss 1 - E factor", _loss)):
        ordered = sorted((c for c in cases if c.startswith(prefix)), key=key)
        cells = []
        for n in noises:
            for d in DETECTORS:
                best = "none"
                for c in reversed(ordered):  # from the largest severity down, while detected
                    if cases[c].get(n, {}).get(d, 0.0) < 0.9:
                        break
                    best = f"{key(c):.3g} %"
                cells.append(best)
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _depth(case: str) -> float:
    return float(case.split()[1].rstrip("%"))


def _loss(case: str) -> float:
    return 100.0 * (1.0 - float(case.split()[-1]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=10, help="sweeps per crack cell")
    ap.add_argument("--healthy", type=int, default=30, help="healthy repeats per speed and noise level")
    ap.add_argument("--quick", action="store_true", help="1x noise, three severities (a smoke run)")
    args = ap.parse_args(argv)
    t = time.perf_counter()
    result = run(args.seeds, args.healthy, args.quick)
    print(table(result))
    print(f"\n({time.perf_counter() - t:.0f} s; {args.seeds} sweeps per crack cell, {args.healthy} healthy "
          f"repeats per speed and noise level, each against its own fresh baseline)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
