"""Issue 30 ("Speed"): CPU time of ``rotorcheck locate`` (every shaft element a candidate) before and after, in one run.

``python -m bench.locate_speed [--before main] [--repeat 1]`` exports the ``--before`` revision's tree
(``git archive``, read only) to a temporary folder and times, interleaved round by round, fresh processes
of

- ``python -c "import numpy"`` (the baseline),
- ``rotorcheck locate --no-plots`` of the bundled open crack (one probe, ``crack_rig/open_crack_0rpm.h5``)
  and of the x/y sample (``crack_rig_xy/open_crack_0rpm.h5``, 8 channel pairs) with each tree,

one BLAS thread, ``MPLBACKEND=Agg``, bytecode cached as an installed package has it (``PYTHONDONTWRITEBYTECODE``
removed from the children's environment); the baselines are made beforehand by each tree's own ``fit-noise`` and
``validate --no-plots``. Prints the children's CPU seconds (user + system: steadier than wall time on a
shared machine), their ratio to the numpy start and the seconds beyond it, and after/before. Target:
at most 5 CPU-s per sweep (issue 30).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: (name, healthy sweep, new sweep) under data_samples
CASES = (("open crack, one probe", "crack_rig/healthy_0rpm.h5", "crack_rig/open_crack_0rpm.h5"),
         ("open crack, x/y 8 pairs", "crack_rig_xy/healthy_0rpm.h5", "crack_rig_xy/open_crack_0rpm.h5"))
TARGET_S = 5.0


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(argv: list[str], tree: Path, cwd: Path, ok: tuple[int, ...] = (0, 1, 3)) -> tuple[float, float]:
    """(wall s, CPU s) of one command with ``tree`` first on the path."""
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=str(tree))
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as installed: bytecode cached (the first run writes it)
    c, t = _cpu(), time.perf_counter()
    rc = subprocess.run(argv, cwd=cwd, env=env, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                        text=True)
    if rc.returncode not in ok:
        raise RuntimeError(f"{' '.join(argv)}: exit {rc.returncode}\n{rc.stderr[-2000:]}")
    return time.perf_counter() - t, _cpu() - c


def export(rev: str, dest: Path) -> Path:
    """The tree of ``rev`` under ``dest`` (git archive: the repository is only read)."""
    dest.mkdir(parents=True)
    arch = subprocess.run(["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=arch, check=True)
    return dest


def run(before: str, repeat: int) -> dict[str, list[float]]:
    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"before": export(before, Path(tmp) / "before"), "after": ROOT}
        work = Path(tmp) / "work"
        cmds: dict[str, tuple[Path, list[str]]] = {"python -c 'import numpy'": (ROOT, [py, "-c", "import numpy"])}
        for label, tree in trees.items():
            for k, (name, healthy, new) in enumerate(CASES):
                out = work / f"{label}{k}"
                s = tree / "data_samples"
                _run([py, "-m", "rotorcheck", "fit-noise", str(s / healthy), "--out", str(out)], tree, tree)
                _run([py, "-m", "rotorcheck", "validate", str(s / healthy), "--out", str(out), "--no-plots"], tree,
                     tree)
                cmds[f"locate {name} ({label})"] = (tree, [py, "-m", "rotorcheck", "locate", str(s / new), "--out",
                                                            str(out), "--no-plots", "--force"])
        times: dict[str, list[float]] = {k: [] for k in cmds}
        for _ in range(repeat):
            for key, (tree, argv) in cmds.items():
                times[key].append(_run(argv, tree, tree)[1])
                print(f"{key}: {times[key][-1]:.2f} CPU-s", file=sys.stderr, flush=True)
    return times


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default="main", help="the revision timed as 'before' (default: main)")
    ap.add_argument("--repeat", type=int, default=1)
    a = ap.parse_args(argv)
    times = run(a.before, a.repeat)
    base = statistics.median(times["python -c 'import numpy'"])
    print("| command | CPU s | x numpy start | CPU s beyond numpy | target |")
    print("|---|---:|---:|---:|---|")
    for k, ts in times.items():
        med = statistics.median(ts)
        mark = "" if "(after)" not in k else ("ok" if med - base <= TARGET_S else "MISS") + f" (<= {TARGET_S:g} s)"
        print(f"| {k} | {med:.2f} | {med / base:.1f} | {med - base:.2f} | {mark} |")
    for name, _, _ in CASES:
        b, f = statistics.median(times[f"locate {name} (before)"]), statistics.median(times[f"locate {name} (after)"])
        print(f"\n{name}: after / before = {f / b:.3f}", end="")
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
