"""Command line: a thin layer over the library (see ``../shared/spec/cli.md``).

Human summaries go to stderr; ``--json`` prints one JSON document on stdout and nothing else there.
Exit codes: 0 ok / no damage, 1 damage detected (detect only), 2 unusable input or failure,
3 inconclusive. An unexpected exception is 2, never 1.

One module per group of commands (``sweep_commands``, ``rig_commands``, ``baseline_commands``,
``detect_commands``; the fleet registers its own); ``common`` holds what they share. Importing a command
module registers its commands on :data:`app`.
"""

from __future__ import annotations

import copy
import os
import sys
from typing import Any

import typer
from rich.markup import escape

from rotorcheck.cli import baseline_commands, detect_commands, rig_commands, sweep_commands  # noqa: F401 (registers)
from rotorcheck.cli.common import (
    EXIT_DAMAGE,
    EXIT_INCONCLUSIVE,
    EXIT_INPUT,
    EXIT_OK,
    QUIET,
    app,
    err,
    package_version,
)
from rotorcheck.errors import UserInputError
from rotorcheck.fleet import command as fleet_command

__all__ = ["EXIT_DAMAGE", "EXIT_INCONCLUSIVE", "EXIT_INPUT", "EXIT_OK", "app", "err", "main", "package_version", "run"]


def _register_fleet() -> None:
    """`rotorcheck fleet` (issue 15): many machines over time (rotorcheck.fleet)."""
    fleet_command.register(app)


_register_fleet()


# --------------------------------------------------------------------------------------------
# entry point


def main(argv: list[str] | None = None) -> int:
    """Run the CLI and return its exit code; every failure maps to the documented codes."""
    command = typer.main.get_command(app)
    shared = [p for p in command.params if p.name in ("version", "quiet")]
    for sub in getattr(command, "commands", {}).values():  # `rotorcheck <command> --version` / -q too (cli.md)
        for top in shared:
            opt = copy.copy(top)
            opt.expose_value = False  # handled by its callback; never passed to the command
            sub.params.append(opt)
    QUIET["on"] = False  # one run of main, one setting (tests call main many times in one process)
    try:
        return _run(command, argv)
    finally:
        from rotorcheck.fileio import release_claims  # lazy: keeps `rotorcheck --help` start-up light

        release_claims()  # the outputs this command claimed (fileio.claim_outputs)


def _run(command: Any, argv: list[str] | None) -> int:
    """:func:`main` without the claims' release."""
    try:
        rc = command.main(args=argv, prog_name="rotorcheck", standalone_mode=False)
    except (UserInputError, FileExistsError) as exc:  # InputError, ConfigError, SweepFormatError
        err.print(f"[bold red]error:[/] {escape(str(exc))}")
        return EXIT_INPUT
    except typer.Exit as exc:
        return int(exc.exit_code)
    except OSError as exc:  # a file the OS refused (no permission, full disk, a folder in the way): name it
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        if exc.filename is None:
            err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
            return EXIT_INPUT
        err.print(f"[bold red]error:[/] {escape(str(exc.filename))}: {escape(exc.strerror or str(exc))}")
        return EXIT_INPUT
    except typer.Abort:
        err.print("aborted")
        return EXIT_INPUT
    except Exception as exc:  # the contract: an unexpected exception is 2, never 1
        if hasattr(exc, "show") and hasattr(exc, "exit_code"):  # click/typer usage errors
            _hint_positional(exc)
            exc.show(file=sys.stderr)
            return EXIT_INPUT if exc.exit_code else EXIT_OK
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
        return EXIT_INPUT
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except BaseException as exc:  # a native panic (pyo3's PanicException) outside a guarded solver call: still 2
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
        return EXIT_INPUT
    return rc if isinstance(rc, int) else EXIT_OK


def _hint_positional(exc: Any) -> None:
    """``rotorcheck model --rig x.yaml``: an unknown option named like one of the command's arguments gets the
    hint that it is positional (the usage error says only "No such option")."""
    name = str(getattr(exc, "option_name", "") or "").lstrip("-").replace("-", "_")
    ctx = getattr(exc, "ctx", None)
    if not name or ctx is None:
        return
    for param in ctx.command.params:
        if getattr(param, "param_type_name", "") == "argument" and param.name == name:
            exc.message += (f" ({name.upper()} is an argument here, given without an option: "
                            f"rotorcheck {ctx.info_name} <{name}> ...)")
            return


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())
