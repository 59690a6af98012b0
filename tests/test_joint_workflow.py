"""The joint test in the product path: baseline storage, speed tolerance, rule selection, bad input."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.baseline import read_baseline, write_baseline
from rotorcheck.cli import main
from rotorcheck.errors import InputError
from rotorcheck.resources import configs_dir

CR = Path(__file__).resolve().parents[1] / "data_samples" / "crack_rig"
TM = Path(__file__).resolve().parents[1] / "data_samples" / "three_mass"


@pytest.fixture(scope="module")
def pair():  # type: ignore[no-untyped-def]
    rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
    h = workflow.load_run(CR / "healthy_1000rpm.h5", rig)
    r = workflow.load_run(CR / "healthy_1000rpm_repeat.h5", rig)
    return rig, h, r


def test_two_healthy_sweeps_store_their_benign_model(pair, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    rig, h, r = pair
    val = workflow.validate(rig, [h, r], workflow.fit_noise(h))
    b = val.baseline
    assert b.n_healthy == 2 and b.benign_kappa is None  # fewer than 3: no leave-one-out, the anchor's default
    write_baseline(b, tmp_path / "b.h5")
    back = read_baseline(tmp_path / "b.h5")
    assert back.n_healthy == 2 and back.benign_kappa == b.benign_kappa
    if b.benign_directions is None:
        assert back.benign_directions is None
    else:
        np.testing.assert_array_equal(back.benign_directions, b.benign_directions)
        np.testing.assert_array_equal(back.benign_direction_bound, b.benign_direction_bound)


def test_speed_inside_the_tolerance_is_compared_through_the_model(pair) -> None:  # type: ignore[no-untyped-def]
    rig, h, r = pair
    base = workflow.validate(rig, [h], workflow.fit_noise(h)).baseline
    assert workflow.speed_tolerance(rig) == 20.0
    workflow.check_baseline(base, rig, dataclasses.replace(r, speed_rpm=1010.0), "b.h5")
    with pytest.raises(InputError, match=r"outside the rig's speed tolerance \(variability: speed \+-20 rpm\)"):
        workflow.check_baseline(base, rig, dataclasses.replace(r, speed_rpm=1030.0), "b.h5")
    plain = rig.model_copy(update={"variability": []})
    base_plain = workflow.validate(plain, [h], workflow.fit_noise(h)).baseline
    with pytest.raises(InputError, match="sets no speed tolerance"):
        workflow.check_baseline(base_plain, plain, dataclasses.replace(r, speed_rpm=1010.0), "b.h5")
    # the joint test then fits the speed around the recorded offset (the range moves with it)
    out = workflow.detect(rig, base, dataclasses.replace(r, speed_rpm=1010.0))
    k = out.joint.theta_names.index("speed")
    assert -10.0 <= out.joint.theta[k] <= 30.0


def test_rule_choice_and_bad_values_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "o"
    assert main(["validate", str(CR / "healthy_1000rpm.h5"), "--out", str(out), "--no-plots"]) == 0
    capsys.readouterr()
    assert main(["detect", str(CR / "healthy_1000rpm_repeat.h5"), "--out", str(out), "--no-plots",
                 "--rule", "vote"]) == 2
    assert "--rule" in capsys.readouterr().err
    assert main(["detect", str(CR / "healthy_1000rpm_repeat.h5"), "--out", str(out), "--no-plots",
                 "--false-alarm", "1.5"]) == 2
    assert "--false-alarm" in capsys.readouterr().err
    tm = tmp_path / "tm"
    rig = str(configs_dir() / "three_mass_trial3.yaml")
    assert main(["validate", str(TM / "healthy.h5"), "--rig", rig, "--out", str(tm), "--no-plots"]) == 0
    capsys.readouterr()
    assert main(["detect", str(TM / "damaged.h5"), "--rig", rig, "--out", str(tm), "--no-plots", "--rule",
                 "joint"]) == 2
    assert "lumped" in capsys.readouterr().err


def test_model_without_speed_reports_every_configured_speed(capsys: pytest.CaptureFixture) -> None:
    """analysis.speeds_rpm [0, 1000] of the crack rig: one table per speed, the first at the top level;
    each equals the single-speed run."""
    import json

    assert main(["model", "--demo", "--no-plots", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [a["speed_rpm"] for a in doc["at_speeds"]] == [0.0, 1000.0] and doc["speed_rpm"] == 0.0
    assert main(["model", "--demo", "--no-plots", "--json", "--speed", "1000"]) == 0
    one = json.loads(capsys.readouterr().out)
    got = [m["frequency_hz"] for m in doc["at_speeds"][1]["modes"]]
    np.testing.assert_allclose(got, [m["frequency_hz"] for m in one["modes"]], rtol=1e-12)
    assert got[1] - got[0] > 0.3  # gyroscopic split of mode 1 at 1000 rpm (54.42 / 54.81 Hz)


def test_learn_drift_needs_three_sweeps(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["validate", str(CR / "healthy_1000rpm.h5"), str(CR / "healthy_1000rpm_repeat.h5"), "--out",
                 str(tmp_path / "o"), "--no-plots", "--learn-drift"]) == 2
    assert "--learn-drift" in capsys.readouterr().err
