"""Run a fleet: find the new sweeps, run their tasks serially, on local processes or on Dask, then write the
summary, the alert list, the trends and the HTML index.

Executors (:class:`FleetOptions.executor`): ``serial`` (this process), ``processes`` (the default:
:class:`concurrent.futures.ProcessPoolExecutor`, ``workers`` default the number of cores; a pool broken
by a dead worker is replaced and the unfinished tasks run again) and ``dask`` (``scheduler`` an address:
``distributed.Client(address)``; else a ``distributed.LocalCluster`` of ``workers`` processes with one
thread each). Every task is idempotent and publishes its result atomically (:mod:`rotorcheck.fleet.tasks`),
so retries never duplicate or corrupt a result, and the summary is read back from the result folders:
the same whatever ran the tasks.

The "nothing new" path (every task finished, same options as the last run) reads only the folder tree,
the hash index and the small ``row.json`` files: no numerics are imported and no output is rewritten.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import secrets
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from rotorcheck.errors import InputError, check_choice, finite_positive, in_open_unit
from rotorcheck.fileio import atomic_write_text
from rotorcheck.fleet import summary
from rotorcheck.fleet.index import HashIndex
from rotorcheck.fleet.layout import Fleet, discover
from rotorcheck.fleet.tasks import (
    Settings,
    SweepTask,
    clean_temporaries,
    is_done,
    read_location,
    read_row,
    run_task,
)
from rotorcheck.fleet.trend import machine_trend

EXECUTORS = ("serial", "processes", "dask")
LOCATE_MODES = ("latest", "all", "none")
STATE_FILE = "state.json"
OUTPUTS = ("summary.csv", "summary.h5", "alerts.json", "alerts.txt", "trends.json", "index.html")
INSTALL_HINT = "needs Dask distributed: pip install 'rotorcheck[fleet]'"


@dataclass
class FleetOptions:
    """How to run a fleet (the ``rotorcheck fleet`` options)."""

    out: Path | None = None  # results folder (default: <DIR>/results, or results/ beside the manifest)
    executor: str = "processes"
    workers: int | None = None  # default: the number of cores
    scheduler: str | None = None  # a Dask scheduler's address (executor "dask")
    settings: Settings = field(default_factory=Settings)
    locate: str = "latest"  # locate the latest damaged sweep of each machine | every damaged sweep | none
    confirm: int = 2  # damage verdicts in a row that make an alarm
    limit: str | None = None  # "500" (N/m) or "2%" (of the damage port's static stiffness)
    trend_confidence: float = 0.95
    force: bool = False  # recompute every result
    kill_marker: str = ""  # testing hook (tasks.SweepTask.kill_marker)


@dataclass
class FleetResult:
    """What a run did and found."""

    out: Path
    n_machines: int
    n_sweeps: int
    n_detected: int  # detect tasks executed in this run (0: every result reused)
    n_located: int
    rows_by_machine: dict[str, list[dict[str, Any]]]
    alerts: list[dict[str, Any]]
    trends: dict[str, Any]
    files: list[Path]
    up_to_date: bool  # nothing new and the same options: no output rewritten
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"out": str(self.out), "n_machines": self.n_machines, "n_sweeps": self.n_sweeps,
                "n_detected": self.n_detected, "n_located": self.n_located, "up_to_date": self.up_to_date,
                "alerts": self.alerts, "files": [str(p) for p in self.files], "seconds": self.seconds}


def default_out(source: Path) -> Path:
    return source / "results" if source.is_dir() else source.parent / "results"


def check_options(opts: FleetOptions) -> None:
    """Refuse bad options (InputError naming the option) before any work."""
    check_choice(opts.executor, EXECUTORS, "--executor")
    if opts.workers is not None and opts.workers < 1:
        raise InputError(None, "--workers", f"must be >= 1, got {opts.workers}")
    check_choice(opts.locate, LOCATE_MODES, "--locate")
    if opts.confirm < 1:
        raise InputError(None, "--confirm", f"must be >= 1, got {opts.confirm}")
    s = opts.settings
    for name, v in (("--confidence", s.confidence), ("--false-alarm", s.false_alarm),
                    ("--trend-confidence", opts.trend_confidence)):
        in_open_unit(v, name)
    finite_positive(s.low_band_hz, "--low-band")
    parse_limit(opts.limit)
    if opts.executor == "dask" or opts.scheduler:
        try:
            import distributed  # noqa: F401  # lazy: optional (the 'fleet' extra): only with --dask or --scheduler
        except ImportError:
            raise InputError(None, "--scheduler" if opts.scheduler else "--dask", INSTALL_HINT) from None


def parse_limit(text: str | None) -> tuple[float, str] | None:
    """``"500"`` -> (500.0, "N/m"); ``"2%"`` -> (2.0, "%") (of the damage port's static stiffness)."""
    if text is None or not str(text).strip():
        return None
    s = str(text).strip().replace(" ", "")
    unit = "%" if s.endswith("%") else "N/m"
    num = s[:-1] if unit == "%" else (s[: -len("N/m")] if s.endswith("N/m") else s)
    try:
        v = float(num)
    except ValueError:
        raise InputError(None, "--limit", f"{text!r}: a stiffness change in N/m (e.g. 500) or in % of the damage "
                         "port's static stiffness (e.g. 2%)") from None
    if not v > 0:
        raise InputError(None, "--limit", f"must be > 0, got {text!r}")
    return v, unit


def plan(fleet: Fleet, index: HashIndex, out: Path, opts: FleetOptions) -> list[SweepTask]:
    """A detect task for every sweep of the fleet (finished or not), machine by machine in time order."""
    tasks = []
    for m in fleet.machines:
        base_sha = index.sha256(m.baseline)
        for s in m.sweeps:
            sha = index.sha256(s.path, s.time)
            tasks.append(SweepTask(machine=m.name, time=s.time, sweep=str(s.path.resolve()), sweep_sha256=sha,
                                   rig=str(m.rig.resolve()), baseline=str(m.baseline.resolve()),
                                   baseline_sha256=base_sha, results=str(out.resolve()), settings=opts.settings,
                                   force=opts.force, kill_marker=opts.kill_marker))
    return tasks


def _same_sweep_twice(tasks: list[SweepTask]) -> None:
    seen: dict[tuple[str, str], SweepTask] = {}
    for t in tasks:
        k = (t.machine, t.key)
        if k in seen:
            raise InputError(t.sweep, "", f"the same file content as {seen[k].sweep} (sha256 {t.key}) in machine "
                             f"{t.machine!r}: one sweep, two times")
        seen[k] = t


# --------------------------------------------------------------------------------------------
# executors


#: called after each finished task: ``(task, finished so far, tasks in all)``; with 0 finished when a stage
#: (detect, locate) begins
Tick = Callable[[SweepTask, int, int], None]


def _no_tick(task: SweepTask, done: int, total: int) -> None:
    return None


def _serial(tasks: list[SweepTask], log: Callable[[str], None], tick: Tick = _no_tick) -> list[dict[str, Any]]:
    out = []
    for k, t in enumerate(tasks, 1):
        out.append(run_task(t))
        tick(t, k, len(tasks))
    return out


def _processes(tasks: list[SweepTask], workers: int, log: Callable[[str], None], tick: Tick = _no_tick
               ) -> list[dict[str, Any]]:
    """A process pool; a pool broken by a dead worker is replaced and the unfinished tasks run again
    (at most 3 pools)."""
    from concurrent.futures import ProcessPoolExecutor, as_completed  # lazy: only for the local process pool
    from concurrent.futures.process import BrokenProcessPool  # lazy: only for the local process pool

    results: dict[str, dict[str, Any]] = {}
    todo = list(tasks)
    for attempt in range(3):
        try:
            with ProcessPoolExecutor(max_workers=max(1, min(workers, len(todo)))) as ex:
                futs = {ex.submit(run_task, t): t for t in todo}
                for fut in as_completed(futs):
                    t = futs[fut]
                    results[t.task_key] = fut.result()
                    tick(t, len(results), len(tasks))
            break
        except BrokenProcessPool:
            todo = [t for t in todo if t.task_key not in results]
            log(f"a worker process died: {len(todo)} tasks again in a new pool (attempt {attempt + 2})")
    else:
        raise RuntimeError("the process pool broke three times")
    return [results[t.task_key] for t in tasks]


#: seconds to connect to a --scheduler before giving up (an InputError naming --scheduler)
SCHEDULER_TIMEOUT_S = 10.0


def _dask(tasks: list[SweepTask], workers: int, scheduler: str | None, log: Callable[[str], None],
          tick: Tick = _no_tick) -> list[dict[str, Any]]:
    """Dask distributed: a client of ``scheduler``, else of a LocalCluster (``workers`` processes, one thread
    each). A task whose worker died is rescheduled by Dask; a task that raised is retried twice."""
    import logging  # lazy: logging only for a Dask LocalCluster's log level

    from distributed import Client, LocalCluster, as_completed  # lazy: optional (the 'fleet' extra): only with Dask

    cluster = None
    if scheduler:
        try:
            client = Client(scheduler, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as exc:  # unreachable, refused, no such address
            raise InputError(None, "--scheduler", f"cannot reach a Dask scheduler at {scheduler!r} within "
                             f"{SCHEDULER_TIMEOUT_S:g} s ({type(exc).__name__}: {exc})") from None
    else:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR)
        client = Client(cluster)
    token = secrets.token_hex(4)
    try:
        futs = client.map(run_task, tasks, key=[f"{t.task_key}-{token}" for t in tasks], retries=2)
        by_key = {f.key: t for f, t in zip(futs, tasks)}
        results: dict[str, dict[str, Any]] = {}
        for fut in as_completed(futs):
            t = by_key[fut.key]
            results[t.task_key] = fut.result()
            tick(t, len(results), len(tasks))
        return [results[t.task_key] for t in tasks]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def execute(tasks: list[SweepTask], opts: FleetOptions, log: Callable[[str], None] = lambda s: None,
            tick: Tick = _no_tick) -> list[dict[str, Any]]:
    """Run ``tasks`` on the chosen executor; their results in the order of ``tasks``; ``tick`` after each
    finished task (progress), ``log`` for what else happens (a worker that died)."""
    if not tasks:
        return []
    tick(tasks[0], 0, len(tasks))  # the stage begins
    workers = opts.workers or os.cpu_count() or 1
    if opts.executor == "dask" or opts.scheduler:
        return _dask(tasks, workers, opts.scheduler, log, tick)
    if opts.executor == "serial":
        return _serial(tasks, log, tick)
    return _processes(tasks, workers, log, tick)


# --------------------------------------------------------------------------------------------
# the run


def _locate_tasks(rows: dict[str, list[tuple[SweepTask, dict[str, Any]]]], mode: str) -> list[SweepTask]:
    """Locate tasks for damaged sweeps without a location: each machine's latest sweep when it is damage
    (``latest``) or every damaged sweep (``all``)."""
    if mode == "none":
        return []
    out = []
    for items in rows.values():
        pick = items[-1:] if mode == "latest" else items
        for t, row in pick:
            # (with --force the detection was recomputed and its folder replaced: the location is gone too)
            if row.get("verdict") == "damage" and read_location(t.result_dir) is None:
                out.append(dataclasses.replace(t, stage="locate", force=False))
    return out


def _fingerprint(tasks: list[SweepTask], merged: dict[str, list[dict[str, Any]]], opts: FleetOptions) -> str:
    """What the outputs depend on: the tasks, the results located, the options."""
    doc = {"tasks": [[t.machine, t.time, t.sweep_sha256, t.baseline_sha256] for t in tasks],
           "located": sorted(r["result"] for items in merged.values() for r in items if r.get("location_summary")),
           "settings": asdict(opts.settings), "locate": opts.locate, "confirm": opts.confirm, "limit": opts.limit,
           "trend_confidence": opts.trend_confidence}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def _limits(fleet: Fleet, rows: dict[str, list[dict[str, Any]]], limit: tuple[float, str] | None
            ) -> tuple[dict[str, float | None], str]:
    """The limit per machine in N/m (a % of the damage port's static stiffness per machine's rig) and words."""
    if limit is None:
        return dict.fromkeys(rows), "none set: --limit"
    value, unit = limit
    if unit == "N/m":
        return dict.fromkeys(rows, value), f"{value:.4g} N/m of the low-frequency Re D_u"
    from rotorcheck import workflow  # lazy: the pipeline only for a limit in % of a rig's stiffness

    out: dict[str, float | None] = {}
    for m in fleet.machines:
        speed = next((r["speed_rpm"] for r in rows.get(m.name, []) if r.get("speed_rpm") is not None), 0.0)
        out[m.name] = value / 100.0 * workflow.port_static_stiffness(workflow.load_rig(m.rig), float(speed))
    return out, (f"{value:g} % of each machine's damage-port static stiffness (nominal model): "
                 + ", ".join(f"{k} {v:.4g} N/m" for k, v in sorted(out.items()) if v is not None))


def run_fleet(source: str | Path, opts: FleetOptions | None = None, log: Callable[[str], None] = lambda s: None,
              tick: Tick = _no_tick) -> FleetResult:
    """Detect every new sweep of the fleet at ``source`` (a folder or a manifest), locate damages, and write
    the summary, alerts, trends and index.html into the results folder (:mod:`rotorcheck.fleet`); ``tick``
    after each finished task (its stage, machine and time; the count done and in all), ``log`` for the
    stages in words."""
    t_start = time.perf_counter()
    opts = opts or FleetOptions()
    check_options(opts)
    src = Path(source)
    out = Path(opts.out) if opts.out is not None else default_out(src)
    index = HashIndex(out)
    fleet = discover(src, index.times(), skip=out)
    out.mkdir(parents=True, exist_ok=True)
    tasks = plan(fleet, index, out, opts)
    index.save()
    _same_sweep_twice(tasks)
    pending = [t for t in tasks if opts.force or not is_done(t)]
    log(f"{len(fleet.machines)} machines, {len(tasks)} sweeps: {len(pending)} to detect")
    executed = execute(pending, opts, log, tick)
    n_detected = sum(1 for r in executed if r.get("executed"))
    rows: dict[str, list[tuple[SweepTask, dict[str, Any]]]] = {m.name: [] for m in fleet.machines}
    for t in tasks:
        row = read_row(t.result_dir)
        if row is None:
            raise RuntimeError(f"no result for {t.sweep} after its task ran ({t.result_dir})")
        rows[t.machine].append((t, row))
    loc_tasks = _locate_tasks(rows, opts.locate)
    if loc_tasks:
        log(f"locating {len(loc_tasks)} damaged sweeps")
    n_located = sum(1 for r in execute(loc_tasks, opts, log, tick) if r.get("executed"))
    merged: dict[str, list[dict[str, Any]]] = {}
    for name, items in rows.items():
        merged[name] = []
        for t, row in items:
            loc = read_location(t.result_dir)
            if loc is not None:
                row = {**row, "location_best_element": loc["best_element"], "location_summary": loc["summary"]}
            merged[name].append({**row, "result": f"{t.machine}/{t.key}"})
    clean_temporaries(out)
    fp = _fingerprint(tasks, merged, opts)
    state_path = out / STATE_FILE
    try:
        state = json.loads(state_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        state = {}
    n_sweeps = len(tasks)
    if state.get("fingerprint") == fp and all((out / f).exists() for f in OUTPUTS) and not (n_detected or n_located):
        alerts = json.loads((out / "alerts.json").read_text(encoding="utf-8"))["alerts"]
        return FleetResult(out, len(fleet.machines), n_sweeps, 0, 0, merged, alerts, {}, [], True,
                           time.perf_counter() - t_start)
    log(f"writing the summary, the trends and index.html ({len(merged)} trend plots)")
    files, alerts, trends = write_outputs(fleet, merged, opts, out)
    atomic_write_text(state_path, json.dumps({"fingerprint": fp}) + "\n")
    return FleetResult(out, len(fleet.machines), n_sweeps, n_detected, n_located, merged, alerts, trends, files,
                       False, time.perf_counter() - t_start)


def write_outputs(fleet: Fleet, rows: dict[str, list[dict[str, Any]]], opts: FleetOptions, out: Path
                  ) -> tuple[list[Path], list[dict[str, Any]], dict[str, Any]]:
    """Trends, alerts, the summary table, the trend plots and index.html."""
    from rotorcheck.fleet import html  # lazy: matplotlib (the trend plots) only when writing the outputs

    limits, limit_text = _limits(fleet, rows, parse_limit(opts.limit))
    trends = {m: machine_trend(m, r, limits.get(m), opts.trend_confidence) for m, r in rows.items()}
    entries = summary.alerts(rows, trends, opts.confirm, opts.settings.false_alarm, limits)
    flat = [r for m in sorted(rows) for r in rows[m]]
    files = summary.write_summary(flat, out)
    files.append(summary.write_trends(trends, out))
    rules = summary.rule_texts(opts.confirm, opts.settings.false_alarm, limit_text, opts.trend_confidence)
    files += summary.write_alerts(entries, out, rules)
    meta = {"source": str(fleet.source), "n_machines": len(fleet.machines), "n_sweeps": len(flat), "rules": rules,
            "limit_text": limit_text}
    files += html.write_index(out, rows, trends, entries, meta)
    return files, entries, trends
