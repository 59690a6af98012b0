"""The bundled sample sweeps (``data_samples/``), regenerated deterministically by ``make samples``.

Every sample is a seeded simulation of a truth rig (``configs/*_truth.yaml``), never of the nominal
model, so validation has real model error to absorb. ``python -m tools.samples DIR``
writes them; ``--check`` compares the files in DIR with what the code makes (bit for bit).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorcheck.config import Port, load_config
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import shaft_angle_from, simulate_rig, simulate_rig_patterns, step_settings
from rotorcheck.sweep import Sweep, compare_sweeps, read_sweep, write_sweep

CREATED_UTC = "2026-01-01T00:00:00Z"

#: 0 rpm grid: 30-800 Hz measured (analysis cut at 600 Hz), same step as the rotating grid.
GRID_0RPM = np.linspace(30.0, 800.0, 353)
#: 1000 rpm grid: 30-600 Hz, 262 points (dissertation section 5.7).
GRID_1000RPM = np.linspace(30.0, 600.0, 262)
#: the sideband orders of the version-3 samples
SIDEBANDS = (-2, -1, 1, 2)
#: three-mass grid: 0.5-8 Hz (section 3.4).
GRID_THREE_MASS = np.linspace(0.5, 8.0, 151)


@dataclass(frozen=True)
class Sample:
    """One bundled file: its relative path and how to make it."""

    path: str
    make: Callable[[], Sweep]


def _crack_rig(fault: str | None, speed: float, grid: np.ndarray, seed: int,
               free_running: bool = False, depth: float | None = None,
               sidebands: tuple[int, ...] = ()) -> Callable[[], Sweep]:
    """A crack-rig sample; rotating runs store per-period phasors (shaft harmonics removable), except those with
    ``sidebands`` (the orders measured, format version 3: key-phasor triggered, so the synchronous leak is the
    same in every sweep, and without per-period phasors, to keep the files small); ``free_running``: the shaft
    angle at the start is random (drawn from ``seed``); ``depth``: the breathing crack's depth (fraction of the
    diameter) instead of the truth rig's."""
    def make() -> Sweep:
        truth = load_config(configs_dir() / "crack_rig_truth.yaml")
        if depth is not None and fault is not None:
            faults = dict(truth.faults)
            faults[fault] = truth.faults[fault].model_copy(update={"depth": depth})  # type: ignore[union-attr]
            truth = truth.model_copy(update={"faults": faults})
        angle = shaft_angle_from("random", seed) if free_running else 0.0
        keep = speed != 0.0 and not sidebands
        st = dataclasses.replace(step_settings(truth, keep_periods=keep), sideband_orders=sidebands)
        return simulate_rig(truth, grid, speed, fault=fault, seed=seed, created_utc=CREATED_UTC, settings=st,
                            shaft_angle_rad=angle)

    return make


#: the x/y set (issue 12): forces in x and y at station 8, x and y probes at stations 6 and 2
XY_ACTUATORS = (("8", "x"), ("8", "y"))
XY_SENSORS = (("6", "x"), ("6", "y"), ("2", "x"), ("2", "y"))


def _crack_rig_xy(fault: str | None, speed: float, grid: np.ndarray, seed: int) -> Callable[[], Sweep]:
    """An x/y crack-rig sample (sweep format version 2, one actuator driven at a time), same truth, crack
    and seed as the one-channel sample. Key-phasor triggered (start angle 0) and without per-period
    phasors, to keep the files small: the synchronous leak is then the same in every sweep."""
    def make() -> Sweep:
        truth = load_config(configs_dir() / "crack_rig_truth.yaml")
        acts = [Port(station=int(s), direction=d) for s, d in XY_ACTUATORS]  # type: ignore[arg-type]
        sens = [Port(station=int(s), direction=d) for s, d in XY_SENSORS]  # type: ignore[arg-type]
        return simulate_rig_patterns(truth, grid, acts, sens, speed_rpm=speed, fault=fault, seed=seed,
                                     created_utc=CREATED_UTC, settings=step_settings(truth, keep_periods=False))

    return make


def _three_mass(fault: str | None) -> Callable[[], Sweep]:
    def make() -> Sweep:
        truth = load_config(configs_dir() / "three_mass_truth.yaml")
        return simulate_rig(truth, GRID_THREE_MASS, 0.0, fault=fault, seed=0, created_utc=CREATED_UTC,
                            settings=step_settings(truth, keep_periods=False))

    return make


SAMPLES: tuple[Sample, ...] = (
    Sample("crack_rig/healthy_0rpm.h5", _crack_rig(None, 0.0, GRID_0RPM, seed=101)),
    Sample("crack_rig/open_crack_0rpm.h5", _crack_rig("open_crack", 0.0, GRID_0RPM, seed=102)),
    # seed 108, not 103: with the truth rig of issue 9, seed 103 drew a baseline with a 3.45-sigma point
    # (91.1 Hz; family-wise p = 0.002 against the noiseless truth) that 3 of 40 fresh repeats then flagged
    # (measured detection, 99 %); the bundled baseline shows the typical case, bench/detection_power.py
    # measures the false-alarm rate over fresh pairs
    Sample("crack_rig/healthy_1000rpm.h5", _crack_rig(None, 1000.0, GRID_1000RPM, seed=108)),
    Sample("crack_rig/breathing_crack_1000rpm.h5",
           _crack_rig("breathing_crack", 1000.0, GRID_1000RPM, seed=104)),
    Sample("crack_rig/healthy_1000rpm_repeat.h5", _crack_rig(None, 1000.0, GRID_1000RPM, seed=105)),
    # free-running (random start angle): 1X at 33.3 Hz and 2X at 66.7 Hz (beside mode 1) in band
    Sample("crack_rig/healthy_2000rpm.h5", _crack_rig(None, 2000.0, GRID_1000RPM, seed=106, free_running=True)),
    Sample("crack_rig/healthy_2000rpm_repeat.h5",
           _crack_rig(None, 2000.0, GRID_1000RPM, seed=107, free_running=True)),
    # sidebands f + k x speed (format version 3): a healthy sweep and a breathing crack 10 % of the diameter deep,
    # below what the joint test finds with the bundled ranges (about 11 % in the best element)
    Sample("crack_rig_sidebands/healthy_1000rpm.h5",
           _crack_rig(None, 1000.0, GRID_1000RPM, seed=111, sidebands=SIDEBANDS)),
    Sample("crack_rig_sidebands/breathing_crack_10pct_1000rpm.h5",
           _crack_rig("breathing_crack", 1000.0, GRID_1000RPM, seed=112, depth=0.1, sidebands=SIDEBANDS)),
    Sample("crack_rig_xy/healthy_0rpm.h5", _crack_rig_xy(None, 0.0, GRID_0RPM, seed=101)),
    Sample("crack_rig_xy/open_crack_0rpm.h5", _crack_rig_xy("open_crack", 0.0, GRID_0RPM, seed=102)),
    Sample("crack_rig_xy/healthy_1000rpm.h5", _crack_rig_xy(None, 1000.0, GRID_1000RPM, seed=108)),
    Sample("crack_rig_xy/breathing_crack_1000rpm.h5",
           _crack_rig_xy("breathing_crack", 1000.0, GRID_1000RPM, seed=104)),
    Sample("crack_rig_xy/healthy_1000rpm_repeat.h5", _crack_rig_xy(None, 1000.0, GRID_1000RPM, seed=105)),
    Sample("three_mass/healthy.h5", _three_mass(None)),
    Sample("three_mass/damaged.h5", _three_mass("stiffness_loss")),
)


def write_samples(out_dir: str | Path, force: bool = True) -> list[Path]:
    """Regenerate every sample into ``out_dir``; returns the paths written."""
    out = Path(out_dir)
    written = []
    for s in SAMPLES:
        path = out / s.path
        path.parent.mkdir(parents=True, exist_ok=True)
        write_sweep(s.make(), path, force=force)
        written.append(path)
    return written


def check_samples(sample_dir: str | Path, fresh_dir: str | Path | None = None) -> dict[str, list[str]]:
    """Differences between the bundled files and freshly made ones ({} when all equal); ``fresh_dir``: a
    folder :func:`write_samples` already filled in this session, compared with instead of making them again."""
    problems: dict[str, list[str]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for s in SAMPLES:
            bundled = Path(sample_dir) / s.path
            if not bundled.exists():
                problems[s.path] = ["missing"]
                continue
            if fresh_dir is not None:
                fresh = Path(fresh_dir) / s.path
            else:
                fresh = Path(tmp) / Path(s.path).name
                write_sweep(s.make(), fresh, force=True)
            diff = compare_sweeps(read_sweep(bundled), read_sweep(fresh))
            if diff:
                problems[s.path] = diff
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("dir", nargs="?", default="data_samples")
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    parser.add_argument("--against", default=None,
                        help="with --check: compare with the samples already written to this folder")
    args = parser.parse_args(argv)
    if args.check:
        problems = check_samples(args.dir, args.against)
        for name, diff in problems.items():
            print(f"{name}: {'; '.join(diff[:5])}", file=sys.stderr)
        return 1 if problems else 0
    for p in write_samples(args.dir):
        print(f"wrote {p} ({p.stat().st_size / 1024:.0f} KiB)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
