"""Free-running sweeps: the start angle of the shaft against an independent construction (every
shaft-fixed angle of the rig file turned by hand), and the bundled free-running 2000 rpm pair."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rotorcheck.config import RigConfig, load_config
from rotorcheck.errors import InputError
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import shaft_angle_from, simulate_rig, step_settings


def _turned(cfg: RigConfig, theta0: float) -> RigConfig:
    """The rig with unbalance (1X), misalignment (2X) and crack orientation turned by the shaft angle."""
    m = cfg.measurement
    unb = [u.model_copy(update={"phase": u.phase + theta0}) for u in m.unbalance]
    mis = None if m.misalignment is None else m.misalignment.model_copy(
        update={"phase": m.misalignment.phase + 2 * theta0})
    faults = {k: (v.model_copy(update={"angle": v.angle + theta0}) if hasattr(v, "angle") else v)
              for k, v in cfg.faults.items()}
    meas = m.model_copy(update={"unbalance": unb, "misalignment": mis})
    return cfg.model_copy(update={"measurement": meas, "faults": faults})


@pytest.mark.parametrize("fault", [None, "breathing_crack"])
def test_shaft_angle_equals_turning_every_shaft_fixed_angle(fault: str | None) -> None:
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    grid = np.array([31.0, 33.0, 54.5, 66.0, 120.0])
    st = dataclasses.replace(step_settings(truth), output_noise_std=0.0, n_periods=8)
    theta0 = 1.1
    a = simulate_rig(truth, grid, 1000.0, fault=fault, settings=st, shaft_angle_rad=theta0)
    b = simulate_rig(_turned(truth, theta0), grid, 1000.0, fault=fault, settings=st)
    c = simulate_rig(truth, grid, 1000.0, fault=fault, settings=st)
    ra, rb, rc = (next(iter(s.runs.values())) for s in (a, b, c))
    assert ra.period_phasor is not None and rb.period_phasor is not None
    scale = np.abs(ra.output_phasor).max()
    np.testing.assert_allclose(ra.period_phasor, rb.period_phasor, rtol=0, atol=1e-10 * scale)
    # and the angle matters (the leak moves): the key-phasor sweep differs
    assert np.abs(ra.output_phasor - rc.output_phasor).max() > 1e-4 * scale


def test_shaft_angle_spec() -> None:
    assert shaft_angle_from("90", 0) == pytest.approx(np.pi / 2)
    r1, r2 = shaft_angle_from("random", 3), shaft_angle_from("random", 3)
    assert r1 == r2 and 0 <= r1 < 2 * np.pi
    assert shaft_angle_from("random", 4) != r1
    with pytest.raises(InputError, match="--shaft-angle"):
        shaft_angle_from("north", 0)


def test_bundled_free_running_pair_leaks_without_removal_and_is_healthy_with_it(
        tmp_path: pytest.TempPathFactory, capsys: pytest.CaptureFixture) -> None:
    """healthy_2000rpm(_repeat).h5 start at random shaft angles: the plain averaged phasors differ by the
    2X leak beside mode 1 (a certified 'fault' at 67.1 Hz, 2X = 66.7 Hz); with the shaft harmonics fitted
    out of the per-period phasors the pair is healthy, through the CLI as a user runs it."""
    import json

    from rotorcheck import workflow
    from rotorcheck.cli import main
    from rotorcheck.resources import samples_dir
    from rotorcheck.robust.measured import measured_detect

    cr = samples_dir() / "crack_rig"
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    raw = [workflow.load_run(cr / f, nominal, shaft_orders=0)
           for f in ("healthy_2000rpm.h5", "healthy_2000rpm_repeat.h5")]
    m = measured_detect(workflow.frf_estimate(raw[1]), workflow.frf_estimate(raw[0]), 0.99)
    flagged = raw[0].frequency_hz[m.fault]
    assert flagged.size >= 1
    shaft_hz = 2000 / 60
    assert np.all(np.min(np.abs(flagged[:, None] - shaft_hz * np.arange(1, 5)[None, :]), axis=1) < 1.5)
    out = str(tmp_path)
    assert main(["fit-noise", str(cr / "healthy_2000rpm.h5"), "--out", out]) == 0
    assert main(["validate", str(cr / "healthy_2000rpm.h5"), "--out", out, "--no-plots"]) == 0
    capsys.readouterr()
    rc = main(["detect", str(cr / "healthy_2000rpm_repeat.h5"), "--out", out, "--no-plots", "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert rc == 0 and rep["verdict"] == "healthy" and rep["shaft_orders_removed"] == 4


def test_info_reports_the_noise_with_shaft_harmonics_removed() -> None:
    """On the free-running 2000 rpm sample the stored scatter is leak-inflated; with the harmonics
    fitted out the pooled bound is the white-noise value: V = (sigma/32) sqrt(-ln(1 - 0.99^(1/262)))
    = 0.0997 sigma for sigma = 0.2 um per sample, 64 x 64 samples (the truth rig's measurement)."""
    from rotorcheck.resources import samples_dir
    from rotorcheck.sweep import read_sweep
    from rotorcheck.sweep.summary import summarize

    doc = summarize(read_sweep(samples_dir() / "crack_rig" / "healthy_2000rpm.h5"))
    noise = doc["runs"][0]["noise"]
    expected = 2e-7 / 32 * np.sqrt(-np.log(-np.expm1(np.log(0.99) / 262)))
    assert noise["pooled_bound_harmonics_removed_m"] == pytest.approx(expected, rel=0.1)
    assert noise["pooled_bound_m"] > 3 * noise["pooled_bound_harmonics_removed_m"]
