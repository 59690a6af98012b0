"""A sweep file (one run or several) checked against a baseline: every run matched to the baseline's run at
its speed, detected and diagnosed, and one verdict for the file. The CLI's ``detect``, the fleet and the
bench call :func:`check_sweep`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rotorcheck.baseline import Baseline, read_baselines
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError
from rotorcheck.progress import Progress
from rotorcheck.workflow.detection import EXIT_CODES, DetectionOutcome, baseline_for_speed, check_baseline, detect
from rotorcheck.workflow.detectors import DetectorSettings
from rotorcheck.workflow.locating import locate_damage
from rotorcheck.workflow.measured import MeasuredRun, grid_mismatch, load_rig_and_runs, resample_run

#: the rule of a file's verdict over its runs
FILE_RULE = ("the file: damage if any run is damage, else inconclusive if any run is, else healthy; each run by "
             "its own rule (its report)")


@dataclass
class SweepCheck:
    """The runs of one sweep file against a baseline: ``outcomes`` in the file's run order, each with the
    baseline run it was compared with."""

    sweep: Path
    rig: RigConfig
    rig_file: Path
    baseline_path: Path
    outcomes: list[DetectionOutcome]

    @property
    def verdict(self) -> str:
        """The file's verdict by :data:`FILE_RULE`."""
        verdicts = [o.verdict.verdict for o in self.outcomes]
        return "damage" if "damage" in verdicts else ("inconclusive" if "inconclusive" in verdicts else "healthy")

    @property
    def exit_code(self) -> int:
        """0 healthy, 1 damage, 3 inconclusive."""
        return EXIT_CODES[self.verdict]


def paired_runs(sweep: str | Path, baseline_path: str | Path, rig_path: str | Path | None = None,
                run_id: str | None = None, resample: bool = False, say: Callable[[str], None] | None = None,
                sha256: str | None = None) -> tuple[RigConfig, Path, list[tuple[Baseline, MeasuredRun]]]:
    """The sweep's rig, its file, and each run (``run_id``; else every run) with the baseline's run at its
    speed (one baseline run: that one; several: the closest within the rig's speed tolerance), resampled onto
    the baseline's grid when ``resample`` and the grids differ (``say`` is told), checked against it
    (:func:`check_baseline`)."""
    cfg, rig_file, runs = load_rig_and_runs(sweep, rig_path, baseline_path, run_id, every_run=True)
    bases = read_baselines(baseline_path)
    out = []
    for run in runs:
        base = bases[0] if len(bases) == 1 else baseline_for_speed(bases, cfg, run, baseline_path)
        if resample and base.frequency_hz is not None and grid_mismatch(run.frequency_hz,
                                                                        base.frequency_hz) is not None:
            run = resample_run(run, base.frequency_hz)
            if say is not None:
                say(f"resampled {sweep} ({run.resampled_from} points) onto the baseline's grid "
                    f"({base.frequency_hz.size} points, linear interpolation)")
        out.append((base, check_baseline(base, cfg, run, baseline_path)))
    return cfg, rig_file, out


def detect_pairs(cfg: RigConfig, rig_file: Path, sweep: str | Path, baseline_path: str | Path,
                 pairs: list[tuple[Baseline, MeasuredRun]], rule: str | None = None,
                 settings: DetectorSettings | None = None, locate: bool = False,
                 say: Callable[[str], None] | None = None, progress: Progress | None = None) -> SweepCheck:
    """Each (baseline run, run) of :func:`paired_runs` detected with the detector ``rule`` (None: the default)
    and ``settings``, a damage verdict with where (the ranked candidate elements); with ``locate`` the
    certificates too (``outcome.location``). ``say`` hears progress in words, ``progress`` each element
    ranked or certified (:data:`rotorcheck.progress.Progress`)."""
    s = settings if settings is not None else DetectorSettings()
    if not pairs:
        raise InputError(sweep, "/runs", "no run to check")
    outcomes = []
    for base, run in pairs:
        if say is not None and len(pairs) > 1:
            say(f"run {run.run_id}: detecting against the baseline's run {base.run_id}")
        outcome = detect(cfg, base, run, s.fail_at, s.confidence, rule, s.false_alarm, progress)
        if locate and outcome.verdict.verdict == "damage":
            # the deeper search on detect's own ranking: the same rank 1, with certificates
            prior = outcome.location
            outcome.location = locate_damage(cfg, base, run, s.false_alarm, damage=True,
                                             ranking=None if prior is None else prior.ranking, progress=progress)
        outcomes.append(outcome)
    return SweepCheck(Path(sweep), cfg, rig_file, Path(baseline_path), outcomes)


def check_sweep(sweep: str | Path, baseline_path: str | Path, rig_path: str | Path | None = None,
                run_id: str | None = None, rule: str | None = None, settings: DetectorSettings | None = None,
                resample: bool = False, locate: bool = False, say: Callable[[str], None] | None = None,
                progress: Progress | None = None) -> SweepCheck:
    """A sweep file against a baseline: :func:`paired_runs`, then :func:`detect_pairs`."""
    cfg, rig_file, pairs = paired_runs(sweep, baseline_path, rig_path, run_id, resample, say)
    return detect_pairs(cfg, rig_file, sweep, baseline_path, pairs, rule, settings, locate, say, progress)
