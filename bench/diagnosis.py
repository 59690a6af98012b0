"""Issue 30's "Must show": one diagnosis for detect and locate, on the truth rig and independent-physics variants.

Per truth (``truth`` and variants of :mod:`bench.truth_variants`), channels (the samples' one probe 8x -> 6x,
and x/y probes at stations 6 and 2 with forces 8x and 8y) and crack kind (open cracks at 0 rpm with
stiffness losses 10 / 20 / 40 %; breathing cracks at 1000 rpm, depths 20 / 30 / 50 % of the diameter,
the truth's Mayes-Davies crack), every element 2-8 once, the severities cycling over the elements (a
Latin design: each severity on 2-3 elements per cell, every element once per cell). Each case: a healthy
baseline sweep of the truth (``fit-noise``, ``validate --enclose measured``: the product's default path)
and a cracked sweep, seeded, the samples' measurement; then ``detect`` (its diagnosis: the ranking) and
``locate`` (certificates; its own ranking, not detect's) against the nominal model ``configs/crack_rig.yaml``.
Healthy repeats per (truth, channels, speed): detect only (a healthy verdict shows no finding).

Reported: detect's verdict, detect's rank 1, locate's rank 1 and its kind (located / ranked / not
locatable), the true element's status, relative likelihood and certified loss interval against the truth,
the depth interval (breathing). ``python -m bench.diagnosis [--variants truth,dampers,fine_mesh] [--quick]``
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from bench.detection_power import GRID
from bench.location import SECTION, XY_ACTUATORS, XY_SENSORS
from bench.truth_variants import nominal, truth_variant
from rotorcheck import workflow
from rotorcheck.config import Crack, RigConfig
from rotorcheck.location import breathing_loss
from rotorcheck.sim.rig_sim import simulate_rig, simulate_rig_patterns, step_settings

ELEMENTS = tuple(range(2, 9))
OPEN_LOSSES = (0.10, 0.20, 0.40)
DEPTHS = (0.20, 0.30, 0.50)


def _sweep(cfg: RigConfig, nom: RigConfig, speed: float, xy: bool, seed: int, fault: str | None) -> Any:
    st = step_settings(cfg, keep_periods=False)
    if xy:
        sw = simulate_rig_patterns(cfg, GRID, XY_ACTUATORS, XY_SENSORS, speed_rpm=speed, fault=fault, seed=seed,
                                   settings=st)
    else:
        sw = simulate_rig(cfg, GRID, speed, fault=fault, seed=seed, settings=st)
    return workflow.measured_run(sw, nom)


def _cracked(truth: RigConfig, kind: str, element: int, severity: float) -> RigConfig:
    faults = dict(truth.faults)
    if kind == "open":
        faults["loc"] = Crack(element=element, model="open", modulus_factor=1.0 - severity)
    else:
        faults["loc"] = truth.faults["breathing_crack"].model_copy(  # type: ignore[union-attr]
            update={"element": element, "depth": severity})
    return truth.model_copy(update={"faults": faults})


def run_cell(variant: str, xy: bool, kind: str, seed0: int, quick: bool, log: Any) -> list[dict[str, Any]]:
    nom = nominal()
    truth = truth_variant(variant, nom)
    speed = 0.0 if kind == "open" else 1000.0
    sev = OPEN_LOSSES if kind == "open" else DEPTHS
    h = _sweep(truth, nom, speed, xy, seed0, None)
    base = workflow.validate(nom, [h], workflow.fit_noise(h), enclose="measured").baseline
    rows: list[dict[str, Any]] = []
    rep = _sweep(truth, nom, speed, xy, seed0 + 1, None)
    out = workflow.detect(nom, base, rep)
    rows.append({"variant": variant, "xy": xy, "kind": "healthy", "speed": speed, "verdict": out.verdict.verdict,
                 "headline_where": out.location is not None})
    elements = ELEMENTS[::3] if quick else ELEMENTS
    for k, e in enumerate(elements):
        s = sev[(k + (1 if xy else 0) + (2 if kind == "breathing" else 0)) % 3]
        t0 = time.process_time()
        run = _sweep(_cracked(truth, kind, e, s), nom, speed, xy, seed0 + 10 + k, "loc")
        t1 = time.process_time()
        out = workflow.detect(nom, base, run)
        t2 = time.process_time()
        row: dict[str, Any] = {"variant": variant, "xy": xy, "kind": kind, "element": e, "severity": s,
                               "verdict": out.verdict.verdict, "sim_s": t1 - t0, "detect_s": t2 - t1}
        d_loc = out.location
        row["detect_rank1"] = None if d_loc is None or d_loc.best is None else d_loc.best.element
        true_loss = s if kind == "open" else breathing_loss(s, 0.008, SECTION, 0.3)
        if d_loc is not None and d_loc.best is not None and d_loc.best.estimate_interval is not None:
            b = d_loc.best
            row["est"] = b.estimate_interval
            row["est_depth"] = b.estimate_depth_interval
            if b.element == e:  # detect's interval about the true element: does it hold the truth?
                row["est_in"] = bool(b.estimate_interval[0] <= true_loss <= b.estimate_interval[1])
                if kind == "breathing" and b.estimate_depth_interval is not None:
                    d0, d1 = b.estimate_depth_interval
                    row["est_depth_in"] = d0 is not None and d0 <= s and (d1 is None or s <= d1)
                    row["est_depth_width"] = None if d0 is None or d1 is None else d1 - d0
        if out.verdict.verdict == "damage":
            loc = workflow.locate_damage(nom, base, run, damage=True, section_length=SECTION)
            row["locate_s"] = time.process_time() - t2
            row["locate_rank1"] = None if loc.best is None else loc.best.element
            row["kind_said"] = loc.kind
            row["summary"] = loc.summary()
            c = next(x for x in loc.candidates if x.element == e)
            row.update(status=c.status, rank=c.rank, likelihood=c.likelihood, loss=c.loss_interval, true_loss=true_loss,
                       estimate=c.loss_estimate,
                       loss_in=bool(c.status == "consistent" and c.loss_interval[0] <= true_loss <= c.loss_interval[1]),
                       depth=c.depth_interval)
            if kind == "breathing":
                d0, d1 = c.depth_interval
                row["depth_in"] = d0 is not None and d0 <= s and (d1 is None or s <= d1)
                row["depth_width"] = None if d0 is None or d1 is None else d1 - d0
        rows.append(row)
        log(f"{variant} {'x/y' if xy else 'one'} {kind} e{e} {s}: {row['verdict']}, detect {row['detect_rank1']}, "
            f"locate {row.get('locate_rank1')} ({row.get('kind_said')}), true {row.get('status')} "
            f"{row.get('likelihood')}; sim {row['sim_s']:.1f} detect {row['detect_s']:.1f} "
            f"locate {row.get('locate_s', 0):.1f} s")
    return rows


def _frac(xs: list[bool]) -> str:
    return f"{sum(xs)}/{len(xs)}" if xs else "-"


def _median(xs: list[float | None]) -> str:
    """The median of the known values in percent of the diameter ('-' when none)."""
    known = sorted(100 * x for x in xs if x is not None)
    return f"{known[len(known) // 2]:.0f} %" if known else "-"


def _interval(x: tuple[float | None, float | None] | None) -> str:
    if x is None or x[0] is None:
        return ""
    return f"{100 * x[0]:.0f}-" + ("over 50" if x[1] is None else f"{100 * x[1]:.0f}") + " %"


def table(rows: list[dict[str, Any]], variants: list[str]) -> str:
    lines = ["| truth | channels | kind | cases | damage verdicts | rank 1 = true (detect) | rank 1 = true (locate) | "
             "detect = locate rank 1 | says where (located / ranked / not locatable) | located but wrong | "
             "true element excluded | "
             "loss interval holds truth | depth interval holds truth | detect's 95 % interval holds truth (loss; "
             "depth) | depth interval width, median (certified; detect's) | healthy repeat: verdict, where shown |",
             "|---|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|---|---|"]
    for v in variants:
        for xy in (False, True):
            for kind in ("open", "breathing"):
                sub = [r for r in rows if r["variant"] == v and r["xy"] == xy and r["kind"] == kind]
                dmg = [r for r in sub if r["verdict"] == "damage"]
                hr = [r for r in rows if r["variant"] == v and r["xy"] == xy and r["kind"] == "healthy"
                      and r["speed"] == (0.0 if kind == "open" else 1000.0)]
                said = [r.get("kind_said") for r in dmg]
                lines.append(
                    f"| {v} | {'x/y 8 pairs' if xy else 'one probe'} | {kind} | {len(sub)} | {len(dmg)} | "
                    f"{_frac([r['detect_rank1'] == r['element'] for r in sub])} | "
                    f"{_frac([r.get('locate_rank1') == r['element'] for r in dmg])} | "
                    f"{_frac([r.get('locate_rank1') == r['detect_rank1'] for r in dmg])} | "
                    f"{said.count('located')} / {said.count('ranked')} / {said.count('not locatable')} | "
                    f"{sum(r.get('kind_said') == 'located' and r.get('locate_rank1') != r['element'] for r in dmg)} | "
                    f"{_frac([r.get('status') == 'excluded' for r in dmg])} | "
                    f"{_frac([bool(r.get('loss_in')) for r in dmg])} | "
                    f"{_frac([bool(r.get('depth_in')) for r in dmg]) if kind == 'breathing' else ''} | "
                    f"{_frac([r['est_in'] for r in sub if 'est_in' in r])}"
                    + (f"; {_frac([r['est_depth_in'] for r in sub if 'est_depth_in' in r])}" if kind == "breathing"
                       else "") + " | "
                    + (f"{_median([r.get('depth_width') for r in dmg])}; "
                       f"{_median([r.get('est_depth_width') for r in sub])}" if kind == "breathing" else "") + " | "
                    + ", ".join(f"{r['verdict']}{' WHERE SHOWN' if r['headline_where'] else ''}" for r in hr) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", default="truth,dampers,fine_mesh")
    ap.add_argument("--quick", action="store_true", help="elements 2, 5, 8 only")
    a = ap.parse_args(argv)
    variants = a.variants.split(",")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    t0 = time.process_time()
    rows: list[dict[str, Any]] = []
    for i, v in enumerate(variants):
        for xy in (False, True):
            for kind in ("open", "breathing"):
                rows += run_cell(v, xy, kind, 30_000_000 + 100_000 * i + (50_000 if xy else 0)
                                 + (1000 if kind == "breathing" else 0), a.quick, log)
    print(table(rows, variants))
    print("\n| case | verdict | detect rank 1 | locate rank 1 | true: status, rank, likelihood | loss interval (truth) "
          "| best fit | depth interval | detect's 95 % loss interval; depth |\n"
          "|---|---|---:|---:|---|---|---:|---|---|")
    for r in rows:
        if r["kind"] == "healthy":
            continue
        sev = f"loss {100 * r['severity']:.0f} %" if r["kind"] == "open" else f"depth {100 * r['severity']:.0f} %"
        lo_hi = r.get("loss")
        loss = "" if lo_hi is None else f"{100 * lo_hi[0]:.1f}-{100 * lo_hi[1]:.1f} % ({100 * r['true_loss']:.1f} %)"
        d = r.get("depth") or (None, None)
        depth = ("" if d[0] is None else f"{100 * d[0]:.0f}-" + ("over 50" if d[1] is None else f"{100 * d[1]:.0f}")
                 + " %")
        lik = r.get("likelihood")
        est = r.get("estimate")
        print(f"| {r['variant']} {'x/y' if r['xy'] else 'one'} {r['kind']} e{r['element']} {sev} | {r['verdict']} | "
              f"{r['detect_rank1']} | {r.get('locate_rank1')} | {r.get('status')}, {r.get('rank')}, "
              f"{'' if lik is None else f'{lik:.2f}'} | {loss} | {'' if est is None else f'{100 * est:.1f} %'} | "
              f"{depth} | {_interval(r.get('est'))}; {_interval(r.get('est_depth'))} |")
    located = [r.get("locate_s", 0.0) for r in rows if "locate_s" in r]
    print(f"\nCPU {time.process_time() - t0:.0f} s in all; locate per damaged sweep: median "
          f"{sorted(located)[len(located) // 2] if located else 0:.1f} s, max {max(located, default=0):.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
