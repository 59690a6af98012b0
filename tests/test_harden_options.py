"""Issue 32: option values that are not finite, out of range or a path where a name belongs end as exit 2
with a message naming the option, before anything is computed or written."""

from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import pytest

from rotorcheck.cli import main
from rotorcheck.errors import InputError, check_rig_id
from rotorcheck.resources import default_rig_path, samples_dir

HEALTHY = samples_dir() / "crack_rig" / "healthy_0rpm.h5"

CASES = [  # (argv with OUT for the output folder, the option the message names)
    (["model", "--demo", "--speed", "nan", "--out", "OUT"], "--speed"),
    (["model", "--demo", "--speed", "inf", "--out", "OUT"], "--speed"),
    (["model", "--demo", "--speed", "1e308", "--out", "OUT"], "--speed"),
    (["info", str(HEALTHY), "--confidence", "nan"], "--confidence"),
    (["info", str(HEALTHY), "--confidence", "2"], "--confidence"),
    (["simulate", "OUT/s.h5", "--f-max", "inf"], "--f-max"),
    (["simulate", "OUT/s.h5", "--periods", "0"], "--periods"),
    (["simulate", "OUT/s.h5", "--seed", "-1"], "--seed"),
    (["crack", "--demo", "--unbalance", "nan", "--out", "OUT"], "--unbalance"),
    (["detectability", "--demo", "--noise-std", "nan", "--out", "OUT"], "--noise-std"),
    (["detectability", "--demo", "--noise-std", "0", "--out", "OUT"], "--noise-std"),
    (["detectability", "--demo", "--speed", "nan", "--out", "OUT"], "--speed"),
    (["locate", str(HEALTHY), "--crack-section-length", "0", "--out", "OUT"], "--crack-section-length"),
    (["locate", str(HEALTHY), "--crack-section-length", "nan", "--out", "OUT"], "--crack-section-length"),
    (["locate", str(HEALTHY), "--crack-section-length", "inf", "--out", "OUT"], "--crack-section-length"),
    (["locate", str(HEALTHY), "--crack-section-length", "-0.01", "--out", "OUT"], "--crack-section-length"),
    (["fleet", "OUT", "--low-band", "nan", "--out", "OUT/r"], "--low-band"),
    (["fleet", "OUT", "--low-band", "-1", "--out", "OUT/r"], "--low-band"),
    (["convert", str(HEALTHY), "OUT/c.h5", "--rig-id", "../evil"], "--rig-id"),
    (["import-ross", "OUT/r.toml", "OUT/r.yaml", "--rig-id", "/etc/x"], "--rig-id"),
]


@pytest.mark.parametrize(("argv", "option"), CASES, ids=[" ".join(a[:1] + a[-3:-1]) for a, _ in CASES])
def test_bad_option_is_refused_naming_it(tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str],
                                        option: str) -> None:
    out = tmp_path / "out"
    out.mkdir()
    argv = [a.replace("OUT", str(out)) for a in argv]
    assert main(argv) == 2
    msg = capsys.readouterr().err
    assert f"error: {option}:" in msg and "internal error" not in msg
    assert list(out.iterdir()) == []  # nothing written


@pytest.mark.parametrize("elements", ["0", "99", "3,0"])
def test_detectability_elements_outside_the_rig_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                            elements: str) -> None:
    assert main(["detectability", "--demo", "--elements", elements, "--out", str(tmp_path / "o")]) == 2
    msg = capsys.readouterr().err
    assert "error: --elements: no shaft element" in msg and "(elements 1-9)" in msg
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("bad", ["../configs/crack_rig", "/etc/passwd", "a/b", "a\\b", "..", ".hidden", "", "x" * 129])
def test_a_rig_id_is_a_name(bad: str) -> None:
    with pytest.raises(InputError, match="no rig name"):
        check_rig_id(bad, "f.h5", "/@rig_id")
    with pytest.raises(InputError, match="no rig name"):
        default_rig_path(bad)


@pytest.mark.parametrize("good", ["crack_rig", "rig-2.v1", "A_b"])
def test_a_rig_name_passes(good: str) -> None:
    assert check_rig_id(good, None, "--rig-id") == good


def test_a_sweep_whose_rig_id_is_a_path_loads_no_rig(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`validate` without --rig took the rig file a sweep's rig_id named anywhere on disk."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    shutil.copy(default_rig_path("crack_rig"), elsewhere / "evil.yaml")
    sweep = tmp_path / "s.h5"
    shutil.copy(HEALTHY, sweep)
    with h5py.File(sweep, "r+") as h5:
        h5.attrs["rig_id"] = str(elsewhere / "evil")  # configs_dir() / "<abs>.yaml" is that file
    out = tmp_path / "out"
    assert main(["validate", str(sweep), "--out", str(out), "--no-plots"]) == 2
    msg = capsys.readouterr().err
    assert f"error: {sweep}: /@rig_id:" in msg and "no rig name" in msg
    assert not (out / "baseline.h5").exists()
