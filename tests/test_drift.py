"""Drift learned from several healthy sweeps on the modal anchor (``validate --learn-drift``,
:mod:`rotorcheck.workflow.drift`; issue 29: more healthy sweeps must not make the detector blinder).

Checked against closed forms (the binomial tail, the moved ranges, the centre's set), Monte Carlo (the mean's
Student-t interval) and the simulator, whose states are known: four sweeps of the truth rig at Young's modulus
-1.6 / -0.4 / +0.7 / +1.6 % learn where the kept sweep sits (true centre -0.625 % from it), a new healthy sweep
inside the declared ranges but 2.6 % from the kept sweep is no alarm any more, and a 5 % loss still is.
"""

from __future__ import annotations

from math import comb
from pathlib import Path

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.baseline import read_baseline, write_baseline
from rotorcheck.config import RigConfig, load_config
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig
from rotorcheck.variability import benign_parameters, pair_ranges, recentred_rig, with_benign
from rotorcheck.workflow.drift import _mean_interval, allowed_alarms, drift_centre

F = np.linspace(30.0, 600.0, 120)
E_STATES = (-0.016, -0.004, 0.007, 0.016)


def test_allowed_alarms_is_the_binomial_tail() -> None:
    """The largest m with P(X >= m) > 1 %, X ~ Binomial(n, p), summed by hand."""
    for n in (0, 1, 2, 9, 29, 99):
        for p in (0.01, 0.05):
            def tail(m: int, n: int = n, p: float = p) -> float:
                return sum(comb(n, j) * p**j * (1 - p) ** (n - j) for j in range(m, n + 1))
            want = max((m for m in range(n + 1) if tail(m) > 0.01), default=0)
            assert allowed_alarms(n, p) == want, (n, p)
    assert (allowed_alarms(2, 0.01), allowed_alarms(9, 0.01), allowed_alarms(29, 0.01)) == (1, 1, 2)


def test_recentred_ranges_move_factors_only() -> None:
    rig = load_config(configs_dir() / "crack_rig.yaml")
    moved = {p.name: (p.lo, p.hi) for p in benign_parameters(
        recentred_rig(rig, {"youngs_modulus": 0.005, "speed": 7.0}, {"youngs_modulus": 0.003}))}
    np.testing.assert_allclose(moved["youngs_modulus"], (-0.02 + 0.005 - 0.003, 0.02 + 0.005 + 0.003), atol=1e-12)
    np.testing.assert_allclose(moved["bearing_stiffness.nme"], (-0.03, 0.03), atol=1e-12)
    np.testing.assert_allclose(moved["speed"], (-20.0, 20.0))  # the speed tolerance is never moved
    pairs = {p.name: (p.lo, p.hi) for p in benign_parameters(pair_ranges(rig, 0.0))}
    np.testing.assert_allclose(pairs["youngs_modulus"], (-0.04, 0.04), atol=1e-12)
    np.testing.assert_allclose(pairs["sensor_gain"], (-0.02, 0.02), atol=1e-12)
    assert recentred_rig(rig, {}, {}) is rig


def test_mean_interval_holds_its_rate() -> None:
    """Student t on normal draws: 95 % coverage of the mean (Monte Carlo, 4000 sets of 3 and of 10)."""
    rng = np.random.default_rng(3)
    for k in (3, 10):
        lo, hi = _mean_interval(rng.standard_normal((k, 4000)))
        cover = float(np.mean((lo <= 0.0) & (0.0 <= hi)))
        assert abs(cover - 0.95) < 0.012, (k, cover)


def test_drift_centre_is_the_set_the_declared_ranges_allow() -> None:
    lo, hi = np.array([-0.02]), np.array([0.02])
    theta = np.array([[-0.015], [0.0], [0.015]])  # relative to the middle one
    c_lo, c_hi, beyond = drift_centre(theta, np.zeros_like(theta), lo, hi)
    # the ranges allow centres with every state within 2 % of them: [0.015 - 0.02, -0.015 + 0.02]
    np.testing.assert_allclose([c_lo[0], c_hi[0]], [-0.005, 0.005], atol=1e-12)
    assert not beyond[0]
    # a state's standard error widens that set by 1.96 of it
    c_lo, c_hi, _ = drift_centre(theta, np.full_like(theta, 0.001), lo, hi)
    np.testing.assert_allclose([c_lo[0], c_hi[0]], [-0.005 - 0.00196, 0.005 + 0.00196], atol=1e-12)
    # states further apart than the ranges' width: no centre fits them, the mean's t interval stands
    wide = np.array([[-0.03], [0.0], [0.03]])
    c_lo, c_hi, beyond = drift_centre(wide, np.zeros_like(wide), lo, hi)
    m_lo, m_hi = _mean_interval(wide)
    assert beyond[0] and c_lo[0] == m_lo[0] and c_hi[0] == m_hi[0]


@pytest.fixture(scope="module")
def rigs() -> tuple[RigConfig, RigConfig]:
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    truth = load_config(configs_dir() / "crack_rig_truth.yaml").model_copy(update={"variability": nominal.variability})
    return nominal, truth


def _run(truth: RigConfig, nominal: RigConfig, seed: int, e: float = 0.0, loss: float = 0.0) -> workflow.MeasuredRun:
    cfg = with_benign(truth, {"youngs_modulus": e})[0] if e else truth
    fault = None
    if loss:
        faults = dict(cfg.faults)
        faults["open_crack"] = faults["open_crack"].model_copy(update={"modulus_factor": 1.0 - loss})
        cfg, fault = cfg.model_copy(update={"faults": faults}), "open_crack"
    return workflow.measured_run(simulate_rig(cfg, F, 0.0, seed=seed, fault=fault), nominal)


@pytest.fixture(scope="module")
def learned(rigs: tuple[RigConfig, RigConfig]) -> tuple[workflow.ValidationOutcome, workflow.ValidationOutcome]:
    nominal, truth = rigs
    runs = [_run(truth, nominal, 40 + k, e) for k, e in enumerate(E_STATES)]
    noise = workflow.fit_noise(runs[0])
    return (workflow.validate(nominal, runs, noise),  # learned by default: 4 sweeps differing beyond their noise
            workflow.validate(nominal, runs, noise, learn_drift=False))


def test_the_sweeps_say_where_the_kept_sweep_sits(learned) -> None:
    out, _ = learned
    ref = out.healthy_run
    assert ref == 2  # the most central state, +0.7 %
    lrn = out.learning
    assert lrn is not None
    k = lrn.names.index("youngs_modulus")
    rel = (1.0 + np.array(E_STATES)) / (1.0 + E_STATES[ref]) - 1.0
    np.testing.assert_allclose(lrn.theta[:, k], rel, atol=0.002)  # each state fitted on the anchor
    centre = float(np.mean(rel))
    assert abs(lrn.shift[k] - centre) <= lrn.widen[k] and lrn.widen[k] < 0.012, (lrn.shift[k], lrn.widen[k])
    assert lrn.kappa == workflow.KAPPA_MODAL and "youngs_modulus: ranges moved by" in lrn.summary()
    assert out.baseline.drift.range_shift == pytest.approx(lrn.shift_by_name)
    # validate --json states the ranges the detector's rig will read (workflow.rigs.baseline_rig)
    doc = out.typed_report(workflow.fit_noise(out.runs[0]), "baseline.h5").to_dict()["learned_drift"]
    read = {p.name: p for p in benign_parameters(workflow.baseline_rig(out.rig, out.baseline))}
    for row in doc["parameters"]:
        assert row["range"] == pytest.approx([100 * read[row["name"]].lo, 100 * read[row["name"]].hi], abs=1e-9)
    assert doc["kept_sweep"] == 3 and doc["kappa"] == lrn.kappa


def test_learning_is_refused_where_it_cannot_hold(learned, rigs) -> None:
    """Asked for with fewer than 3 sweeps or against the model (``--enclose system``): an InputError naming the
    option; two drifted sweeps by default: nothing learned (the ranges about the kept sweep)."""
    nominal, truth = rigs
    runs = [_run(truth, nominal, 40 + k, e) for k, e in enumerate(E_STATES[:2])]
    noise = workflow.fit_noise(runs[0])
    with pytest.raises(workflow.InputError, match="at least 3"):
        workflow.validate(nominal, runs, noise, learn_drift=True)
    assert workflow.validate(nominal, runs, noise).learning is None
    with pytest.raises(workflow.InputError, match="--enclose measured"):
        workflow.validate(nominal, runs + runs[:1], noise, enclose="system", learn_drift=True)


def test_a_state_inside_the_ranges_is_no_alarm_and_a_loss_still_is(learned, rigs, tmp_path: Path) -> None:
    """A healthy sweep at E -1.9 % (inside the declared +-2 %, 2.6 % from the kept sweep): damage against the
    ranges read about the kept sweep, healthy with the learned centre; a 5 % loss of the crack element at the
    sweeps' centre is damage with both; the learned ranges survive the baseline file."""
    out, plain = learned
    nominal, truth = rigs
    drifted = _run(truth, nominal, 90, -0.019)
    assert workflow.detect(nominal, plain.baseline, drifted).verdict.verdict == "damage"
    assert workflow.detect(nominal, out.baseline, drifted).verdict.verdict == "healthy"
    cracked = _run(truth, nominal, 91, float(np.mean(E_STATES)), loss=0.05)
    assert workflow.detect(nominal, out.baseline, cracked).verdict.verdict == "damage"
    path = tmp_path / "baseline.h5"
    write_baseline(out.baseline, path)
    back = read_baseline(path)
    assert back.drift.range_shift == pytest.approx(out.baseline.drift.range_shift)
    assert back.drift.range_widen == pytest.approx(out.baseline.drift.range_widen)
    assert back.drift.on_anchor and back.benign_kappa == out.learning.kappa
    assert workflow.detect(nominal, back, drifted).verdict.verdict == "healthy"


def test_a_damaged_sweep_among_the_healthy_ones_is_named(rigs) -> None:
    """Five training sweeps, the one at E +1.6 % with a 10 % loss of the crack element: left out and tested against
    the others it reads as damage, and validate's summary names it (the others do not)."""
    nominal, truth = rigs
    runs = [_run(truth, nominal, 40 + k, e) for k, e in enumerate(E_STATES[:3])]
    runs += [_run(truth, nominal, 60, 0.0), _run(truth, nominal, 61, 0.016, loss=0.10)]
    out = workflow.validate(nominal, runs, workflow.fit_noise(runs[0]))
    assert out.learning is not None and out.healthy_run != 4
    assert out.learning.alarmed == (4,)
    assert "warning: sweep(s) 5," in out.learning.summary()


def test_healthy_sweeps_at_measured_speeds_within_the_tolerance_are_one_operating_point(rigs) -> None:
    """Healthy sweeps of one operating point are never at one exact speed. Three sweeps of the truth rig at 992,
    1000 and 1009 rpm (the shaft speed itself moved, as recorded): ``validate`` takes them (the rig's speed range
    +-20 rpm about the operating point: two sweeps up to 40 rpm apart), the baseline sits at its kept sweep's speed,
    and a new healthy sweep at 1005 rpm is no alarm against it; sweeps 53 rpm apart, or one at standstill beside
    spinning ones, are refused naming the speed field (and the range)."""
    nominal, truth = rigs
    f = np.linspace(30.0, 600.0, 90)

    def spun(rpm: float, seed: int) -> workflow.MeasuredRun:
        return workflow.measured_run(simulate_rig(truth, f, rpm, seed=seed), nominal)

    runs = [spun(rpm, 70 + k) for k, rpm in enumerate((992.0, 1000.0, 1009.0))]
    out = workflow.validate(nominal, runs, workflow.fit_noise(runs[0]))
    kept = runs[0] if out.healthy_run is None else runs[out.healthy_run]
    assert out.baseline.speed_rpm == kept.speed_rpm
    found = workflow.detect(nominal, out.baseline, spun(1005.0, 80))
    assert found.verdict.verdict == "healthy", found.verdict.reason
    with pytest.raises(workflow.InputError, match="speed range allows") as err:
        workflow.validate(nominal, [*runs, spun(1045.0, 81)], workflow.fit_noise(runs[0]))
    assert "@speed_rpm" in str(err.value) and "(variability: speed +-20 rpm)" in str(err.value)
    at_rest = workflow.measured_run(simulate_rig(truth, f, 0.0, seed=82), nominal)
    with pytest.raises(workflow.InputError, match=r"992 rpm differs .* [(]0 rpm[)]$"):
        workflow.validate(nominal, [runs[0], at_rest], workflow.fit_noise(runs[0]))
