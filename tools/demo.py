"""``make demo``: the whole pipeline on the bundled crack-rig samples, as a user would type it.

Each case runs in its own folder under ``demo/`` so that the commands need no flag beyond the file
names (``--rig`` defaults to the bundled rig named by the sweep, ``--out`` to ``rotorcheck-out/``):

    rotorcheck model configs/crack_rig.yaml --speed 1000
    rotorcheck crack --demo                (Fig. 56-58: the breathing crack's stiffness, orbit, spectra)
    rotorcheck fit-noise  <healthy sweep>
    rotorcheck validate   <healthy sweep>
    rotorcheck detect     <new sweep>
    rotorcheck locate     <new sweep>      (the open crack at 0 rpm: where and how big)
    rotorcheck detectability --baseline    (1000 rpm: what this rig and noise can detect, per element)

Cases: the open crack at 0 rpm, the breathing crack at 1000 rpm, the repeat healthy sweep at
1000 rpm and a free-running (random start angle) healthy pair at 2000 rpm (false-alarm checks); with
x/y probes (8 channel pairs): the open crack at 0 rpm and the repeat healthy sweep at 1000 rpm.
One case starts from raw time records (issue 33): the simulator records a healthy and an open-crack
stepped-sine test at 0 rpm (40 steps, force, probe volts, 5.12 kHz clock not locked to the
excitation; CSV and TDMS), ``rotorcheck ingest`` turns them into sweeps, then fit-noise, validate and
detect (certified per-point rule: 40 points are too few for the joint test's benign-change budget).
Previous demo output is replaced (it is the demo's own folder).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from rotorcheck.resources import configs_dir, samples_dir

#: the cases where the demo also locates the change (every shaft element a candidate)
LOCATE = ("open_crack_0rpm",)
#: the cases where the demo also predicts what the rig can detect, from the baseline's noise
DETECTABILITY = ("breathing_crack_1000rpm",)
CASES = (
    ("open_crack_0rpm", "crack_rig/healthy_0rpm.h5", "crack_rig/open_crack_0rpm.h5"),
    ("breathing_crack_1000rpm", "crack_rig/healthy_1000rpm.h5", "crack_rig/breathing_crack_1000rpm.h5"),
    ("repeat_healthy_1000rpm", "crack_rig/healthy_1000rpm.h5", "crack_rig/healthy_1000rpm_repeat.h5"),
    ("free_running_healthy_2000rpm", "crack_rig/healthy_2000rpm.h5", "crack_rig/healthy_2000rpm_repeat.h5"),
    ("sidebands_shallow_crack_1000rpm", "crack_rig_sidebands/healthy_1000rpm.h5",
     "crack_rig_sidebands/breathing_crack_10pct_1000rpm.h5"),
    # x and y probes at stations 6 and 2, forces in x and y at station 8 (8 channel pairs)
    ("xy_open_crack_0rpm", "crack_rig_xy/healthy_0rpm.h5", "crack_rig_xy/open_crack_0rpm.h5"),
    ("xy_repeat_healthy_1000rpm", "crack_rig_xy/healthy_1000rpm.h5", "crack_rig_xy/healthy_1000rpm_repeat.h5"),
)
VERDICTS = {0: "healthy", 1: "DAMAGE", 2: "error", 3: "inconclusive"}


def _run(args: list[str], cwd: Path) -> int:
    cmd = [sys.executable, "-m", "rotorcheck", *args]
    print(f"\n$ (cd {cwd}) rotorcheck {' '.join(args)}", flush=True)
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run(cmd, cwd=cwd, env=env, check=False).returncode


def main(root: str | Path = "demo") -> int:
    base = Path(root).resolve()
    if base.exists():
        shutil.rmtree(base)
    base.mkdir(parents=True)
    samples = samples_dir().resolve()
    summary = []
    model_dir = base / "model"
    model_dir.mkdir()
    if _run(["model", str(configs_dir() / "crack_rig.yaml"), "--speed", "1000"], model_dir) != 0:
        return 2
    if _run(["crack", "--demo"], model_dir) != 0:  # the cracked rotor of section 5.3: Fig. 56-58
        return 2
    for name, healthy, new in CASES:
        work = base / name
        work.mkdir()
        h, n = str(samples / healthy), str(samples / new)
        for step in (["fit-noise", h], ["validate", h]):
            if _run(step, work) not in (0, 3):
                print(f"demo: {name}: '{step[0]}' failed", file=sys.stderr)
                return 2
        rc = _run(["detect", n], work)
        if rc == 2:
            return 2
        summary.append((name, VERDICTS.get(rc, str(rc)), work / "rotorcheck-out"))
        if name in LOCATE and _run(["locate", n], work) == 2:
            return 2
        if name in DETECTABILITY and _run(["detectability", "--baseline", "rotorcheck-out/baseline.h5"], work) != 0:
            return 2
    raw = _raw_records_case(base)
    if raw is None:
        return 2
    summary.append(raw)
    print("\nsummary")
    for name, verdict, out in summary:
        print(f"  {name:26s} {verdict:12s} reports and plots in {out} (open {out / 'report.html'})")
    return 0


def _raw_records_case(base: Path) -> tuple[str, str, Path] | None:
    """Time records made now by the simulator -> ``rotorcheck ingest`` -> fit-noise, validate, detect."""
    from tools.time_records import make

    name = "raw_time_records_open_crack_0rpm"
    work = base / name
    work.mkdir()
    sweeps = []
    for tag, fmt, fault, seed in (("healthy", "csv", None, 21), ("new", "tdms", "open_crack", 22)):
        rec, cmap = make(work / f"{tag}_records", fmt, 0.0, fault, points=40, seed=seed, fs_hz=5120.0)
        if _run(["ingest", str(rec), f"{tag}.h5", "--map", str(cmap)], work) != 0:
            return None
        sweeps.append(f"{tag}.h5")
    for step in (["fit-noise", sweeps[0]], ["validate", sweeps[0], "--no-plots"]):
        if _run(step, work) not in (0, 3):
            print(f"demo: {name}: '{step[0]}' failed", file=sys.stderr)
            return None
    rc = _run(["detect", sweeps[1], "--rule", "certified"], work)
    if rc == 2:
        return None
    return name, VERDICTS.get(rc, str(rc)), work / "rotorcheck-out"


if __name__ == "__main__":
    sys.exit(main())
