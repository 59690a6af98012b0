"""`rotorcheck --version`, `-h` as `--help` on the app and every command, `--samples-dir` (issue 12)."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

import pytest
import typer

from rotorcheck import resources
from rotorcheck.cli import EXIT_OK, app, main, package_version


def _commands() -> list[str]:
    """Every command registered on the typer app (so a command added later is checked too)."""
    names = sorted(getattr(typer.main.get_command(app), "commands", {}))
    assert {"model", "info", "fit-noise", "validate", "detect", "simulate"} <= set(names)
    return names


def test_version_is_the_installed_distributions(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == EXIT_OK
    out = capsys.readouterr().out
    assert out == f"rotorcheck {importlib.metadata.version('rotorcheck')}\n"
    assert package_version() == importlib.metadata.version("rotorcheck")


@pytest.mark.parametrize("command", _commands())
def test_every_command_takes_version(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([command, "--version"]) == EXIT_OK
    assert capsys.readouterr().out == f"rotorcheck {importlib.metadata.version('rotorcheck')}\n"


def test_version_falls_back_to_the_package_attribute(monkeypatch: pytest.MonkeyPatch) -> None:
    import rotorcheck

    def missing(name: str) -> str:
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "version", missing)
    assert package_version() == rotorcheck.__version__


def test_h_is_help_on_the_app(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-h"]) == EXIT_OK
    short = capsys.readouterr().out
    assert main(["--help"]) == EXIT_OK
    assert short == capsys.readouterr().out
    assert "Usage: rotorcheck" in short
    for name in ("--version", "--samples-dir", "-h", *_commands()):
        assert name in short


@pytest.mark.parametrize("command", _commands())
def test_h_is_help_on_every_command(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([command, "-h"]) == EXIT_OK  # even where an argument is required
    short = capsys.readouterr().out
    assert main([command, "--help"]) == EXIT_OK
    assert short == capsys.readouterr().out
    assert f"Usage: rotorcheck {command}" in short


def test_samples_dir_prints_the_bundled_samples(capsys: pytest.CaptureFixture[str],
                                                monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("ROTORCHECK_SAMPLES", raising=False)
    assert main(["--samples-dir"]) == EXIT_OK
    printed = Path(capsys.readouterr().out.strip())
    assert printed == resources.samples_dir()
    assert (printed / "crack_rig" / "healthy_1000rpm.h5").is_file()
    monkeypatch.setenv("ROTORCHECK_SAMPLES", str(tmp_path))
    assert main(["--samples-dir"]) == EXIT_OK
    assert Path(capsys.readouterr().out.strip()) == tmp_path
