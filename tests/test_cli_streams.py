"""One stream rule for every command (issue 31): human text on stderr, data on stdout; `--help` lists no type
after an on/off flag; a missing argument fails with the usage (exit 2) unless ``--demo`` asks for the bundled
file; list options take repeats and commas alike; a positional argument given as an option gets a hint; a
normal run raises no third-party warning."""

from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import pytest
import typer

from rotorcheck.cli import EXIT_DAMAGE, EXIT_INPUT, EXIT_OK, app, main
from rotorcheck.cli.common import element_list, split_list
from rotorcheck.resources import configs_dir, samples_dir

COMMANDS = sorted(typer.main.get_command(app).commands)  # type: ignore[attr-defined]
#: commands that need an argument (a file) and refuse to run without one
NEEDS_ARGUMENT = ("model", "info", "simulate", "convert", "ingest", "fit-noise", "validate", "detect", "locate",
                  "detectability", "crack", "import-ross", "fleet")
CR = samples_dir() / "crack_rig"
ROSS = Path(__file__).resolve().parent / "data" / "ross"


def test_every_command_is_covered() -> None:
    assert set(NEEDS_ARGUMENT) | {"schema"} == set(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
def test_help_is_data_on_stdout_with_no_flag_types(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([command, "--help"]) == EXIT_OK
    out, err = capsys.readouterr()
    assert "Usage: rotorcheck " + command in " ".join(out.split()) and err == ""
    assert "<bool>" not in out  # Typer prints the type of every option; an on/off flag has none to say


@pytest.mark.parametrize("command", NEEDS_ARGUMENT)
def test_a_missing_argument_fails_with_the_usage(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([command]) == EXIT_INPUT
    out, err = capsys.readouterr()
    assert out == ""
    assert "Usage: rotorcheck " + command in err and f"Try 'rotorcheck {command} -h' for help." in err


def test_demo_is_said_and_not_mixed_with_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["model", "--demo", "--no-plots", "--out", str(tmp_path / "o")]) == EXIT_OK
    out, err = capsys.readouterr()
    assert out == "" and f"--demo: using the bundled rig {configs_dir() / 'crack_rig.yaml'}" in err
    assert main(["model", str(configs_dir() / "crack_rig.yaml"), "--demo", "--no-plots"]) == EXIT_INPUT
    assert "give RIG or --demo, not both" in capsys.readouterr().err


@pytest.mark.parametrize(("argv", "argument"), [(["model", "--rig", "x.yaml"], "RIG"),
                                                (["detect", "--sweep", "x.h5"], "SWEEP")])
def test_an_argument_given_as_an_option_gets_a_hint(argv: list[str], argument: str,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == EXIT_INPUT
    err = capsys.readouterr().err
    assert f"No such option: {argv[1]}" in err and f"{argument} is an argument here" in err


def test_list_options_take_repeats_and_commas() -> None:
    want = ["6x", "6y", "2x"]
    assert split_list(["6x,6y", "2x"]) == split_list(["6x", "6y", "2x"]) == split_list("6x, 6y,2x") == want
    assert split_list(None) == []
    assert element_list(["3,4", "5"]) == element_list("3,4,5") == (3, 4, 5)
    assert element_list(None) is None


def test_simulate_sensors_by_commas_equal_repeats(tmp_path: Path) -> None:
    """The same x/y sweep from ``--sensor 6x --sensor 6y`` and ``--sensors 6x,6y`` (the files' FRFs equal)."""
    from rotorcheck.sweep.hdf5io import read_sweep

    common = ["--speed", "0", "--points", "4", "--periods", "2", "--f-min", "20", "--f-max", "40"]
    assert main(["simulate", str(tmp_path / "a.h5"), *common, "--sensor", "6x", "--sensor", "6y"]) == EXIT_OK
    assert main(["simulate", str(tmp_path / "b.h5"), *common, "--sensors", "6x,6y"]) == EXIT_OK
    a, b = read_sweep(tmp_path / "a.h5"), read_sweep(tmp_path / "b.h5")
    assert [c.name for c in a.channels] == [c.name for c in b.channels]
    assert len([c for c in a.channels if c.role == "output"]) == 2
    import numpy as np

    for ra, rb in zip(a.runs.values(), b.runs.values()):
        np.testing.assert_array_equal(ra.frf, rb.frf)
        assert ra.frf.shape[-2:] == (2, 1)  # (frequency, outputs, inputs)


def _no_foreign_warnings(caught: list[warnings.WarningMessage]) -> list[str]:
    """Warnings raised from outside rotorcheck (matplotlib, numpy, scipy, h5py, ...)."""
    return [f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}" for w in caught
            if "rotorcheck" not in w.filename]


def test_normal_runs_print_data_only_and_no_third_party_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], validated_0rpm: object) -> None:
    """model, info, schema, simulate, convert, detect, locate, detectability, import-ross, ingest (fit-noise and
    validate through the shared run): stdout is empty, or one JSON document with --json, or the schema; no
    warning from a third-party library on the way. crack and fleet: their own tests parse the whole stdout as one
    JSON document and record the warnings (tests/test_pipeline.py, tests/fleet/test_fleet_runs.py)."""
    out = validated_0rpm.copy_to(tmp_path / "run")  # type: ignore[attr-defined]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        steps: list[tuple[list[str], int, str]] = [
            (["model", str(configs_dir() / "crack_rig.yaml"), "--speed", "0", "--no-plots"], EXIT_OK,
             "empty"),
            (["info", str(CR / "healthy_0rpm.h5"), "--json"], EXIT_OK, "json"),
            (["schema"], EXIT_OK, "json"),
            (["simulate", str(tmp_path / "s.h5"), "--speed", "0", "--points", "4", "--periods", "2"], EXIT_OK, "empty"),
            (["convert", str(tmp_path / "s.h5"), str(tmp_path / "s.csv")], EXIT_OK, "empty"),
            (["detect", str(CR / "open_crack_0rpm.h5"), "--out", str(out), "--no-plots"], EXIT_DAMAGE, "empty"),
            (["detect", str(CR / "open_crack_0rpm.h5"), "--out", str(out), "--no-plots", "--json", "--force"],
             EXIT_DAMAGE, "json"),
            (["locate", str(CR / "open_crack_0rpm.h5"), "--out", str(out), "--elements", "4", "--no-plots"], None,
             "empty"),
            (["detectability", str(configs_dir() / "crack_rig.yaml"), "--noise-std", "2e-7", "--speed", "0",
              "--elements", "4", "--no-plots", "--out", str(tmp_path / "d")], EXIT_OK, "empty"),
            (["import-ross", str(ROSS / "conical_4.toml"), str(tmp_path / "ross.yaml"), "--json"], EXIT_OK, "json"),
            (["ingest", *_records(tmp_path), str(tmp_path / "ingested.h5"), "--map", str(tmp_path / "map.yaml")],
             EXIT_OK, "empty"),
        ]
        for argv, code, stdout_kind in steps:
            rc = main(argv)
            stdout, stderr = capsys.readouterr()
            assert code is None or rc == code, (argv, rc, stderr)
            assert rc != EXIT_INPUT, (argv, stderr)
            if stdout_kind == "empty":
                assert stdout == "", argv
            else:
                json.loads(stdout)  # one strict JSON document, nothing else
            assert "Warning" not in stderr, (argv, stderr)
    assert _no_foreign_warnings(caught) == []
    shutil.rmtree(tmp_path / "run")
    assert validated_0rpm.stdout == ("", "")  # type: ignore[attr-defined]  # fit-noise and validate, run shared


def _records(folder: Path) -> list[str]:
    """A small stepped-sine time record (HDF5) and its channel map (``folder/map.yaml``), as the ingest tests
    make them."""
    import yaml

    from rotorcheck.sim.time_records import channel_map_dict, write_record
    from tests.ingest.ingest_helpers import small_record

    sim = small_record()
    (folder / "map.yaml").write_text(yaml.safe_dump(channel_map_dict(sim, "crack_rig")))
    return [str(write_record(sim, folder / "record.h5"))]


def test_progress_lines_say_item_elapsed_and_remaining(monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    """Without a terminal: a line per update once PLAIN_EVERY_S has passed, remaining = elapsed x left / done
    (a linear rate); nothing when quiet."""
    import itertools

    from rotorcheck.cli import common

    clock = itertools.count(0.0, 3.0)  # every call to the clock: 3 s later
    monkeypatch.setattr("time.monotonic", lambda: next(clock))
    with common.Steps("locating") as tick:  # start at t = 0
        tick(1, 4, "element 2")  # t = 3: 1 of 4 done in 3 s -> 9 s left
        tick(4, 4, "element 9")  # t = 6: done, no remaining time
    assert capsys.readouterr().err.splitlines() == [
        "[1/4] locating element 2: elapsed 0:00:03, about 0:00:09 left",
        "[4/4] locating element 9: elapsed 0:00:06, about 0:00:00 left"]
    with common.Steps("locating", quiet=True) as tick:
        tick(1, 4, "element 2")
    monkeypatch.setitem(common.QUIET, "on", True)  # -q
    with common.Steps("locating") as tick:
        tick(1, 4, "element 2")
    assert capsys.readouterr().err == ""


def test_quiet_is_accepted_before_and_after_the_command(capsys: pytest.CaptureFixture[str]) -> None:
    from rotorcheck.cli import common

    assert main(["-q", "schema"]) == EXIT_OK and common.QUIET["on"]
    json.loads(capsys.readouterr().out)
    assert main(["schema", "--quiet"]) == EXIT_OK and common.QUIET["on"]
    capsys.readouterr()
    assert main(["schema"]) == EXIT_OK and not common.QUIET["on"]  # one run, one setting
