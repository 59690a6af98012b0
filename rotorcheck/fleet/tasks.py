"""One idempotent task per sweep: detect against the machine's baseline (or locate a damage), written
atomically to ``<results>/<machine>/<sweep sha256[:16]>/``.

A task builds its result in a temporary folder beside the final one (``.<key>.<token>.tmp``): the
reports (:func:`rotorcheck.report.reports.write_reports`), ``row.json`` (the summary's figures) and last a
``DONE`` marker; then the folder is renamed onto its final name (``os.replace``, atomic on one file
system). A result folder therefore exists complete or not at all; a task run again (a retry after a
killed worker, a second run, a second scheduler) finds it and returns it without detecting again; two
copies racing each other both finish, and the second rename fails on the first's folder, whose result
is returned (never two results for one sweep). The locate stage writes ``location/`` inside the
result folder the same way.

Detection and location are the library's (:func:`rotorcheck.workflow.check_baseline`,
:func:`~rotorcheck.workflow.detect`, :func:`~rotorcheck.workflow.locate_damage`), with the same
defaults as ``rotorcheck detect`` and ``rotorcheck locate``.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.errors import InputError, UserInputError
from rotorcheck.fileio import atomic_write_text, publish_dir, temp_dir_beside
from rotorcheck.report.reports import render_json, write_reports
from rotorcheck.report.schema import DetectionReport, LocationReport

DONE = "DONE"
ROW_FILE = "row.json"
LOCATION_DIR = "location"
#: the low band of the stiffness figure: points below this fraction of the frequency of the healthy
#: FRF's largest magnitude (its first resonance on a rotor rig's receptance)
LOW_BAND_FRACTION = 0.8
ROW_VERSION = 1


@dataclass(frozen=True)
class Settings:
    """What a result depends on besides the sweep and the baseline (a change re-runs the task)."""

    confidence: float = 0.99
    false_alarm: float = 0.01
    low_band_hz: float | None = None  # upper end of the low band, Hz (None: LOW_BAND_FRACTION of the peak)


@dataclass(frozen=True)
class SweepTask:
    """One sweep of one machine to detect (``stage="detect"``) or to locate (``stage="locate"``)."""

    machine: str
    time: str
    sweep: str
    sweep_sha256: str
    rig: str
    baseline: str
    baseline_sha256: str
    results: str
    settings: Settings = Settings()
    stage: str = "detect"
    force: bool = False  # recompute even when a finished result exists
    kill_marker: str = ""  # testing hook: the first attempt (no marker yet) kills its own process mid-task

    @property
    def key(self) -> str:
        return self.sweep_sha256[:16]

    @property
    def result_dir(self) -> Path:
        return Path(self.results) / self.machine / self.key

    @property
    def task_key(self) -> str:
        """A name unique to this task (a scheduler's key: a retry is the same task)."""
        return f"fleet-{self.stage}-{self.machine}-{self.key}"


def _is_current(row: dict[str, Any], task: SweepTask) -> bool:
    return (row.get("row_version") == ROW_VERSION and row.get("baseline_sha256") == task.baseline_sha256
            and row.get("settings") == asdict(task.settings))


def _finished_json(folder: Path, name: str) -> dict[str, Any] | None:
    """The JSON file ``name`` of a finished (``DONE``) result folder; None when unfinished or unreadable."""
    if not (folder / DONE).exists():
        return None
    try:
        doc: dict[str, Any] = json.loads((folder / name).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return doc


def read_row(result_dir: Path) -> dict[str, Any] | None:
    """The finished result's row (None: no finished result there)."""
    return _finished_json(result_dir, ROW_FILE)


def is_done(task: SweepTask) -> bool:
    """A finished, current result exists for ``task`` (cheap: two small reads, no numerics)."""
    if task.stage == "locate":
        return (task.result_dir / LOCATION_DIR / DONE).exists()
    row = read_row(task.result_dir)
    return row is not None and _is_current(row, task)


def _maybe_die(task: SweepTask, tmp: Path) -> None:
    """Testing hook: on the first attempt (the marker file does not exist yet) leave a half-written result
    and kill this process as a crashed worker would (no cleanup, no exception)."""
    if not task.kill_marker:
        return
    try:
        fd = os.open(task.kill_marker, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    except FileExistsError:
        return
    os.write(fd, f"{os.getpid()} {task.task_key}\n".encode())
    os.close(fd)
    (tmp / "report.json").write_text("{ half", encoding="utf-8")
    os._exit(17)


def low_band(frequency_hz: Any, healthy_frf: Any, low_band_hz: float | None) -> Any:
    """Mask of the low band's points: below ``low_band_hz`` or, by default, below
    :data:`LOW_BAND_FRACTION` of the frequency where the healthy FRF is largest (at least 2 points)."""
    f = np.asarray(frequency_hz, dtype=float)
    if low_band_hz is None:
        mag = np.abs(np.asarray(healthy_frf).reshape(f.size, -1)[:, 0])
        low_band_hz = LOW_BAND_FRACTION * float(f[int(np.argmax(mag))])
    mask = f <= low_band_hz
    if np.count_nonzero(mask) < 2:
        mask = np.zeros(f.size, dtype=bool)
        mask[: min(2, f.size)] = True
    return mask


def stiffness_figure(report: DetectionReport, mask: Any) -> dict[str, Any]:
    """The low-frequency stiffness change at the damage port: the mean of the anchored Re D_u over the low
    band's points (N/m, positive: a stiffness loss), its standard error from the points' scatter
    (sample std / sqrt(n), N/m) and the medians of the anchored bound on |D_u| there (N/m)."""
    out: dict[str, Any] = {"du_low_re_n_per_m": None, "du_low_se_n_per_m": None, "du_low_points": 0,
                           "du_low_band_max_hz": None, "du_low_bound_min_abs_n_per_m": None,
                           "du_low_bound_max_abs_n_per_m": None}
    if report.damage_dynamics_anchored_re is None:
        return out
    f = np.asarray(report.frequency_hz, dtype=float)[mask]
    re = np.asarray(report.damage_dynamics_anchored_re, dtype=float)[mask]
    ok = np.isfinite(re)
    if np.count_nonzero(ok) < 2:
        return out
    lo = np.asarray(report.damage_anchored_bound_min_abs, dtype=float)[mask][ok]
    hi = np.asarray(report.damage_anchored_bound_max_abs, dtype=float)[mask][ok]
    n = int(np.count_nonzero(ok))
    out.update(du_low_re_n_per_m=float(np.mean(re[ok])), du_low_se_n_per_m=float(np.std(re[ok], ddof=1) / np.sqrt(n)),
               du_low_points=n, du_low_band_max_hz=float(np.max(f[ok])),
               du_low_bound_min_abs_n_per_m=float(np.median(lo)), du_low_bound_max_abs_n_per_m=float(np.median(hi)))
    return out


def _num(x: Any) -> float | None:
    if x is None:
        return None
    v = float(x)
    return v if math.isfinite(v) else None


def _row_head(task: SweepTask) -> dict[str, Any]:
    """What every row starts with: the version, the sweep and what its result depends on."""
    return {"row_version": ROW_VERSION, "machine": task.machine, "time": task.time, "sweep": task.sweep,
            "sweep_sha256": task.sweep_sha256, "baseline_sha256": task.baseline_sha256,
            "settings": asdict(task.settings)}


def summary_row(task: SweepTask, report: DetectionReport, mask: Any) -> dict[str, Any]:
    """The summary's figures of one detection report (plain JSON types)."""
    interval: list[float | None] = [None, None]
    if report.stiffness_loss_interval:
        interval = [*report.stiffness_loss_interval]
    row: dict[str, Any] = {
        **_row_head(task), "verdict": report.verdict, "verdict_reason": report.verdict_reason, "error": "",
        "n_fault_points": int(report.n_fault_points), "n_points": int(report.n_points),
        "speed_rpm": float(report.speed_rpm), "joint_statistic": _num(report.joint_statistic),
        "joint_threshold": _num(report.joint_threshold), "joint_p_value": _num(report.joint_p_value),
        **stiffness_figure(report, mask),
        "benign_parameters": [{"name": b["name"], "estimate": _num(b["estimate"]), "unit": b["unit"],
                               "interval": [_num(b["interval"][0]), _num(b["interval"][1])],
                               "at_range_edge": bool(b.get("at_range_edge", False))}
                              for b in report.benign_parameters or []],
        "joint_best_element": report.joint_best_element, "stiffness_loss": _num(report.stiffness_loss),
        "stiffness_loss_lo": _num(interval[0]), "stiffness_loss_hi": _num(interval[1]),
        # the diagnosis's where (damage verdicts: the ranked elements); the locate stage's certified one replaces it
        "location_best_element": report.best_element,
        "location_summary": "" if report.verdict != "damage" or report.location is None
        else report.location.summary(),
    }
    return row


def error_row(task: SweepTask, message: str) -> dict[str, Any]:
    """The row of a sweep that could not be checked (bad input): verdict 'error' with the message."""
    return {**_row_head(task), "verdict": "error", "verdict_reason": message, "error": message,
            "benign_parameters": []}


def _inputs(task: SweepTask) -> tuple[Any, Any, Any, Any]:
    """``(rig, rig file, baseline, run)`` of a task: the sweep's one run (a fleet sweep is one run: one speed per
    sweep, one row per sweep) with the baseline's run at its speed, checked (the library's
    :func:`rotorcheck.workflow.paired_runs`, as ``rotorcheck detect``)."""
    from rotorcheck import workflow  # lazy: the pipeline only in the task's worker

    cfg, rig_file, pairs = workflow.paired_runs(task.sweep, task.baseline, task.rig, sha256=task.sweep_sha256)
    if len(pairs) != 1:
        raise InputError(task.sweep, "/runs", f"{len(pairs)} runs: a fleet sweep holds one run (one file per run)")
    base, run = pairs[0]
    return cfg, rig_file, base, run


def _detect(task: SweepTask) -> tuple[dict[str, Any], DetectionReport | None]:
    """(row, report) of the sweep against its machine's baseline: the library's
    :func:`rotorcheck.workflow.detect_pairs`, as ``rotorcheck detect``."""
    from rotorcheck import workflow  # lazy: the pipeline only in the task's worker
    from rotorcheck.fe.blas import one_blas_thread  # lazy: threadpoolctl only in the task's worker

    with one_blas_thread():
        cfg, rig_file, base, mrun = _inputs(task)
        s = task.settings
        check = workflow.detect_pairs(cfg, rig_file, task.sweep, task.baseline, [(base, mrun)],
                                      settings=workflow.DetectorSettings(s.confidence, s.false_alarm))
        report = check.outcomes[0].typed_report()
    healthy = base.healthy_frf if base.healthy_frf is not None else mrun.frf
    report.baseline = task.baseline
    return summary_row(task, report, low_band(mrun.frequency_hz, healthy, s.low_band_hz)), report


def run_detect(task: SweepTask) -> dict[str, Any]:
    """Detect one sweep (idempotent): ``{"row": ..., "executed": bool}``; ``executed`` is False when a
    finished, current result was found (or another copy of the task published first)."""
    final = task.result_dir
    if not task.force:
        row = read_row(final)
        if row is not None and _is_current(row, task):
            return {"row": row, "executed": False}
    tmp = temp_dir_beside(final)
    try:
        _maybe_die(task, tmp)
        try:
            row, report = _detect(task)
        except UserInputError as exc:  # a bad sweep is the fleet's news, not the end of the night's run
            row, report = error_row(task, str(exc)), None
        if report is not None:
            write_reports(report, tmp, [])
        atomic_write_text(tmp / ROW_FILE, json.dumps(row, sort_keys=True, indent=1) + "\n")
        atomic_write_text(tmp / DONE, task.task_key + "\n")
        stale = final.exists() and (task.force or not is_done(task))
        if not publish_dir(tmp, final, replace=stale):
            return {"row": read_row(final), "executed": False}
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return {"row": row, "executed": True}


def run_locate(task: SweepTask) -> dict[str, Any]:
    """Locate one damaged sweep (idempotent): ``<result>/location/location.json``; returns
    ``{"location": doc, "executed": bool}``."""
    final = task.result_dir / LOCATION_DIR
    done = final / DONE
    if done.exists() and not task.force:
        return {"location": read_location(task.result_dir), "executed": False}
    from rotorcheck import workflow  # lazy: the pipeline only in the task's worker
    from rotorcheck.fe.blas import one_blas_thread  # lazy: threadpoolctl only in the task's worker

    tmp = temp_dir_beside(final)
    try:
        _maybe_die(task, tmp)
        with one_blas_thread():
            cfg, _, base, mrun = _inputs(task)
            # only damaged sweeps are located: the detector's verdict is the row's (no second detection)
            res = workflow.locate_damage(cfg, base, mrun, task.settings.false_alarm, damage=True)
        report = LocationReport(task.sweep, task.sweep_sha256, task.baseline, cfg.rig_id, mrun.speed_rpm, res)
        atomic_write_text(tmp / "location.json", render_json(report.to_json()))
        atomic_write_text(tmp / DONE, task.task_key + "\n")
        if not publish_dir(tmp, final, replace=task.force):
            return {"location": read_location(task.result_dir), "executed": False}
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    best = res.best
    return {"location": {"best_element": None if best is None else best.element, "summary": res.summary()},
            "executed": True}


def read_location(result_dir: Path) -> dict[str, Any] | None:
    """``{"best_element", "summary"}`` of a finished location of a result, else None."""
    doc = _finished_json(result_dir / LOCATION_DIR, "location.json")
    return None if doc is None else {"best_element": doc.get("best_element"), "summary": doc.get("summary", "")}


def run_task(task: SweepTask) -> dict[str, Any]:
    """The task by its stage (the one function a process pool or a Dask worker runs)."""
    return run_locate(task) if task.stage == "locate" else run_detect(task)


def clean_temporaries(results: Path) -> int:
    """Remove temporary folders left by killed tasks (``.*.tmp``, ``.*.old`` under each machine's results
    and their location folders); call only when no task of this results folder runs. Returns the count."""
    n = 0
    if not results.is_dir():
        return 0
    for machine in results.iterdir():
        if not machine.is_dir():
            continue
        for parent in [machine, *(p / "" for p in machine.iterdir() if p.is_dir() and not p.name.startswith("."))]:
            for d in parent.iterdir() if parent.is_dir() else []:
                if d.is_dir() and d.name.startswith(".") and d.name.endswith((".tmp", ".old")):
                    shutil.rmtree(d, ignore_errors=True)
                    n += 1
    return n
