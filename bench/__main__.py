"""``make bench``: every benchmark in one run; prints a table per benchmark."""

from __future__ import annotations

import importlib
import sys
import time

BENCHES = ("bench.bench_fe", "bench.bench_engine", "bench.bench_validation", "bench.bench_crack",
           "bench.bench_pipeline", "bench.bench_mixed_mu", "bench.ingest")


def main() -> int:
    for name in BENCHES:
        t = time.perf_counter()
        print(f"\n== {name}", flush=True)
        result = importlib.import_module(name).run()
        for k, v in result.items():
            if isinstance(v, dict):
                continue
            print(f"  {k:40s} {v:.4g}" if isinstance(v, float) else f"  {k:40s} {v}")
        print(f"  ({time.perf_counter() - t:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
