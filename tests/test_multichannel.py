"""Several channels end to end (issue 12): forces in x and y at station 8, x and y probes at stations 6 and 2
(8 channel pairs, sweep format version 2), against the one-channel sweep of the same crack and seed."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.cli import EXIT_DAMAGE, EXIT_INPUT, EXIT_OK, main
from rotorcheck.config import Port, RigConfig, load_config
from rotorcheck.nominal import ChannelPair, pair_receptance
from rotorcheck.resources import configs_dir
from rotorcheck.robust.joint import JOINT_RULE
from rotorcheck.sim.rig_sim import simulate_rig, simulate_rig_patterns, step_settings
from rotorcheck.sweep import write_sweep

GRID = np.linspace(30.0, 600.0, 262)[::2]  # the samples' grid, every other point (131)
ACTUATORS = [Port(station=8, direction="x"), Port(station=8, direction="y")]
SENSORS = [Port(station=6, direction="x"), Port(station=6, direction="y"), Port(station=2, direction="x"),
           Port(station=2, direction="y")]


@pytest.fixture(scope="module")
def rigs():  # type: ignore[no-untyped-def]
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    crack = workflow.rig_with_crack_depth(truth, None, "breathing_crack", 0.4)
    return truth, crack


@pytest.fixture(scope="module")
def files(rigs, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:  # type: ignore[no-untyped-def]
    """x/y and one-channel sweeps (healthy, crack, repeat) written to disk, same seeds for both layouts."""
    truth, crack = rigs
    d = tmp_path_factory.mktemp("xy")
    out = {}
    for name, cfg, fault, seed in (("healthy", truth, None, 108), ("crack", crack, "breathing_crack", 104),
                                   ("repeat", truth, None, 105)):
        st = step_settings(cfg, keep_periods=True)
        xy = simulate_rig_patterns(cfg, GRID, ACTUATORS, SENSORS, speed_rpm=1000.0, fault=fault, seed=seed, settings=st)
        one = simulate_rig(cfg, GRID, 1000.0, fault=fault, seed=seed, settings=st)
        for tag, sw in (("xy", xy), ("one", one)):
            out[f"{tag}_{name}"] = d / f"{tag}_{name}.h5"
            write_sweep(sw, out[f"{tag}_{name}"])
    return out


@pytest.fixture(scope="module")
def xy_validated(files, tmp_path_factory: pytest.TempPathFactory) -> Path:  # type: ignore[no-untyped-def]
    """`fit-noise` and `validate --no-plots` of the x/y healthy sweep, once for the module (read only: copy it)."""
    out = tmp_path_factory.mktemp("xy_base") / "out"
    assert main(["fit-noise", str(files["xy_healthy"]), "--out", str(out)]) == EXIT_OK
    assert main(["validate", str(files["xy_healthy"]), "--out", str(out), "--no-plots"]) == EXIT_OK
    return out


def test_channel_pairs_and_their_noise(rigs, files) -> None:  # type: ignore[no-untyped-def]
    """The 8 pairs, the rig's actuator -> sensor first and equal to the one-channel run's FRF within the
    noise; every pair's FRF against the truth model's receptance: the whitened error's mean square is
    1 within its sampling scatter (the variances are right), the first pair's within 3 sigma."""
    truth, _ = rigs
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    run = workflow.load_run(files["xy_repeat"], nominal)
    assert run.n_pairs == 8 and [p.key() for p in run.pairs[:2]] == [("s6.x", "s8.x"), ("s6.x", "s8.y")]
    ref = pair_receptance(truth, run.frequency_hz, 1000.0, run.pairs)
    z2 = np.abs(run.frf_pairs - ref) ** 2 / run.var_pairs
    # a free harmonic fit leaves a few points with small dof; the mean of |z|^2 is 1 per entry
    assert 0.85 < float(np.mean(z2)) < 1.2
    one = workflow.load_run(files["one_repeat"], nominal)
    d = np.abs(run.frf_pairs[:, 0] - one.frf) ** 2 / (run.var_pairs[:, 0] + one.output_var / np.abs(one.W) ** 2)
    assert float(np.mean(d)) < 3.0


def test_xy_end_to_end_detects_at_least_as_much_as_one_channel(files, xy_validated: Path, tmp_path: Path,  # type: ignore[no-untyped-def]
                                                                capsys: pytest.CaptureFixture) -> None:
    """fit-noise, validate and detect (per-point certified rule) on the x/y files: the crack is damage
    (exit 1) with at least as many certified fault points as the one-channel sweep of the same crack and
    seed; the healthy repeat is healthy (exit 0, default rule: the joint test, whose benign model error factor
    is compared between the layouts)."""
    docs = {}
    for tag in ("xy", "one"):
        out = tmp_path / tag
        if tag == "xy":  # the module's fit-noise and validate of the x/y healthy sweep
            shutil.copytree(xy_validated, out)
        else:
            assert main(["fit-noise", str(files[f"{tag}_healthy"]), "--out", str(out)]) == EXIT_OK
            assert main(["validate", str(files[f"{tag}_healthy"]), "--out", str(out), "--no-plots"]) == EXIT_OK
        capsys.readouterr()
        assert main(["detect", str(files[f"{tag}_crack"]), "--out", str(out), "--no-plots", "--json",
                     "--rule", "certified"]) == EXIT_DAMAGE
        docs[tag] = json.loads(capsys.readouterr().out)
        # the default rule (the joint test) on the healthy repeat: its benign model, and so its model-error
        # factor kappa, is the baseline's (healthy FRF, channel pairs, speed), whichever sweep is tested
        assert main(["detect", str(files[f"{tag}_repeat"]), "--out", str(out), "--no-plots", "--json",
                     "--force"]) == EXIT_OK
        docs[f"{tag}_joint"] = json.loads(capsys.readouterr().out)
        assert docs[f"{tag}_joint"]["verdict_rule"] == JOINT_RULE
    xy, one = docs["xy"], docs["one"]
    assert xy["n_fault_points"] >= one["n_fault_points"] > 0
    # the joint test: one channel predicts benign change on the modal anchor (kappa 0.1). The x/y sweep at 1000 rpm:
    # on all eight pairs the anchor is refused (several pairs of a spinning rotor: the isotropic model's circular whirl
    # modes cannot stand for the anisotropic rig's elliptical ones in the cross pairs), so the joint test runs on the
    # in-plane pairs whose anchor holds (workflow.benign.anchored_pairs), on the anchor too, and says so
    assert docs["one_joint"]["benign_model_error"] == workflow.KAPPA_MODAL
    assert docs["xy_joint"]["benign_model_error"] == workflow.KAPPA_MODAL
    assert any("in-plane channel pairs" in n for n in docs["xy_joint"]["notes"]), docs["xy_joint"]["notes"]


def test_detect_refuses_other_channels_than_the_baseline(files, xy_validated: Path, tmp_path: Path,  # type: ignore[no-untyped-def]
                                                         capsys: pytest.CaptureFixture) -> None:
    out = shutil.copytree(xy_validated, tmp_path / "b")  # the x/y baseline
    assert main(["detect", str(files["one_crack"]), "--out", str(out), "--no-plots"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "/channels" in err and "s6.x<-s8.x" in err and "s2.y<-s8.y" in err


def test_a_sweep_without_the_rigs_actuator_is_refused(rigs, tmp_path: Path) -> None:
    truth, _ = rigs
    sw = simulate_rig_patterns(truth, GRID[:20], [Port(station=8, direction="y")], [Port(station=6, direction="x")],
                               speed_rpm=0.0, seed=1)
    path = tmp_path / "y_only.h5"
    write_sweep(sw, path)
    with pytest.raises(workflow.InputError, match=r"actuator port \(s8.x\)"):
        workflow.load_run(path, load_config(configs_dir() / "crack_rig.yaml"))


def test_simulate_several_actuators_and_sensors(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """`simulate --actuator 8x --actuator 8y --sensor 6x --sensor s2.y`: a version-2 sweep with two patterns,
    each driving one actuator only; a malformed port exits 2 naming the option."""
    from rotorcheck.sweep import read_sweep

    out = tmp_path / "xy.h5"
    assert main(["simulate", str(out), "--speed", "1000", "--actuator", "8x", "--actuator", "8y", "--sensor", "6x",
                 "--sensor", "s2.y", "--points", "12", "--periods", "4"]) == EXIT_OK
    sw = read_sweep(out)
    run = next(iter(sw.runs.values()))
    assert [c.name for c in sw.inputs] == ["force_s8_x", "force_s8_y"] and len(sw.outputs) == 2
    assert run.n_exc == 2
    X = run.input_phasor_exc
    assert np.all(np.abs(X[:, 0, 1]) == 0) and np.all(np.abs(X[:, 1, 0]) == 0) and np.all(np.abs(X[:, 0, 0]) > 0)
    assert main(["simulate", str(tmp_path / "bad.h5"), "--actuator", "8q"]) == EXIT_INPUT
    assert "--actuator" in capsys.readouterr().err


def test_xy_at_standstill_where_the_cross_pairs_are_silent(sample_pipeline: Callable[..., tuple[Any, Any]]) -> None:
    """At 0 rpm the x and y planes decouple: the model's x -> y receptances are round-off. The bundled x/y
    open-crack sample is still damage, with those pairs predicting no change (signature rows zero there)
    and certified nowhere; more certified fault points than the one-channel sample of the same crack."""
    from rotorcheck.resources import samples_dir
    from rotorcheck.signatures import crack_signatures, io_frf

    nominal = load_config(configs_dir() / "crack_rig.yaml")
    out = {}
    for tag in ("crack_rig_xy", "crack_rig"):  # fit-noise, validate (measured), detect: shared (conftest)
        h = workflow.load_run(samples_dir() / tag / "healthy_0rpm.h5", nominal)
        _, res = sample_pipeline(configs_dir() / "crack_rig.yaml", samples_dir() / tag / "healthy_0rpm.h5",
                                 samples_dir() / tag / "open_crack_0rpm.h5", "measured")
        out[tag] = (h, res)
    h, res = out["crack_rig_xy"]
    assert res.verdict.verdict == "damage" and res.joint.damage
    g0 = io_frf(nominal, h.frequency_hz, 0.0, h.pairs)
    silent = [k for k, p in enumerate(h.pairs) if p.output.direction != p.input.direction]
    assert len(silent) == 4 and np.max(np.abs(g0[:, silent])) < 1e-9 * np.max(np.abs(g0))  # round-off
    _, S = crack_signatures(nominal, h.frequency_hz, 0.0, workflow.frf_estimate(h).frf, pairs=h.pairs)
    nf = h.frequency_hz.size
    assert all(np.all(S[:, k * nf:(k + 1) * nf] == 0) for k in silent)
    assert res.detection.n_fault > out["crack_rig"][1].detection.n_fault


@pytest.fixture(scope="module")
def xy_open_crack(sample_pipeline: Callable[..., tuple[object, object]]) -> tuple[object, object]:
    """The open crack at standstill with x and y probes (8 channel pairs), measured baseline."""
    from rotorcheck.resources import samples_dir

    xy = samples_dir() / "crack_rig_xy"
    return sample_pipeline(configs_dir() / "crack_rig.yaml", xy / "healthy_0rpm.h5", xy / "open_crack_0rpm.h5",
                           "measured")


def test_decision_with_several_pairs_plots_the_statistic_that_decided(xy_open_crack: tuple) -> None:
    """8 channel pairs (the bundled x/y open crack at standstill, the detection of the test above): a point is a
    fault when any pair (or the damage-direction test) exceeds its allowance; the plotted ratio is that largest
    one, so red points are exactly those above 1, grey ones at or below; the largest pair ratio computed here from
    the distances and radii is never above the plotted one."""
    _, out = xy_open_crack
    rep = out.report()  # type: ignore[attr-defined]
    assert len(rep["channel_pairs"]) == 8 and rep["n_fault_points"] > 0
    figs = workflow.detection_figures(out)  # type: ignore[arg-type]
    ax = figs["detection_decision"].axes[0]
    f = out.run.frequency_hz  # type: ignore[attr-defined]
    m = out.measured  # type: ignore[attr-defined]
    pair_ratio = np.max(m.distance / m.radius, axis=1)
    n_red = 0
    for ln in ax.get_lines():
        key = ln.get_gid() or str(ln.get_label())
        if key != "fault_points" and not key.startswith("explained"):
            continue
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        idx = np.searchsorted(f, x)
        assert np.all(pair_ratio[idx] <= y * (1 + 1e-9))
        if key == "fault_points":
            assert np.all(y > 1.0)
            n_red = len(x)
        else:
            assert np.all(y <= 1.0)
    assert n_red == rep["n_fault_points"]
    bode = figs["detection_bode"].axes[0]
    assert any("in any of the 8 pairs" in str(ln.get_label()) for ln in bode.get_lines())
    assert "(1 of 8 channel pairs)" in bode.get_title()


LOSS_X4 = 2.0e5  # N/m: a stiffness loss at station 4 in x only (the damage port's station)


def _xy_pairs() -> list[ChannelPair]:
    """The 8 pairs of the x/y set, the rig's actuator -> sensor first."""
    rest = [(o, i) for o in SENSORS for i in ACTUATORS if (o, i) != (SENSORS[0], ACTUATORS[0])]
    return [ChannelPair(SENSORS[0], ACTUATORS[0], "io")] + [ChannelPair(o, i, f"{k}") for k, (o, i) in enumerate(rest)]


def _dense_frfs(rig: RigConfig, speed: float, f: np.ndarray, pairs: list[ChannelPair], loss: float) -> np.ndarray:
    """Each pair's FRF (f, P) by dense solves of the FE matrices with ``loss`` N/m taken from station 4 x."""
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.system import RPM_TO_RAD_S

    sys_ = build_system(rig)
    M, C, G, K = sys_.matrices(speed)
    D = C + speed * RPM_TO_RAD_S * G
    K = K.copy()
    dx = sys_.port_dof(Port(station=4, direction="x"))
    K[dx, dx] -= loss
    H = [np.linalg.inv(K - (2 * np.pi * x) ** 2 * M + 2j * np.pi * x * D) for x in f]
    return np.array([[h[sys_.port_dof(p.output), sys_.port_dof(p.input)] for p in pairs] for h in H])


def _pair_run(rig: RigConfig, speed: float, f: np.ndarray, pairs: list[ChannelPair], frf: np.ndarray,
              var: np.ndarray) -> workflow.MeasuredRun:
    """A several-pair run from given FRFs and their variances (variances treated as known)."""
    from pathlib import Path as P

    return workflow.MeasuredRun(P("x.h5"), "", rig.rig_id, "r", speed, f, np.ones(f.size, complex), frf[:, 0],
                                np.zeros(f.size), np.zeros(f.size, int), (30.0, 600.0), pairs=tuple(pairs),
                                frf_pairs=frf, var_pairs=var, dof_pairs=np.full(var.shape, np.inf))


def test_damage_dynamics_per_direction_recovers_a_spring_at_the_damage_port() -> None:
    """Noiseless FRFs of the nominal model by dense solves, before and after a stiffness loss of 2e5 N/m
    at station 4 in x only: D_xx = 2e5 N/m (to 1e-3: the engine's model receptances against dense
    solves), D_yy and the cross terms below 1e-6 of it, at every frequency, 1000 rpm (gyroscopic
    coupling of x and y)."""
    rig = load_config(configs_dir() / "crack_rig.yaml")
    speed, f, pairs = 1000.0, np.linspace(30.0, 600.0, 40), _xy_pairs()
    Th, Tn = _dense_frfs(rig, speed, f, pairs, 0.0), _dense_frfs(rig, speed, f, pairs, LOSS_X4)
    res = workflow.damage_per_direction(rig, _pair_run(rig, speed, f, pairs, Tn, np.zeros(Tn.shape)), Th)
    assert res is not None and res.draws == 0
    Dd = res.estimate
    assert Dd.shape == (f.size, 2, 2)
    assert np.max(np.abs(Dd[:, 0, 0] / LOSS_X4 - 1)) < 1e-3
    assert np.max(np.abs(Dd[:, 1, 1])) < 1e-6 * LOSS_X4 and np.max(np.abs(Dd[:, [0, 1], [1, 0]])) < 1e-6 * LOSS_X4


def test_enclose_data_with_several_pairs_brackets_the_closed_form(files) -> None:  # type: ignore[no-untyped-def]
    """`--enclose data` on the 4 x 2 sweep: one experiment per input (unit force) against the additive
    full block over the model's FRF matrix. With W = e_i only column i of Delta acts, so the smallest
    sigma_max(Delta) per experiment is sqrt(sum_o max(0, |r_oi| - V)^2) (r: the data minus the model);
    gamma_h (max over the experiments) is bracketed by the LMI's certified lower and verified upper bounds
    at every point. `system`: the closed form sqrt(sum_o (|r_oi| + V)^2) per experiment, checked against
    the largest distance of 4000 outputs drawn on the data polydisc's boundary (never above it, within
    0.2 % of it)."""
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    run = workflow.load_run(files["xy_healthy"], nominal)
    me, W, Z, V = workflow.pair_experiments(nominal, run)
    n_in, n_out = len(W), Z[0].shape[1]
    G = me[:, n_in:, n_out:]  # the model's FRF matrix inside Me = [[0, I_in], [I_out, G]]
    ref = np.max([np.sqrt(np.sum(np.maximum(np.abs(z - G[:, :, i]) - V[:, None], 0.0) ** 2, axis=1))
                  for i, z in enumerate(Z)], axis=0)
    val = workflow.validate(nominal, [run], workflow.fit_noise(run), enclose="data")
    res = val.result
    ok = res.status == "ok"
    assert ok.mean() > 0.95
    assert np.all(res.gamma_lower[ok] <= ref[ok] * (1 + 1e-6))
    assert np.all(res.gamma_upper[ok] >= ref[ok] * (1 - 1e-6))
    sysres = workflow.validate(nominal, [run], workflow.fit_noise(run), enclose="system").result
    rng = np.random.default_rng(4)
    for k in rng.choice(run.frequency_hz.size, 5, replace=False):
        best = 0.0
        for i, z in enumerate(Z):
            phases = np.exp(2j * np.pi * rng.random((4000, n_out)))
            phases[0] = (z[k] - G[k, :, i]) / np.abs(z[k] - G[k, :, i])  # the farthest corner
            best = max(best, float(np.max(np.linalg.norm(z[k] + V[k] * phases - G[k, :, i], axis=1))))
        assert best <= sysres.gamma[k] * (1 + 1e-12) and best >= sysres.gamma[k] * (1 - 2e-3)


def test_damage_per_direction_intervals_cover_the_truth() -> None:
    """The same 2e5 N/m loss in x, both sweeps with complex Gaussian noise of 0.3 % of |T| per pair: the
    95 % Monte Carlo interval of Re D_xx contains 2e5 N/m at 85-100 % of the frequencies (nominal 95 %,
    40 points), its width grows with the noise, and with no noise it has zero width."""

    rig = load_config(configs_dir() / "crack_rig.yaml")
    speed, f, pairs = 1000.0, np.linspace(30.0, 600.0, 40), _xy_pairs()
    Tn = _dense_frfs(rig, speed, f, pairs, LOSS_X4)
    Th = pair_receptance(rig, f, speed, pairs)  # the engine's healthy model: its E's are exact for it
    rng = np.random.default_rng(5)

    def noise(v: np.ndarray) -> np.ndarray:
        return np.sqrt(v / 2) * (rng.standard_normal(v.shape) + 1j * rng.standard_normal(v.shape))

    widths = []
    for rel in (0.0, 0.003, 0.006):
        var_n, var_h = (rel * np.abs(Tn)) ** 2, (rel * np.abs(Th)) ** 2
        tn, th = Tn + noise(var_n), Th + noise(var_h)
        res = workflow.damage_per_direction(rig, _pair_run(rig, speed, f, pairs, tn, var_n), th, var_h, draws=400)
        assert res is not None and res.draws == 400
        lo, hi = res.re_interval[0][:, 0], res.re_interval[1][:, 0]
        widths.append(float(np.median(hi - lo)))
        if rel > 0:
            inside = np.mean((lo <= LOSS_X4) & (LOSS_X4 <= hi))
            assert 0.85 <= inside <= 1.0, inside
    assert widths[0] < 1e-6 * LOSS_X4 and widths[0] < widths[1] < widths[2]


def test_damage_per_direction_certified_bound_holds_the_truth_where_the_noise_is_within_its_radius() -> None:
    """The certified set of D (robust.damage_block) in the workflow: the 2e5 N/m loss in x with noise drawn
    inside each pair's radius (uniform in the disc, 0.5 % of |T|): the truth lies in the outer Re and Im
    intervals of D_xx and D_yy at every bounded frequency (it is a member of the set: no statistics
    involved), the witnesses' range lies inside the outer one, and the estimate is the weighted least-
    squares member; with a 4x larger radius the median outer width grows about 4x (first order)."""
    rig = load_config(configs_dir() / "crack_rig.yaml")
    speed, f, pairs = 1000.0, np.linspace(40.0, 560.0, 12), _xy_pairs()
    Tn = _dense_frfs(rig, speed, f, pairs, LOSS_X4)
    Th = pair_receptance(rig, f, speed, pairs)
    rng = np.random.default_rng(8)
    widths = []
    for rel in (0.005, 0.02):
        radius = rel * np.abs(Tn)
        u = np.sqrt(rng.random(Tn.shape)) * np.exp(2j * np.pi * rng.random(Tn.shape))
        tn = Tn + 0.9 * radius * u
        res = workflow.damage_per_direction(rig, _pair_run(rig, speed, f, pairs, tn, np.zeros(Tn.shape)), Th,
                                            radius=radius)
        assert res is not None and res.bound is not None
        b = res.bound
        ok = b.kind == "bounded"
        assert ok.mean() >= 0.75, b.kind
        truth = np.array([LOSS_X4, 0.0])
        for k in range(2):
            assert np.all(b.re_outer[ok, k, 0] <= truth[k]) and np.all(truth[k] <= b.re_outer[ok, k, 1])
            assert np.all(b.im_outer[ok, k, 0] <= 0.0) and np.all(0.0 <= b.im_outer[ok, k, 1])
            assert np.all(b.re_outer[ok, k, 0] <= b.re_inner[ok, k, 0] * (1 + 1e-9) + 1e-9)
            assert np.all(b.re_inner[ok, k, 1] <= b.re_outer[ok, k, 1] * (1 + 1e-9) + 1e-9)
        widths.append(float(np.median(b.re_outer[ok, 0, 1] - b.re_outer[ok, 0, 0])))
    assert 3.0 < widths[1] / widths[0] < 5.5, widths


def test_in_plane_signature_zeroes_exactly_the_cross_plane_pairs() -> None:
    """A turning shaft's GLR direction (workflow.benign.in_plane): the x force -> y probe and y -> x pairs' part of
    every crack signature is 0, the in-plane pairs' part is the signature itself, pair after pair."""
    from rotorcheck.workflow.benign import in_plane

    def pair(out: str, inp: str) -> ChannelPair:
        return ChannelPair(Port(station=6, direction=out), Port(station=8, direction=inp), f"6{out}/8{inp}")  # type: ignore[arg-type]

    pairs = [pair("x", "x"), pair("x", "y"), pair("y", "x"), pair("y", "y")]
    nf = 5
    rng = np.random.default_rng(2)
    S = rng.standard_normal((3, 4 * nf)) + 1j * rng.standard_normal((3, 4 * nf))
    out = in_plane(S, pairs, nf)
    for k, keep in enumerate((True, False, False, True)):
        part = slice(k * nf, (k + 1) * nf)
        assert np.array_equal(out[:, part], S[:, part] if keep else np.zeros((3, nf)))
    assert not np.shares_memory(out, S)
