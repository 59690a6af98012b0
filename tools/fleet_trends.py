"""The demo fleet's trends against the simulator's truth: ``python -m tools.fleet_trends FLEET [RESULTS]``
(after ``rotorcheck fleet FLEET``; RESULTS default FLEET/results).

One line per machine that is not healthy in ``truth.json`` (:mod:`tools.fleet_sim`): its kind, the true
growth of the low-frequency stiffness figure (N/m per day; a crack's from the noise-free simulation of the
crack alone, ``growth_true_n_per_m_per_day``; otherwise the least-squares slope of the noise-free figure over
every sweep), rotorcheck's estimate with its interval, whether the interval brackets the truth, the latest
verdict and the prognosis, then each sentence in words. Exit 1 when a crack's interval misses its truth or the
benign drift is given a forecast.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.fleet.trend import days


def true_growth(machine: dict[str, Any]) -> float:
    """The machine's true growth of the figure, N/m per day (module docstring)."""
    if machine.get("growth_true_n_per_m_per_day") is not None:
        return float(machine["growth_true_n_per_m_per_day"])
    t = np.array([days(e["time"]) for e in machine["sweeps"]])
    y = np.array([e["du_low_true_n_per_m"] for e in machine["sweeps"]])
    return float(np.polyfit(t, y, 1)[0])


def rows(fleet: Path, results: Path) -> list[dict[str, Any]]:
    """Per non-healthy machine: kind, truth, estimate, interval, bracketed, verdict, forecast, words."""
    truth = json.loads((fleet / "truth.json").read_text(encoding="utf-8"))["machines"]
    trends = json.loads((results / "trends.json").read_text(encoding="utf-8"))
    out = []
    for m, d in sorted(truth.items()):
        if d["kind"] == "healthy":
            continue
        tr = trends[m]
        lo, hi = tr["slope_interval_n_per_m_per_day"]
        g = true_growth(d)
        out.append({"machine": m, "kind": d["kind"], "true": g, "estimate": tr["slope_n_per_m_per_day"],
                    "lo": lo, "hi": hi, "brackets": lo is not None and lo <= g <= hi,
                    "verdict": tr["latest_verdict"], "forecast": tr["forecast"], "trend": tr["trend"],
                    "prognosis": tr["prognosis"]})
    return out


def render(table: list[dict[str, Any]]) -> str:
    head = (f"{'machine':11s} {'kind':13s} {'true growth':>12s} {'estimate [95 % interval]':>27s} {'brackets':>8s} "
            f"{'verdict':8s} forecast")
    lines = ["trends against the simulator's truth (N/m per day)", head]
    for r in table:
        est = f"{r['estimate']:.3g} [{r['lo']:.3g}, {r['hi']:.3g}]"
        lines.append(f"{r['machine']:11s} {r['kind']:13s} {r['true']:12.3g} {est:>27s} "
                     f"{'yes' if r['brackets'] else 'NO':>8s} {r['verdict']:8s} {'yes' if r['forecast'] else 'no'}")
    for r in table:
        lines.append(f"{r['machine']}: {r['trend']}; {r['prognosis']}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("fleet", type=Path)
    ap.add_argument("results", type=Path, nargs="?")
    a = ap.parse_args(argv)
    table = rows(a.fleet, a.results or a.fleet / "results")
    sys.stdout.write(render(table))
    bad = [r for r in table if (r["kind"].startswith("crack") and not r["brackets"])
           or (r["kind"] == "benign-drift" and r["forecast"])]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
