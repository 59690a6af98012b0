"""Command line: a thin layer over the library (see ``../shared/spec/cli.md``).

Human summaries go to stderr; ``--json`` prints one JSON document on stdout and nothing else there.
Exit codes: 0 ok / no damage, 1 damage detected (detect only), 2 unusable input or failure,
3 inconclusive. An unexpected exception is 2, never 1.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from rotorcheck.errors import InputError

EXIT_OK, EXIT_DAMAGE, EXIT_INPUT, EXIT_INCONCLUSIVE = 0, 1, 2, 3

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Has this shaft changed, where in the spectrum, and what exactly changed?",
)
err = Console(stderr=True, highlight=False)

RigOpt = Annotated[
    Path | None,
    typer.Option("--rig", help="Rig YAML (default: the bundled rig named by the sweep's rig_id)."),
]
OutOpt = Annotated[Path, typer.Option("--out", help="Output folder (created).")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON document on stdout.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Overwrite existing outputs.")]
DEFAULT_OUT = Path("rotorcheck-out")


def _emit_json(doc: dict[str, Any]) -> None:
    sys.stdout.write(json.dumps(doc, indent=2, allow_nan=True, default=_json_default) + "\n")
    sys.stdout.flush()


def _json_default(obj: Any) -> Any:
    import numpy as np

    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serializable: {type(obj).__name__}")


# --------------------------------------------------------------------------------------------
# commands


@app.command()
def model(
    rig: Annotated[Path | None, typer.Argument(help="Rig YAML (default: configs/crack_rig.yaml).")] = None,
    speed: Annotated[float, typer.Option("--speed", help="Spin speed, rpm.")] = 0.0,
    out: OutOpt = DEFAULT_OUT,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
    plots: Annotated[bool, typer.Option(help="Write Campbell and mode-shape plots.")] = True,
) -> int:
    """Natural frequencies, damping, whirl and critical speeds; Campbell and mode-shape plots."""
    from rotorcheck.resources import default_rig_path
    from rotorcheck.workflow import model_report

    rig_path = rig if rig is not None else default_rig_path("crack_rig")
    result = model_report(rig_path, speed_rpm=speed, out_dir=out if plots else None, force=force)
    summary = result["summary"]
    table = Table(title=f"{summary['rig_id']} at {speed:g} rpm", title_justify="left")
    for col in ("mode", "f (Hz)", "zeta", "whirl"):
        table.add_column(col, justify="right")
    for i, m in enumerate(summary["modes"], 1):
        table.add_row(str(i), f"{m['frequency_hz']:.2f}", f"{m['damping_ratio']:.4f}", m["whirl"])
    err.print(table)
    crit = ", ".join(f"{c:.0f}" for c in summary["critical_speeds_rpm"]) or "none"
    err.print(f"critical speeds (rpm, up to {summary.get('campbell_max_rpm', 0):.0f}): {crit}")
    for p in result["files"]:
        err.print(f"wrote {p}")
    if as_json:
        _emit_json(summary)
    return EXIT_OK


@app.command()
def info(
    sweep: Annotated[Path, typer.Argument(help="Sweep file (HDF5, rotorcheck.sweep v1).")],
    as_json: JsonOpt = False,
    confidence: Annotated[float, typer.Option(help="Family-wise confidence of the noise bound.")] = 0.99,
) -> int:
    """Validate a sweep file and summarise it: runs, speeds, grid, channels, noise estimate."""
    from rotorcheck.sweep.format import read_sweep, sweep_sha256
    from rotorcheck.sweep.summary import summarize

    sw = read_sweep(sweep)
    doc = summarize(sw, confidence=confidence)
    doc["file"] = str(sweep)
    doc["sha256"] = sweep_sha256(sweep)
    err.print(f"{sweep}: valid rotorcheck.sweep v1, rig_id {sw.rig_id!r}, source {sw.source}, {sw.generator}")
    chans = ", ".join(f"{c.name} ({c.role} s{c.node}.{c.direction} {c.unit})" for c in sw.channels)
    err.print(f"channels: {chans}")
    for run in doc["runs"]:
        g, nz = run["grid"], run["noise"]["all_outputs"]
        err.print(
            f"run {run['run_id']}: {run['speed_rpm']:g} rpm, {g['n']} points "
            f"{g['min_hz']:g}-{g['max_hz']:g} Hz, {run['n_periods_min']}-{run['n_periods_max']} periods; "
            f"noise std median {nz['median_std_m']:.3g} m, "
            f"family-wise {confidence:.0%} bound {nz['sidak_bound_m']:.3g} m"
        )
    if as_json:
        _emit_json(doc)
    return EXIT_OK


@app.command()
def schema(
    out: Annotated[Path | None, typer.Option("--out", help="Write to this file instead of stdout.")] = None,
    force: ForceOpt = False,
) -> int:
    """JSON Schema of the rig YAML, for editors."""
    from rotorcheck.config import json_schema
    from rotorcheck.fileio import atomic_write_text, check_writable

    text = json.dumps(json_schema(), indent=2) + "\n"
    if out is None:
        sys.stdout.write(text)
    else:
        check_writable([out], force)
        atomic_write_text(out, text)
        err.print(f"wrote {out}")
    return EXIT_OK


# --------------------------------------------------------------------------------------------
# entry point


def main(argv: list[str] | None = None) -> int:
    """Run the CLI and return its exit code; every failure maps to the documented codes."""
    command = typer.main.get_command(app)
    try:
        rc = command.main(args=argv, prog_name="rotorcheck", standalone_mode=False)
    except (InputError, FileExistsError) as exc:
        err.print(f"[bold red]error:[/] {escape(str(exc))}")
        return EXIT_INPUT
    except typer.Exit as exc:
        return int(exc.exit_code)
    except typer.Abort:
        err.print("aborted")
        return EXIT_INPUT
    except Exception as exc:  # the contract: an unexpected exception is 2, never 1
        if type(exc).__name__ == "SweepFormatError":  # names the file, the path inside and the reason
            err.print(f"[bold red]error:[/] {escape(str(exc))}")
            return EXIT_INPUT
        if hasattr(exc, "show") and hasattr(exc, "exit_code"):  # click/typer usage errors
            exc.show(file=sys.stderr)
            return EXIT_INPUT if exc.exit_code else EXIT_OK
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
        return EXIT_INPUT
    return rc if isinstance(rc, int) else EXIT_OK


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())


if __name__ == "__main__":
    run()
