"""Screenshots of the reports an engineer reads (issue 31), by headless Chromium: report.html of a damage, a
healthy repeat and a benign case (the truth drifted inside the rig's ranges: E -1.5 %, the motor-end bearing
+2.5 %), location.html of the bundled open crack, and a small fleet's index.html.

``python -m tools.screenshots OUTDIR`` (needs ``chromium`` on PATH) writes the reports under ``OUTDIR/work``
and the PNGs (1200 px wide, full page height up to 6000 px) as ``OUTDIR/*.png``. Seeded; bench-only
imports (the drifted sweep comes from :mod:`bench.detection_limit`).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from rotorcheck.cli import main as cli
from rotorcheck.resources import configs_dir, samples_dir

CR = samples_dir() / "crack_rig"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--disable-dev-shm-usage"]
BENIGN = {"youngs_modulus": -0.015, "bearing_stiffness.me": 0.025}


def _ok(argv: list[str], allowed: tuple[int, ...] = (0, 1)) -> None:
    rc = cli(argv)
    if rc not in allowed:
        raise SystemExit(f"screenshots: rotorcheck {' '.join(argv)} exited {rc}")


def _benign_sweep(path: Path) -> None:
    """A sweep of the truth rig at 1000 rpm with :data:`BENIGN` applied (seeded), written as a sweep file."""
    from rotorcheck.config import load_config
    from rotorcheck.sim.rig_sim import simulate_rig, step_settings
    from rotorcheck.sweep.hdf5io import read_sweep, write_sweep
    from rotorcheck.variability import with_benign

    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    truth = truth.model_copy(update={"variability": load_config(configs_dir() / "crack_rig.yaml").variability})
    cfg, _, _, _ = with_benign(truth, BENIGN)  # structural drift only: no speed, no gains
    grid = read_sweep(CR / "healthy_1000rpm.h5").runs["1000rpm"].frequency
    sw = simulate_rig(cfg, grid, 1000.0, seed=7, settings=step_settings(cfg, keep_periods=True))
    write_sweep(sw, path, force=True)


def shoot(exe: str, html: Path, png: Path, height: int = 6000) -> None:
    profile = png.parent / ".chromium-profile"
    subprocess.run([exe, *FLAGS, f"--user-data-dir={profile}", f"--window-size=1200,{height}",
                    f"--screenshot={png}", html.resolve().as_uri()], capture_output=True, timeout=180, check=True)


def main(out: str = "screenshots") -> int:
    exe = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome") if shutil.which(n)), None)
    if exe is None:
        print("screenshots: no chromium on PATH", file=sys.stderr)
        return 2
    root = Path(out).resolve()
    work = root / "work"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    base = work / "baseline_1000rpm"
    _ok(["fit-noise", str(CR / "healthy_1000rpm.h5"), "--out", str(base)])
    _ok(["validate", str(CR / "healthy_1000rpm.h5"), "--out", str(base), "--no-plots"])
    _benign_sweep(work / "benign_1000rpm.h5")
    pages = {}
    for name, sweep in (("damage", CR / "breathing_crack_1000rpm.h5"), ("healthy", CR / "healthy_1000rpm_repeat.h5"),
                        ("benign", work / "benign_1000rpm.h5")):
        _ok(["detect", str(sweep), "--out", str(work / name), "--baseline", str(base / "baseline.h5"), "-q"])
        pages[f"report_{name}"] = work / name / "report.html"
    loc = work / "location"
    _ok(["fit-noise", str(CR / "healthy_0rpm.h5"), "--out", str(loc)])
    _ok(["validate", str(CR / "healthy_0rpm.h5"), "--out", str(loc), "--no-plots"])
    _ok(["locate", str(CR / "open_crack_0rpm.h5"), "--out", str(loc), "-q"])
    pages["location"] = loc / "location.html"
    fleet = work / "fleet"
    subprocess.run([sys.executable, "-m", "tools.fleet_sim", str(fleet), "--machines", "6", "--sweeps", "6", "--seed",
                    "0"], check=True)
    _ok(["fleet", str(fleet), "--limit", "3000", "-q"])
    pages["fleet_index"] = next(fleet.rglob("index.html"))
    for name, html in pages.items():
        shoot(exe, html, root / f"{name}.png")
        print(f"{root / (name + '.png')}  <-  {html}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(*sys.argv[1:]))
