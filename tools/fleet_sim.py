"""A simulated fleet for ``rotorcheck fleet`` (issue 15), seeded: ``python -m tools.fleet_sim OUTDIR
--machines 20 --sweeps 10 --seed 0``.

Every machine is the crack rig (``configs/crack_rig.yaml`` as its rig file) played by the truth rig
(``configs/crack_rig_truth.yaml``) at standstill, on the samples' 30-600 Hz grid (``--points``, default 262), one
sweep every ``--step-days`` (default 7) at 02:00 UTC, named by its time (``sweeps/2026-03-01T02-00.h5``).
Each machine's baseline is made as a user would: ``validate --enclose measured`` (the library's
:func:`rotorcheck.workflow.validate`) on its first two healthy sweeps (``healthy/``), noise fitted on the
first.

Machines (``machine-NN``):

- two with an open crack in element 4 that grows linearly in time from an onset between two sweeps
  (stiffness loss of the element 0 -> 12 % and 0 -> 10 % by the last sweep);
- one whose motor-end bearing stiffness drifts linearly from 0 to -2.5 % (inside the rig's +-3 % range:
  benign);
- the rest healthy. Every sweep but the drifting machine's has benign scatter (Young's modulus +-0.2 %,
  each bearing's stiffness +-1 %, uniform: :data:`SCATTER`).

``truth.json`` holds, per machine and sweep, the stiffness loss, the benign values and the noise-free
low-frequency stiffness figure (the anchored Re D_u averaged over the low band, N/m, from noise-free
simulations of the healthy and the current truth), and per cracked machine the true growth of that figure
(N/m per day: the least-squares slope over its cracked sweeps of the noise-free figure of the crack alone,
without the benign scatter: ``du_low_crack_only_n_per_m``).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck import workflow
from rotorcheck.baseline import write_baseline
from rotorcheck.config import RigConfig, load_config
from rotorcheck.fleet.tasks import low_band
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.sweep import Sweep, write_sweep
from rotorcheck.variability import with_benign

START = dt.datetime(2026, 3, 1, 2, 0)
#: benign scatter of every sweep but the drifting machine's (uniform within +-): Young's modulus (temperature)
#: and both bearings' stiffness, as relative changes (the rig's ranges: 2 % and 3 %)
SCATTER = {"youngs_modulus": 0.002, "bearing_stiffness": 0.01}
CRACKS = {"A": (0.12, 0.2, 0.5), "B": (0.10, 0.4, 0.15)}  # final loss, onset share of the span, offset (steps)


def _configs() -> tuple[RigConfig, RigConfig]:
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    return truth.model_copy(update={"variability": nominal.variability}), nominal


def _cracked(truth: RigConfig, loss: float) -> tuple[RigConfig, str | None]:
    if loss <= 0.0:
        return truth, None
    faults = dict(truth.faults)
    faults["open_crack"] = faults["open_crack"].model_copy(update={"modulus_factor": 1.0 - loss})
    return truth.model_copy(update={"faults": faults}), "open_crack"


def _sweep(truth: RigConfig, grid: np.ndarray, loss: float, benign: dict[str, float], seed: int, created: str,
           noise: bool = True) -> Sweep:
    cfg, _, _, _ = with_benign(truth, benign) if benign else (truth, 0.0, 1.0, 1.0)
    cfg, fault = _cracked(cfg, loss)
    st = step_settings(cfg, keep_periods=False)
    if not noise:
        st = dataclasses.replace(st, output_noise_std=0.0)
    return simulate_rig(cfg, grid, 0.0, fault=fault, seed=seed, settings=st, created_utc=created)


def _frf(sw: Sweep) -> np.ndarray:
    run = next(iter(sw.runs.values()))
    return np.asarray(run.output_phasor[:, 0] / run.input_phasor[:, 0])


def machine_kinds(n: int) -> dict[int, str]:
    """Machine index -> kind: 'crack-A', 'crack-B', 'benign-drift' or 'healthy'."""
    kinds = dict.fromkeys(range(n), "healthy")
    if n >= 2:
        kinds[1] = "crack-A"
    if n >= 3:
        kinds[2] = "benign-drift"
    if n >= 4:
        kinds[max(3, n // 2 + 1)] = "crack-B"
    return kinds


def make_fleet(out: Path, machines: int = 20, sweeps: int = 10, seed: int = 0, points: int = 262,
               step_days: float = 7.0, only: set[str] | None = None) -> dict[str, Any]:
    """Write the fleet into ``out`` (module docstring); returns the truth document (also truth.json).
    ``only``: write just these machines (names ``machine-NN``), each exactly as in the whole fleet (the
    seeds and the random benign scatter of the others are drawn and dropped)."""
    if sweeps < 3:
        raise ValueError("at least 3 sweeps per machine")
    truth, nominal = _configs()
    grid = np.linspace(30.0, 600.0, points)
    from rotorcheck.nominal import nominal_model
    from rotorcheck.robust import identify

    E = nominal_model(nominal, grid, 0.0).E
    times = [START + dt.timedelta(days=step_days * k) for k in range(sweeps)]
    t_days = np.array([step_days * k for k in range(sweeps)])
    healthy_true = _frf(_sweep(truth, grid, 0.0, {}, 0, "", noise=False))
    band = low_band(grid, healthy_true, None)

    def du_true(frf: np.ndarray) -> float:
        if np.array_equal(frf, healthy_true):
            return 0.0  # no change (the formula is 0/0 there)
        d = identify.damage_dynamics(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], healthy_true, frf)
        return float(np.mean(d.real[band]))

    doc: dict[str, Any] = {"seed": seed, "points": points, "step_days": step_days, "speed_rpm": 0.0,
                           "low_band_max_hz": float(grid[band].max()), "machines": {}}
    rng = np.random.default_rng([seed, 15])
    for i, kind in sorted(machine_kinds(machines).items()):
        name = f"machine-{i:02d}"
        if only is not None and name not in only:
            if kind != "benign-drift":  # draw its scatter all the same: the machines after it stay as they are
                rng.uniform(-1.0, 1.0, (sweeps, 3))
            continue
        mdir = out / name
        (mdir / "sweeps").mkdir(parents=True, exist_ok=True)
        (mdir / "healthy").mkdir(exist_ok=True)
        shutil.copyfile(configs_dir() / "crack_rig.yaml", mdir / "rig.yaml")
        mseed = seed * 1_000_000 + i * 1000
        # the baseline: two healthy sweeps a month before monitoring starts, validated as a user would
        hpaths = []
        for k in range(2):
            p = mdir / "healthy" / f"healthy_{k + 1}.h5"
            write_sweep(_sweep(truth, grid, 0.0, {}, mseed + 900 + k, "2026-02-01T02:00:00Z"), p, force=True)
            hpaths.append(p)
        rig = workflow.load_rig(mdir / "rig.yaml")
        runs = [workflow.load_run(p, rig) for p in hpaths]
        nb = workflow.fit_noise(runs[0])
        outcome = workflow.validate(rig, runs, nb, enclose="measured")
        outcome.baseline.provenance.rig_path = str((mdir / "rig.yaml").resolve())
        write_baseline(outcome.baseline, mdir / "baseline.h5")
        final_loss, share, offset = CRACKS.get(kind.removeprefix("crack-"), (0.0, 0.0, 0.0))
        onset = (max(1, round(share * sweeps)) - offset) * step_days
        rate = final_loss / (t_days[-1] - onset) if final_loss else 0.0
        entries = []
        for k, t in enumerate(times):
            loss = max(0.0, rate * (t_days[k] - onset)) if final_loss else 0.0
            benign: dict[str, float] = {}
            if kind == "benign-drift":
                benign = {"bearing_stiffness.me": -0.025 * k / (sweeps - 1)}
            else:  # healthy and cracked machines: temperature and bearing scatter
                u = rng.uniform(-1.0, 1.0, 3)
                benign = {"youngs_modulus": SCATTER["youngs_modulus"] * u[0],
                          "bearing_stiffness.nme": SCATTER["bearing_stiffness"] * u[1],
                          "bearing_stiffness.me": SCATTER["bearing_stiffness"] * u[2]}
            stamp = t.strftime("%Y-%m-%dT%H-%M")
            created = t.strftime("%Y-%m-%dT%H:%M:%SZ")
            write_sweep(_sweep(truth, grid, loss, benign, mseed + k, created), mdir / "sweeps" / f"{stamp}.h5",
                        force=True)
            clean = _frf(_sweep(truth, grid, loss, benign, 0, created, noise=False))
            # no crack: the crack-only response is the healthy one (du_true 0), not simulated again
            du_crack = du_true(_frf(_sweep(truth, grid, loss, {}, 0, created, noise=False))) if loss > 0 else 0.0
            entries.append({"file": f"{name}/sweeps/{stamp}.h5", "time": created, "loss": loss, "benign": benign,
                            "du_low_true_n_per_m": du_true(clean), "du_low_crack_only_n_per_m": du_crack})
        m: dict[str, Any] = {"kind": kind, "sweeps": entries}
        if final_loss:
            cracked = [k for k, e in enumerate(entries) if e["loss"] > 0]
            y = np.array([entries[k]["du_low_crack_only_n_per_m"] for k in cracked])
            slope = float(np.polyfit(t_days[cracked], y, 1)[0]) if len(cracked) >= 2 else float("nan")
            m.update(loss_rate_per_day=rate, onset_time=(START + dt.timedelta(days=onset)).strftime(
                "%Y-%m-%dT%H:%M:%SZ"), growth_true_n_per_m_per_day=slope)
        doc["machines"][name] = m
        print(f"{name}: {kind}", file=sys.stderr, flush=True)
    (out / "truth.json").write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    return doc


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path)
    ap.add_argument("--machines", type=int, default=20)
    ap.add_argument("--sweeps", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--points", type=int, default=262)
    ap.add_argument("--step-days", type=float, default=7.0)
    ap.add_argument("--only", default=None, help="comma-separated machine names: write just these (as in the "
                                                 "whole fleet)")
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    make_fleet(a.out, a.machines, a.sweeps, a.seed, a.points, a.step_days,
               None if a.only is None else {x.strip() for x in a.only.split(",") if x.strip()})
    print(f"wrote a fleet of {a.machines} machines x {a.sweeps} sweeps into {a.out} (truth.json)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
