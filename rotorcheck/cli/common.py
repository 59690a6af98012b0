"""What every command shares: the Typer app, the stderr console, exit codes, option types and checks,
progress, the JSON printer, the top-level options and the output manifests."""

from __future__ import annotations

import contextlib
import datetime as dt
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer
import typer.core
from rich.console import Console

from rotorcheck import __version__
from rotorcheck.errors import InputError, finite_positive
from rotorcheck.progress import ConsoleSteps

EXIT_OK, EXIT_DAMAGE, EXIT_INPUT, EXIT_INCONCLUSIVE = 0, 1, 2, 3
#: frequency points of a simulated sweep when neither --points nor the rig's analysis.n_points sets them
DEFAULT_POINTS = 262
#: the largest spin speed an option accepts, rpm (1e308 rpm overflows every frequency computed from it)
MAX_SPEED_RPM = 1e6


def split_list(values: list[str] | str | None) -> list[str]:
    """A list option given as repeats (``--sensor 6x --sensor 6y``), commas (``--sensor 6x,6y``) or both."""
    if values is None:
        return []
    items = [values] if isinstance(values, str) else values
    return [x for v in items for x in v.replace(" ", "").split(",") if x]


def _context() -> Any:
    """The running command's click context (usage line and help hint of its errors), if any."""
    import click  # lazy: click is not loaded when this module is imported

    return click.get_current_context(silent=True)


def bundled_or_given(given: Path | None, demo: bool, bundled: Path, what: str, argument: str) -> Path:
    """The file the user named, or with ``--demo`` the bundled one (said on stderr); neither: a usage error.

    A forgotten argument never runs a bundled file silently (issue 31)."""
    if given is not None:
        if demo:
            raise typer.BadParameter(f"give {argument} or --demo, not both", ctx=_context(), param_hint="--demo")
        return given
    if not demo:
        raise typer.BadParameter(f"missing {argument} ({what}); --demo uses the bundled {bundled.name}",
                                 ctx=_context(), param_hint=argument)
    err.print(f"--demo: using the bundled {what} {bundled}")
    return bundled


def check_speed(value: float | None, option: str = "--speed") -> float | None:
    """A spin speed option: None or a finite number of rpm in [0, MAX_SPEED_RPM], else an InputError naming it."""
    return finite_positive(value, option, allow_zero=True, maximum=MAX_SPEED_RPM)


def at_least(value: int | None, minimum: int, option: str) -> int | None:
    """An integer option: None or >= ``minimum``, else an InputError naming it."""
    if value is not None and value < minimum:
        raise InputError(None, option, f"must be >= {minimum}, got {value}")
    return value

#: the order ``rotorcheck --help`` lists the commands in: the pipeline's (rig, sweep, baseline, new sweep), then tools
COMMAND_ORDER = ("model", "info", "simulate", "convert", "ingest", "fit-noise", "validate", "detect", "locate",
                 "detectability", "fleet", "crack", "schema", "import-ross")


def _flag_type(self: Any, ctx: Any) -> str | None:
    """The help's type column: none for an on/off flag (Typer prints ``<bool>`` after every flag)."""
    return None if getattr(self, "is_flag", False) else _TYPE_COLUMN(self, ctx)


_TYPE_COLUMN = typer.core.TyperOption.display_type_rich
typer.core.TyperOption.display_type_rich = _flag_type  # type: ignore[method-assign]


class _PipelineOrder(typer.core.TyperGroup):
    """Lists the commands in :data:`COMMAND_ORDER` (any other after them, as registered)."""

    def list_commands(self, ctx: Any) -> list[str]:
        names = list(self.commands)
        return sorted(names, key=lambda n: COMMAND_ORDER.index(n) if n in COMMAND_ORDER else len(COMMAND_ORDER))


app = typer.Typer(
    cls=_PipelineOrder,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Has this shaft changed, where in the spectrum, and what exactly changed?",
    context_settings={"help_option_names": ["-h", "--help"]},  # inherited by every command
)
err = Console(stderr=True, highlight=False, soft_wrap=True)  # never break paths in messages


#: ``-q``/``--quiet`` given (any command): no progress on stderr
QUIET = {"on": False}
#: seconds before a step's first progress line when stderr is no terminal, and between lines
PLAIN_EVERY_S = 2.0


def progress(text: str) -> Any:
    """One long step without items to count: on a terminal a spinner with ``text`` and the elapsed time
    (rich); otherwise, when it took :data:`PLAIN_EVERY_S` or more, one line after it saying how long;
    nothing with ``-q``."""
    if QUIET["on"]:
        return contextlib.nullcontext()
    if err.is_terminal:
        from rich.progress import (  # lazy: rich.progress only for a spinner on a terminal
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
        )

        bar = Progress(SpinnerColumn("dots"), TextColumn("{task.description}"), TimeElapsedColumn(), console=err,
                       transient=True)
        bar.add_task(text, total=None)
        return bar

    @contextlib.contextmanager
    def timed() -> Any:
        start = time.monotonic()
        yield
        took = time.monotonic() - start
        if took >= PLAIN_EVERY_S:
            err.print(f"{text}: {took:.0f} s")

    return timed()


class Steps(ConsoleSteps):
    """Progress of a long step over items on stderr (:class:`rotorcheck.progress.ConsoleSteps` on the CLI's
    console); nothing with ``-q`` or ``quiet`` (the commands pass ``--json``).

    ``with Steps("locating") as tick: library_call(..., progress=tick)``"""

    def __init__(self, text: str, quiet: bool = False) -> None:
        super().__init__(err, text, quiet or QUIET["on"], PLAIN_EVERY_S)

DemoOpt = Annotated[bool, typer.Option("--demo", help="Use the bundled sample file when the argument is not given.")]
RigOpt = Annotated[
    Path | None,
    typer.Option("--rig", help="Rig YAML (default: the bundled rig named by the sweep's rig_id)."),
]
OutOpt = Annotated[Path, typer.Option("--out", help="Output folder (created).")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON document on stdout.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Overwrite existing outputs.")]
DEFAULT_OUT = Path("rotorcheck-out")
PlotFormatOpt = Annotated[str, typer.Option("--plot-format", help="png (default) | pdf | both.")]
FrfUnitOpt = Annotated[str, typer.Option("--frf-unit", help="Receptance unit of the plots: m/N (default) | mm/N | "
                                                             "um/N.")]


def emit_json(doc: dict[str, Any]) -> None:
    """One strict JSON document on stdout (non-finite numbers as the strings "inf"/"nan")."""
    from rotorcheck.report.reports import render_json  # lazy: keeps `rotorcheck --help` start-up light

    sys.stdout.write(render_json(doc))
    sys.stdout.flush()


# --------------------------------------------------------------------------------------------
# top-level options


def package_version() -> str:
    """The installed distribution's version (importlib.metadata), else ``rotorcheck.__version__``."""
    from importlib.metadata import PackageNotFoundError, version  # lazy: ~20 ms (email, zipfile), only for --version

    try:
        return version("rotorcheck")
    except PackageNotFoundError:  # imported from a checkout that is not installed
        return __version__


def _print_version(value: bool) -> None:
    if value:
        sys.stdout.write(f"rotorcheck {package_version()}\n")
        raise typer.Exit(EXIT_OK)


def _set_quiet(value: bool) -> None:
    if value:
        QUIET["on"] = True


def _print_samples_dir(value: bool) -> None:
    if value:
        from rotorcheck.resources import samples_dir  # lazy: keeps `rotorcheck --help` start-up light

        sys.stdout.write(f"{samples_dir()}\n")
        raise typer.Exit(EXIT_OK)


@app.callback()
def _top_level(
    version: Annotated[bool, typer.Option(
        "--version", is_eager=True, callback=_print_version, help="Print 'rotorcheck <version>' and exit.")] = False,
    samples: Annotated[bool, typer.Option(
        "--samples-dir", is_eager=True, callback=_print_samples_dir,
        help="Print the folder of the bundled sample sweeps (e.g. crack_rig/healthy_1000rpm.h5) and exit.")] = False,
    quiet: Annotated[bool, typer.Option(
        "--quiet", "-q", callback=_set_quiet, help="No progress on stderr (any command; --json implies it).")] = False,
) -> None:
    """Has this shaft changed, where in the spectrum, and what exactly changed?"""




def element_list(values: list[str] | str | None) -> tuple[int, ...] | None:
    """``--elements 3,4,5`` (or repeated) as element numbers (None: every element)."""
    items = split_list(values)
    try:
        return tuple(int(x) for x in items) or None
    except ValueError:
        raise InputError(None, "--elements", f"{','.join(items)!r} is no list of element numbers (e.g. 3,4,5)"
                         ) from None


def fail_at_points(spec: str) -> tuple[int, ...]:
    """Testing hook ``--fail-at 3,17`` (hidden): the solver fails at those point indices."""
    try:
        return tuple(int(x) for x in split_list(spec))
    except ValueError:
        raise InputError(None, "--fail-at", f"expected comma-separated point indices, got {spec!r}") from None


FailAtOpt = Annotated[str, typer.Option("--fail-at", hidden=True, help="Testing: fail the solver at these points.")]


RunOpt = Annotated[str | None, typer.Option("--run", help="Run id inside the sweep file (default: the only one).")]


def record_run(command: str, written: list[Path], folders: list[Path], force: bool) -> None:
    """Record what this run of ``command`` wrote (the folders' manifests); a forced run then removes what an
    earlier run of the command wrote there and this one did not rewrite (e.g. plots after --no-plots)."""
    from rotorcheck.fileio import record_outputs, remove_stale_outputs  # lazy: keeps `rotorcheck --help` start-up light

    record_outputs(written, command)
    if force:
        for p_ in remove_stale_outputs(folders, command, written):
            err.print(f"removed {p_} (an earlier {command} run's output this run did not rewrite)")




def utc_now() -> str:
    return dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
