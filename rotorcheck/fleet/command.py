"""``rotorcheck fleet DIR|MANIFEST``: :func:`register` adds the command to the rotorcheck Typer app
(``rotorcheck.fleet.command.register(app)`` in ``rotorcheck/cli.py``, whose ``main`` maps errors to the exit
codes). Exit codes: 0 no alarm, 1 a machine is in alarm, 2 bad input.
Human output on stderr, ``--json`` one document on stdout. Progress on stderr, per sweep with the time elapsed
and the time left (a rich progress bar on a terminal, one line per sweep otherwise); none with ``-q`` or
``--json``."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from rotorcheck.errors import InputError
from rotorcheck.progress import ConsoleSteps

EXIT_OK, EXIT_ALARM = 0, 1


def _err() -> Any:
    return Console(stderr=True, highlight=False, soft_wrap=True)


@contextmanager
def progress_reporter(err: Any, quiet: bool) -> Iterator[Callable[[Any, int, int], None]]:
    """A ``tick(task, done, total)`` for :func:`rotorcheck.fleet.runner.run_fleet` (``done`` 0: the stage
    begins): per stage (detect, locate) the one progress display of the CLI
    (:class:`rotorcheck.progress.ConsoleSteps`: a bar on a terminal, else one line per finished sweep, both with
    the time elapsed and the time left); nothing when ``quiet``."""
    stages: dict[str, ConsoleSteps] = {}

    def tick(task: Any, done: int, total: int) -> None:
        if task.stage not in stages:
            for running in stages.values():  # stages run one after the other: one display at a time
                running.__exit__(None, None, None)
            stages[task.stage] = ConsoleSteps(err, task.stage, quiet, every_s=0.0).__enter__()
        stages[task.stage](done, total, f"{task.machine} {task.time}")

    try:
        yield tick
    finally:
        for running in stages.values():
            running.__exit__(None, None, None)


def fleet(
    source: Annotated[Path, typer.Argument(help="Fleet folder (one folder per machine: rig.yaml, baseline.h5, "
                                                "sweeps/<time>.h5) or a manifest (.csv/.yaml: machine, rig, "
                                                "baseline, sweep[, time]); docs/fleet.md.")],
    out: Annotated[Path | None, typer.Option("--out", help="Results folder (default: <DIR>/results, or results/ "
                                                           "beside the manifest).")] = None,
    workers: Annotated[int | None, typer.Option("--workers", help="Worker processes (default: the cores).")] = None,
    serial: Annotated[bool, typer.Option("--serial", help="Run every task in this process.")] = False,
    dask: Annotated[bool, typer.Option("--dask", help="Run on a Dask LocalCluster of --workers processes.")] = False,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", help="Run on the Dask cluster at this address (e.g. tcp://host:8786); paths must be the "
                            "same on its workers.")] = None,
    limit: Annotated[str | None, typer.Option(
        "--limit", help="Prognosis limit of the low-frequency stiffness change Re D_u: N/m (e.g. 500) or % of "
                        "the damage port's static stiffness (e.g. 0.5%).")] = None,
    confirm: Annotated[int, typer.Option("--confirm", help="Damage verdicts in a row that make an alarm.")] = 2,
    locate: Annotated[str, typer.Option(
        "--locate", help="latest (each machine's latest sweep when damaged) | all (every damaged sweep) | none.")
    ] = "latest",
    confidence: Annotated[float, typer.Option(help="Family-wise confidence of measured detection.")] = 0.99,
    false_alarm: Annotated[float, typer.Option("--false-alarm", help="False-alarm probability per sweep.")] = 0.01,
    low_band: Annotated[float | None, typer.Option(
        "--low-band", help="Upper end (Hz) of the low band of the stiffness figure (default: 0.8 x the frequency "
                           "of the healthy FRF's peak).")] = None,
    trend_confidence: Annotated[float, typer.Option("--trend-confidence", help="Confidence of the trend's "
                                                                                "intervals.")] = 0.95,
    force: Annotated[bool, typer.Option("--force", help="Recompute every sweep's result.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON document on stdout (no progress).")
                       ] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress on stderr.")] = False,
) -> int:
    """A fleet over time: every new sweep against its machine's baseline (skipping those done, by sha256),
    damages located, one summary table (CSV, HDF5), an alert list, per-machine trends with the time to a
    limit, and index.html. Exit 1 when a machine is in alarm."""
    from rotorcheck.fleet.runner import FleetOptions, run_fleet  # lazy: the runner (numpy) only when the command runs
    from rotorcheck.fleet.summary import render_alerts_text  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.fleet.tasks import Settings  # lazy: the tasks (numpy) only when the command runs

    err = _err()
    if serial and (dask or scheduler):
        raise InputError(None, "--serial", "cannot be combined with --dask or --scheduler")
    executor = "dask" if (dask or scheduler) else ("serial" if serial else "processes")
    opts = FleetOptions(out=out, executor=executor, workers=workers, scheduler=scheduler,
                        settings=Settings(confidence, false_alarm, low_band), locate=locate, confirm=confirm,
                        limit=limit, trend_confidence=trend_confidence, force=force)

    silent = quiet or as_json

    def log(text: str) -> None:
        if not silent:
            err.print(text)

    with progress_reporter(err, silent) as tick:
        res = run_fleet(source, opts, log, tick)
    what = ("nothing new: every sweep's result exists, outputs up to date" if res.up_to_date else
            f"detected {res.n_detected} sweeps, located {res.n_located}")
    err.print(f"{res.n_machines} machines, {res.n_sweeps} sweeps: {what} ({res.seconds:.2f} s); results in {res.out}")
    sys.stderr.write(render_alerts_text(res.alerts))
    if not res.up_to_date:
        err.print(f"wrote {res.out / 'summary.csv'}, summary.h5, alerts.json, trends.json, index.html")
    if as_json:
        from rotorcheck.report.reports import render_json  # lazy: keeps `rotorcheck --help` start-up light

        sys.stdout.write(render_json(res.to_dict()))
        sys.stdout.flush()
    return EXIT_ALARM if any(a["level"] == "alarm" for a in res.alerts) else EXIT_OK


def register(app: typer.Typer) -> None:
    """Add ``fleet`` to ``app`` (the rotorcheck CLI)."""
    app.command("fleet")(fleet)
