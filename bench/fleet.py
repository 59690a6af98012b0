"""Wall time of ``rotorcheck fleet`` with 1 and 2 workers, local processes and a Dask LocalCluster (issue 15).

``python -m bench.fleet FLEET_DIR [--machines 5]``: the first ``--machines`` machines of a fleet made by
``tools.fleet_sim`` (every sweep), detection only (``--locate none``), each executor into a fresh results
folder; prints seconds and the 1-worker / 2-worker ratio, and checks the summaries are identical.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from rotorcheck.fleet.layout import discover
from rotorcheck.fleet.runner import FleetOptions, run_fleet


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("fleet", type=Path)
    ap.add_argument("--machines", type=int, default=5)
    a = ap.parse_args(argv)
    fleet = discover(a.fleet)
    with tempfile.TemporaryDirectory() as tmp:
        man = Path(tmp) / "fleet.csv"
        lines = ["machine,rig,baseline,sweep,time"]
        for m in fleet.machines[: a.machines]:
            lines += [f"{m.name},{m.rig},{m.baseline},{s.path},{s.time}" for s in m.sweeps]
        man.write_text("\n".join(lines) + "\n")
        times: dict[tuple[str, int], float] = {}
        texts = set()
        for executor in ("processes", "dask"):
            for workers in (1, 2):
                out = Path(tmp) / f"{executor}{workers}"
                t0 = time.perf_counter()
                res = run_fleet(man, FleetOptions(out=out, executor=executor, workers=workers, locate="none"))
                times[executor, workers] = time.perf_counter() - t0
                texts.add((out / "summary.csv").read_text())
                print(f"{executor} x{workers}: {res.n_detected} sweeps in {times[executor, workers]:.1f} s",
                      file=sys.stderr, flush=True)
        for executor in ("processes", "dask"):
            print(f"{executor}: 1 worker {times[executor, 1]:.1f} s, 2 workers {times[executor, 2]:.1f} s, "
                  f"ratio {times[executor, 1] / times[executor, 2]:.2f}")
        print(f"summaries identical: {len(texts) == 1}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
