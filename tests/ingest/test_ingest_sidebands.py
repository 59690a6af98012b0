"""Sidebands read by ``rotorcheck ingest`` from time records, against the simulator's phasor path.

The reference is :func:`rotorcheck.sim.simulator.simulate_fast` (``StepSettings.sideband_orders``): it fits
the noise-free tones of each point on its own sample grid (``M`` samples per period, exactly ``N`` periods)
and references them with the shaft angle it turned the rig by; the ingest reads a simulated recording
(a sample clock not locked to the excitation, probes in volts with offset and drift, keyphasor pulses)
and finds the time origin, the shaft angle and the drift itself. Breathing crack of the bundled truth rig
at 1000 rpm, the shaft at 40 deg when the sweep starts.

The grid: ``(m + 1/4) Omega`` and ``(m + 3/4) Omega``, so that no tone of the fit lies within the resolution
``f / N`` of another one (every requested sideband is separable; all tones the fit models are fitted).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from rotorcheck.cli import main as cli_main
from rotorcheck.config import load_config
from rotorcheck.config.ports import Port
from rotorcheck.errors import InputError
from rotorcheck.ingest import analyse, ingest_files, parse_channel_map
from rotorcheck.resources import configs_dir
from rotorcheck.signal.lockin import SHAFT_ORDERS
from rotorcheck.signal.sidebands import FITTED_ORDERS
from rotorcheck.sim.rig_sim import RigPlant, at_shaft_angle, rig_plant, rig_plants, simulate_rig, step_settings
from rotorcheck.sim.simulator import Plant, StepSettings, simulate_fast, simulate_fast_patterns
from rotorcheck.sim.time_records import (
    RecordSpec,
    SimulatedRecord,
    channel_map_dict,
    simulate_record,
    simulate_rig_record,
    write_record,
)
from rotorcheck.sweep.hdf5io import read_sweep

SPEED = 1000.0
OMEGA = SPEED / 60.0
ANGLE = np.radians(40.0)
ORDERS = (-2, -1, 1, 2)
GRID = OMEGA * np.array([1.75, 2.25, 2.75, 3.25, 3.75, 4.25, 5.75, 6.25])  # 29-104 Hz
FS_HZ = 5120.0  # not a multiple of any grid frequency
PORTS = ((8, "x"), [(6, "x")])
#: Monte Carlo records of the noise test (8 points x 4 orders each)
N_RECORDS = 16


@pytest.fixture(scope="module")
def rig() -> tuple[object, RigPlant, StepSettings]:
    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    rp = at_shaft_angle(rig_plant(cfg, SPEED, "breathing_crack", 8, float(GRID.max())), SPEED, ANGLE)
    st = dataclasses.replace(step_settings(cfg, keep_periods=False), sideband_orders=ORDERS)
    return cfg, rp, st


def _spec() -> RecordSpec:
    return RecordSpec(fs_hz=FS_HZ, probe_names=("disp_s6_x",))


def _ingest(sim: SimulatedRecord, with_steps: bool = True):
    doc = channel_map_dict(sim, "crack_rig", with_steps=with_steps, sideband_orders=list(ORDERS))
    return analyse([sim.record], parse_channel_map(doc)).sweep.runs["1000rpm"]


def _modelled(rp: RigPlant) -> tuple[Plant, list]:
    """The rig's plant and disturbances with only the tones the fit models: sidebands |k| <= FITTED_ORDERS,
    shaft harmonics (and DC) up to SHAFT_ORDERS."""
    def tones(f: float) -> tuple[np.ndarray, np.ndarray]:
        tf, ta = rp.plant.tones(f)
        tf = np.asarray(tf, dtype=float).reshape(-1)
        ta = np.asarray(ta, dtype=complex).reshape(tf.size, rp.plant.n_out)
        keep = np.abs(np.rint((tf - f) / OMEGA)) <= FITTED_ORDERS
        return tf[keep], ta[keep]

    dist = [d for d in rp.disturbances if abs(round(d.freq_hz / OMEGA)) <= SHAFT_ORDERS]
    return Plant(tones, rp.plant.n_out, "modelled"), dist


@pytest.mark.parametrize("with_steps", [True, False])
def test_noise_free_matches_phasor_path_exactly(rig, tmp_path: Path, with_steps: bool) -> None:
    # every tone in the record is one the fit models: both paths fit the same tones exactly, whatever
    # their samples; what is left is the ingest's time origin, keyphasor angle, conjugation, sign of k,
    # drift and scaling (a wrong one is an O(1) error: k x 40 deg of phase) and rounding: measured 3e-13 of
    # the largest sideband. Steps found in the force: another time origin (the first zero crossing, 63
    # periods) which the shaft reference makes immaterial to S = Y_k / X, and a frequency estimated to
    # ~1e-9 (phase error 2 pi f T 1e-9 ~ 4e-7 over the window): measured 2e-8
    _cfg, rp, st = rig
    st0 = dataclasses.replace(st, output_noise_std=0.0)
    plant, dist = _modelled(rp)
    ref = simulate_fast(plant, GRID, st0, dist, rng=0, speed_rpm=SPEED, shaft_angle_rad=ANGLE).to_run("r", SPEED)
    sim = simulate_record(plant, GRID, st0, dist, 0, _spec(), SPEED, ANGLE, *PORTS)
    run = _ingest(sim, with_steps=with_steps)
    s_ing, v_ing = run.sideband_frf()
    s_sim, _ = ref.sideband_frf()
    assert s_ing.shape == s_sim.shape == (GRID.size, len(ORDERS), 1, 1)
    assert np.all(np.isfinite(s_ing)) and np.all(np.isfinite(s_sim))  # every sideband separable on this grid
    big = float(np.max(np.abs(s_sim)))
    tol = 1e-9 if with_steps else 1e-6
    assert np.max(np.abs(s_ing - s_sim)) < tol * big, np.max(np.abs(s_ing - s_sim)) / big
    assert np.all(v_ing < (tol * big) ** 2)  # noise free: the residual is rounding
    if not with_steps:
        return
    # the sweep file keeps them (version 3)
    out = tmp_path / "sb.h5"
    rec = write_record(sim, tmp_path / "rec.h5")
    (tmp_path / "map.yaml").write_text(yaml.safe_dump(channel_map_dict(sim, "crack_rig",
                                                                       sideband_orders=list(ORDERS))))
    ingest_files([rec], tmp_path / "map.yaml", out)
    back = read_sweep(out).runs["1000rpm"]
    assert list(back.sideband_order) == list(ORDERS)
    np.testing.assert_allclose(back.sideband_phasor_exc, run.sideband_phasor_exc, rtol=0, atol=1e-12 * big)


def test_noise_free_patterns_match(rig) -> None:
    # two actuators (station 8, x and y) driven one at a time, probes at station 6 x and y: every pattern's
    # sidebands (a version-3 run with n_exc = 2), as the phasor path's simulate_fast_patterns
    cfg, _rp, st = rig
    st0 = dataclasses.replace(st, output_noise_std=0.0)
    grid = GRID[[1, 3, 6]]
    rps = rig_plants(cfg, SPEED, [Port(station=8, direction="x"), Port(station=8, direction="y")],
                     [Port(station=6, direction="x"), Port(station=6, direction="y")], "breathing_crack", 8,
                     float(grid.max()))
    turned = [at_shaft_angle(RigPlant(p, rps.disturbances, rps.system, 0, 0), SPEED, ANGLE) for p in rps.plants]
    modelled = [_modelled(t) for t in turned]
    plants, dist = [m[0] for m in modelled], modelled[0][1]
    ref = simulate_fast_patterns(plants, grid, st0, dist, rng=0, speed_rpm=SPEED, shaft_angle_rad=ANGLE)
    sim = simulate_record(plants, grid, st0, dist, 0, RecordSpec(fs_hz=FS_HZ, probe_names=("p6x", "p6y")), SPEED,
                          ANGLE, [(8, "x"), (8, "y")], [(6, "x"), (6, "y")])
    run = _ingest(sim)
    s_ref = ref.to_run("r", SPEED).sideband_phasor_exc
    assert run.sideband_phasor_exc.shape == s_ref.shape == (grid.size, 2, len(ORDERS), 2)
    big = float(np.max(np.abs(s_ref)))
    assert np.all(np.isfinite(s_ref)) and np.max(np.abs(run.sideband_phasor_exc - s_ref)) < 1e-9 * big


def test_noise_free_full_rig_matches_within_the_unfitted_leak(rig) -> None:
    # the full rig (harmonic balance to order 8) also holds sidebands |k| = 5..8 (up to ~7e-9 m/N, 3e-3 of
    # the largest sideband) and harmonics 5X..10X, which the fit leaves out: they leak into the fitted
    # tones (~1 % of their size) and how much depends on the samples: the simulator's 64 per period over
    # exactly N periods, the ingest's floor(fs/f) from each period start (a fraction of a sample left out
    # per period) and its drift columns. Measured: 4.0e-5 of the largest sideband (at 29.2 Hz, fs/f =
    # 175.5); each of the three sample-set differences alone gives 1e-6..4e-5 (without the unfitted
    # tones the two agree to 1e-14, test above).
    cfg, _rp, st = rig
    st0 = dataclasses.replace(st, output_noise_std=0.0)
    ref = simulate_rig(cfg, GRID, SPEED, "breathing_crack", settings=st0, shaft_angle_rad=ANGLE).runs["1000rpm"]
    sim = simulate_rig_record(cfg, GRID, SPEED, "breathing_crack", spec=_spec(), settings=st0,
                              shaft_angle_rad=ANGLE)
    s_ing, _ = _ingest(sim).sideband_frf()
    s_sim, _ = ref.sideband_frf()
    big = float(np.max(np.abs(s_sim)))
    assert np.max(np.abs(s_ing - s_sim)) < 1e-4 * big, np.max(np.abs(s_ing - s_sim)) / big


def test_noise_chi_square_and_variance(rig) -> None:
    # independent noise on the two paths: |S_ing - S_sim|^2 / (V_ing + V_sim) is Exp(1) (circular complex
    # Gaussian differences), mean 1 with a Monte Carlo sd of 1 / sqrt(n); the phasor path at each point
    # with M = floor(fs/f) samples per period, the ingest's window, so that both state the same variance
    _cfg, rp, st = rig
    ratios, z = [], []
    for seed in range(N_RECORDS):
        sim = simulate_record(rp.plant, GRID, st, rp.disturbances, 100 + seed, _spec(), SPEED, ANGLE, *PORTS)
        s_ing, v_ing = _ingest(sim).sideband_frf()
        for j, (f, t0, _end) in enumerate(sim.steps):
            pt = dataclasses.replace(st, samples_per_period=int(np.floor(FS_HZ / f + 1e-9)), t_start_s=t0)
            res = simulate_fast(rp.plant, [f], pt, rp.disturbances, rng=1000 * seed + j, speed_rpm=SPEED,
                                shaft_angle_rad=ANGLE)
            s_sim, v_sim = res.to_run("r", SPEED).sideband_frf()
            z.append(np.abs(s_ing[j] - s_sim[0]) ** 2 / (v_ing[j] + v_sim[0]))
            ratios.append(v_ing[j] / v_sim[0])
    zz = np.concatenate([a.ravel() for a in z])
    rr = np.array(ratios).reshape(N_RECORDS, GRID.size, len(ORDERS))
    assert np.all(np.isfinite(zz)) and zz.size == N_RECORDS * GRID.size * len(ORDERS)
    assert abs(zz.mean() - 1.0) < 4.0 / np.sqrt(zz.size), zz.mean()  # 4 Monte Carlo sd
    assert np.mean(zz > -np.log(0.05)) == pytest.approx(0.05, abs=4 * np.sqrt(0.05 * 0.95 / zz.size))
    assert np.all(np.abs(rr.mean(axis=0) - 1.0) < 0.05), rr.mean(axis=0)
    assert np.all(np.abs(rr - 1.0) < 0.15), (rr.min(), rr.max())


def _doc(rig, **change: object) -> dict:
    _cfg, rp, st = rig
    sim = simulate_record(rp.plant, GRID[:2], dataclasses.replace(st, n_periods=16), rp.disturbances, 0, _spec(),
                          SPEED, ANGLE, *PORTS)
    return channel_map_dict(sim, "crack_rig", **change)


@pytest.mark.parametrize("orders, what", [([0, 1], "order 0"), ([1, -1, 1], "twice"), ([1.5], "integer")])
def test_bad_orders_refused(rig, orders: list, what: str) -> None:
    with pytest.raises(InputError) as exc:
        parse_channel_map(_doc(rig, sideband_orders=orders), "map.yaml")
    msg = str(exc.value)
    assert "map.yaml" in msg and "analysis.sideband_orders" in msg and what in msg, msg


@pytest.mark.parametrize("case", ["no keyphasor", "at rest"])
def test_sidebands_need_a_turning_shaft_with_keyphasor(rig, tmp_path: Path, case: str) -> None:
    doc = _doc(rig, sideband_orders=[1])
    if case == "no keyphasor":
        del doc["keyphasor"]
        doc["speed_rpm"] = SPEED
    else:
        doc["speed_rpm"] = 0.0
    with pytest.raises(InputError) as exc:
        parse_channel_map(doc, "map.yaml")
    msg = str(exc.value)
    assert "analysis.sideband_orders" in msg and ("no keyphasor" if case == "no keyphasor" else "at rest") in msg
    # the command: exit 2, nothing written
    _cfg, rp, st = rig
    sim = simulate_record(rp.plant, GRID[:2], dataclasses.replace(st, n_periods=16), rp.disturbances, 0, _spec(),
                          SPEED, ANGLE, *PORTS)
    rec = write_record(sim, tmp_path / "rec.h5")
    (tmp_path / "map.yaml").write_text(yaml.safe_dump(doc))
    assert cli_main(["ingest", rec, str(tmp_path / "out.h5"), "--map", str(tmp_path / "map.yaml")]) == 2
    assert not (tmp_path / "out.h5").exists()


def test_default_no_sidebands(rig) -> None:
    # without the setting nothing changes: no sideband datasets, the main phasors identical
    _cfg, rp, st = rig
    sim = simulate_record(rp.plant, GRID[:2], dataclasses.replace(st, n_periods=16), rp.disturbances, 0, _spec(),
                          SPEED, ANGLE, *PORTS)
    plain = analyse([sim.record], parse_channel_map(channel_map_dict(sim, "crack_rig"))).sweep.runs["1000rpm"]
    with_sb = _ingest(sim)
    assert not plain.has_sidebands and with_sb.has_sidebands
    np.testing.assert_array_equal(plain.output_phasor_exc, with_sb.output_phasor_exc)
    np.testing.assert_array_equal(plain.output_var_exc, with_sb.output_var_exc)
