"""Where and how big (issue 11): the candidate-element location on fresh simulated sweeps of the truth rig.

Every case simulates a healthy sweep and a damaged one of ``configs/crack_rig_truth.yaml`` (the samples'
262-point grid and measurement, output noise 1x) and locates against the nominal rig
(:func:`rotorcheck.workflow.locate_run`, every shaft element a candidate, 1 % chance per sweep that a true
candidate is excluded): open cracks (a modulus factor on the whole element) at 0 rpm, breathing cracks
(Mayes-Davies, the truth's 20 mm section) at 1000 rpm, with the samples' one channel (force 8x, probe 6x)
and with x and y probes at stations 6 and 2 (forces 8x and 8y); benign changes inside the ranges and
healthy repeats must locate nothing. Per case: the true element's status and rank, its loss interval
against the truth, the depth interval, the excluded elements.

``python -m bench.location [--quick] [--workers 2] [--out bench/results_location.md]``
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from bench.detection_power import GRID
from rotorcheck import workflow
from rotorcheck.config import Crack, Port, RigConfig, load_config
from rotorcheck.location import breathing_loss
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig, simulate_rig_patterns, step_settings
from rotorcheck.variability import with_benign

XY_ACTUATORS = (Port(station=8, direction="x"), Port(station=8, direction="y"))
XY_SENSORS = (Port(station=6, direction="x"), Port(station=6, direction="y"), Port(station=2, direction="x"),
              Port(station=2, direction="y"))
SECTION = 0.020  # m, the truth's breathing crack section length
OPEN = [(e, mf) for e in range(2, 9) for mf in (0.8, 0.6)]
BREATHING = [(e, d) for e in range(3, 8) for d in (0.3, 0.5)]
BENIGN = {"healthy repeat": {}, "E -1 %, nme +2 %, gain +0.5 %": {"youngs_modulus": -0.01,
          "bearing_stiffness.nme": 0.02, "sensor_gain": 0.005}}


def _rigs() -> tuple[RigConfig, RigConfig]:
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    return truth.model_copy(update={"variability": nominal.variability}), nominal


def case_runs(kind: str, element: int, severity: float, xy: bool, seed: int, benign: dict[str, float] | None = None,
              speed: float | None = None) -> tuple[RigConfig, workflow.MeasuredRun, workflow.MeasuredRun, float]:
    """(nominal rig, healthy run, new run, speed): ``kind`` 'open' (modulus factor ``severity``, 0 rpm),
    'breathing' (depth ``severity`` of the diameter, 1000 rpm) or 'benign' (``benign`` values, no crack)."""
    truth, nominal = _rigs()
    rpm = speed if speed is not None else (0.0 if kind == "open" else 1000.0)
    faults = dict(truth.faults)
    fault = None
    if kind == "open":
        faults["loc"] = Crack(element=element, model="open", modulus_factor=severity)
        fault = "loc"
    elif kind == "breathing":
        faults["loc"] = truth.faults["breathing_crack"].model_copy(update={"element": element,  # type: ignore[union-attr]
                                                                          "depth": severity})
        fault = "loc"
    cracked = truth.model_copy(update={"faults": faults})
    values = {k: v for k, v in (benign or {}).items() if not (k == "speed" and rpm == 0.0)}
    cfg, d_rpm, g_s, g_a = with_benign(cracked, values) if values else (cracked, 0.0, 1.0, 1.0)
    st = step_settings(truth, keep_periods=False)

    def sweep(c: RigConfig, s: int, flt: str | None, r: float) -> Any:
        if xy:
            return simulate_rig_patterns(c, GRID, XY_ACTUATORS, XY_SENSORS, speed_rpm=r, fault=flt, seed=s,
                                         settings=st)
        return simulate_rig(c, GRID, r, fault=flt, seed=s, settings=st)

    healthy = workflow.measured_run(sweep(truth, seed, None, rpm), nominal)
    new = workflow.measured_run(sweep(cfg, seed + 1, fault, rpm + d_rpm), nominal)
    g = g_s * g_a
    if g != 1.0:
        new = dataclasses.replace(new, Zt=new.Zt * g, output_var=new.output_var * g**2,
                                  frf_pairs=None if new.frf_pairs is None else new.frf_pairs * g,
                                  var_pairs=None if new.var_pairs is None else new.var_pairs * g**2)
    return nominal, healthy, new, rpm


def run_case(spec: tuple[str, int, float, bool, int, str]) -> dict[str, Any]:
    """One case: the location's figures for the table."""
    kind, element, severity, xy, seed, name = spec
    nominal, h, new, rpm = case_runs(kind, element, severity, xy, seed, BENIGN.get(name))
    est = workflow.healthy_estimate([h])
    t0 = time.perf_counter()
    res = workflow.locate_run(nominal, new, est.frf, est.var, rpm, 0.01, None, SECTION, both=False)
    dt = time.perf_counter() - t0
    out: dict[str, Any] = {"kind": kind, "element": element, "severity": severity, "xy": xy, "name": name,
                           "seconds": dt, "summary": res.summary(), "located": res.best is not None,
                           "best": None if res.best is None else res.best.element,
                           "excluded": [c.element for c in res.candidates if c.status == "excluded"]}
    if kind in ("open", "breathing"):
        c = next(x for x in res.candidates if x.element == element)
        true_loss = 1.0 - severity if kind == "open" else breathing_loss(severity, 0.008, SECTION, 0.3)
        out.update(status=c.status, rank=c.rank, loss=list(c.loss_interval), true_loss=true_loss,
                   loss_in=bool(c.loss_interval[0] <= true_loss <= c.loss_interval[1]),
                   depth=list(c.depth_interval), estimate=c.loss_estimate)
        if kind == "breathing":
            d0, d1 = c.depth_interval
            out["depth_in"] = d0 is not None and d0 <= severity and (d1 is None or severity <= d1)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.location")
    ap.add_argument("--quick", action="store_true", help="elements 3-5, one severity each")
    ap.add_argument("--full", action="store_true", help="every case of issue 11 (about 50; 40 min on 2 cores)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="bench/results_location.md")
    a = ap.parse_args(argv)
    specs: list[tuple[str, int, float, bool, int, str]] = []
    for xy in (False, True):
        if a.quick:
            opens, breaths = [(e, 0.6) for e in (3, 4, 5)], [(e, 0.5) for e in (3, 5)]
        elif a.full:
            opens, breaths = OPEN, BREATHING
        elif not xy:  # the default: every element once, the other severity on some
            opens = [(e, 0.6) for e in range(2, 9)] + [(e, 0.8) for e in (3, 4, 6)]
            breaths = [(e, 0.5) for e in range(3, 8)] + [(e, 0.3) for e in (4, 6)]
        else:
            opens, breaths = [(e, 0.6) for e in (3, 4, 6)] + [(4, 0.8)], [(e, 0.5) for e in (4, 5, 6)] + [(4, 0.3)]
        specs += [("open", e, mf, xy, 7100 + 10 * e + int(10 * mf), "") for e, mf in opens]
        specs += [("breathing", e, d, xy, 7300 + 10 * e + int(10 * d), "") for e, d in breaths]
        specs += [("benign", 0, 0.0, xy, 7500 + k, name) for k, name in enumerate(BENIGN)]
    t0 = time.perf_counter()
    rows = []
    with ProcessPoolExecutor(a.workers) as ex:
        for r in ex.map(run_case, specs):
            rows.append(r)
            print(f"{r['kind']} e{r['element']} {r['severity']} xy={r['xy']} {r['name']}: {r['summary']} "
                  f"({r['seconds']:.0f} s)", flush=True)
    lines = ["| case | channels | true element: status, rank | loss interval (truth) | depth interval | excluded | s |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        ch = "x/y 8 pairs" if r["xy"] else "one (8x->6x)"
        if r["kind"] == "benign":
            lines.append(f"| {r['name']} | {ch} | {'LOCATED ' + str(r['best']) if r['located'] else 'nothing located'} "
                         f"| | | {r['excluded']} | {r['seconds']:.0f} |")
            continue
        sev = f"modulus factor {r['severity']}" if r["kind"] == "open" else f"depth {100 * r['severity']:.0f} %"
        d0, d1 = r["depth"]
        depth = "" if d0 is None else f"{100 * d0:.0f}-" + ("over 50" if d1 is None else f"{100 * d1:.0f}") + " %"
        lines.append(f"| {r['kind']} e{r['element']}, {sev} | {ch} | {r['status']}, {r['rank']} | "
                     f"{100 * r['loss'][0]:.1f}-{100 * r['loss'][1]:.1f} % ({100 * r['true_loss']:.1f} %) | {depth} | "
                     f"{r['excluded']} | {r['seconds']:.0f} |")
    crack = [r for r in rows if r["kind"] != "benign"]
    for xy in (False, True):
        sub = [r for r in crack if r["xy"] == xy]
        if not sub:
            continue
        lines.append("")
        n_ex, n_first = sum(r["status"] == "excluded" for r in sub), sum(r["rank"] == 1 for r in sub)
        lines.append(f"{'x/y' if xy else 'one channel'}: true element excluded {n_ex}/{len(sub)}, ranked first "
                     f"{n_first}/{len(sub)}, loss interval holds the truth {sum(r['loss_in'] for r in sub)}/{len(sub)}")
    benign = [r for r in rows if r["kind"] == "benign"]
    lines.append(f"benign and healthy: located {sum(r['located'] for r in benign)}/{len(benign)}")
    lines.append(f"wall time {time.perf_counter() - t0:.0f} s with {a.workers} workers")
    text = "\n".join(lines) + "\n"
    print(text)
    with open(a.out, "w") as fh:
        fh.write("# Location on fresh simulated sweeps (bench/location.py)\n\n" + text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
