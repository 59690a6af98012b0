"""Harmonic balance of the cracked rotor: against the full Hill matrix and an independent dense HB
(tests/oracles/hb.py), the healthy and open-crack limits, conjugate symmetry, convergence in H,
unbalance harmonics and critical speeds on the rig."""

from __future__ import annotations

import numpy as np
import pytest
from faults_helpers import CONFIGS, HAVE_ASSEMBLY, RIG_CRACK, eq_5_24, small_rotor

from rotorcheck.config import Crack, UnbalanceMass, load_config
from rotorcheck.faults.crack import crack_stiffness
from rotorcheck.faults.harmonic_balance import convergence_table, cracked_tones, fold_tones, solve_hb
from rotorcheck.fe.frf import Receptance
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from tests.oracles.hb import harmonic_balance_plant, hill_matrix

needs_assembly = pytest.mark.skipif(not HAVE_ASSEMBLY, reason="rotorcheck.fe.assembly missing")

JUN = Crack(
    element=4,
    model="jun",
    angle=0.4,
    jun_b_xi=[0.7, 0.25, 0.05],
    jun_b_eta=[0.9, 0.08],
    jun_a=[0.04, 0.02],
)


def _direct(system: MechanicalSystem, k: np.ndarray, speed: float, f: float, b: np.ndarray) -> np.ndarray:
    M, C, G, _ = system.matrices(speed)
    w = 2 * np.pi * f
    return np.linalg.solve(k - w**2 * M + 1j * w * (C + speed * RPM_TO_RAD_S * G), b)


@pytest.mark.parametrize("crack", [RIG_CRACK, RIG_CRACK.model_copy(update={"model": "gasch"}), JUN])
def test_reduced_solve_equals_full_hill_matrix(rotor: MechanicalSystem, crack: Crack) -> None:
    ck = crack_stiffness(rotor, crack, n_terms=7)
    n, H = rotor.n_dof, 6
    ind, outs = rotor.dof(8, "x"), [rotor.dof(6, "x"), rotor.dof(6, "y"), rotor.dof(3, "y")]
    for f in (23.0, 54.0, 170.0):
        res = solve_hb(rotor, ck, 1000.0, f, ind, outs, H)
        A = hill_matrix(rotor, ck, 1000.0, f, H)
        rhs = np.zeros((2 * H + 1) * n, complex)
        rhs[H * n + ind] = 1.0
        q = np.linalg.solve(A, rhs).reshape(2 * H + 1, n)[:, outs]
        assert np.abs(res.out[0, :, :, 0] - q).max() <= 1e-9 * np.abs(q).max()


def test_modal_and_direct_receptance_agree(rotor: MechanicalSystem) -> None:
    M, C, G, K = rotor.matrices(1000.0)
    D = C + 1000 * RPM_TO_RAD_S * G
    cols = np.eye(rotor.n_dof)[:, [3, 17, 29]]
    rows = np.array([0, 5, 21])
    a, b = Receptance(M, D, K, rows, cols, "modal"), Receptance(M, D, K, rows, cols, "direct")
    nu = 2 * np.pi * np.array([[-80.0, 12.0, 54.6], [171.0, 333.0, 1500.0]])
    assert np.abs(a(nu) - b(nu)).max() <= 1e-9 * np.abs(b(nu)).max()
    assert Receptance(M, D, K, rows, cols, "auto").method == "modal"


def test_closed_crack_gives_the_healthy_response(rotor: MechanicalSystem) -> None:
    ind, out = rotor.dof(8, "x"), rotor.dof(6, "x")
    f = np.array([31.0, 54.6, 140.0, 530.0])
    b = np.zeros(rotor.n_dof)
    b[ind] = 1.0
    K = rotor.matrices(1000.0)[3]
    ref = np.array([_direct(rotor, K, 1000.0, fi, b)[out] for fi in f])
    closed = [
        crack_stiffness(rotor, RIG_CRACK, steering=lambda th: 0.0 * th),
        crack_stiffness(rotor, JUN.model_copy(update={"jun_b_xi": [1.0], "jun_b_eta": [1.0], "jun_a": []})),
    ]
    for ck in closed:
        res = solve_hb(rotor, ck, 1000.0, f, ind, [out], 6, method="direct")
        assert np.abs(res.fundamental[:, 0, 0] - ref).max() <= 1e-12 * np.abs(ref).max()
        res = solve_hb(rotor, ck, 1000.0, f, ind, [out], 6)  # modal receptances: ~1e-10
        assert np.abs(res.fundamental[:, 0, 0] - ref).max() <= 1e-9 * np.abs(ref).max()
        others = np.delete(res.out[:, :, 0, 0], 6, axis=1)
        assert np.abs(others).max() == 0.0


def test_custom_steering_matches_builtin(rotor: MechanicalSystem) -> None:
    a = crack_stiffness(rotor, RIG_CRACK)
    b = crack_stiffness(rotor, RIG_CRACK, steering=lambda th: 0.5 * (1 - np.cos(th)), n_terms=4)
    ra = solve_hb(rotor, a, 1000.0, [40.0, 200.0], rotor.dof(8, "x"), [rotor.dof(6, "x")], 8)
    rb = solve_hb(rotor, b, 1000.0, [40.0, 200.0], rotor.dof(8, "x"), [rotor.dof(6, "x")], 8)
    assert np.abs(ra.out - rb.out).max() <= 1e-12 * np.abs(ra.out).max()


def test_non_rotating_open_crack_equals_time_invariant_eq_5_24(rotor: MechanicalSystem) -> None:
    # Omega = 0, crack at theta = pi (fully open); up_angle = pi puts the xi axis along +x at
    # theta = pi, so the fixed-frame reduction is eq. 5.24 itself (typed in from the dissertation)
    crack = RIG_CRACK.model_copy(update={"angle": np.pi})
    ck = crack_stiffness(rotor, crack, up_angle=np.pi)
    el = rotor.elements[3]
    dk = eq_5_24(el.youngs_modulus, el.length, ck.delta_xi * el.second_moment, ck.delta_eta * el.second_moment)
    K = rotor.matrices(0.0)[3].copy()
    K[np.ix_(el.dofs, el.dofs)] -= dk
    ind = rotor.dof(8, "x")
    outs = [rotor.dof(6, "x"), rotor.dof(6, "y"), rotor.dof(4, "theta")]
    b = np.zeros(rotor.n_dof)
    b[ind] = 1.0
    b[rotor.dof(8, "y")] = 0.3
    f = np.array([20.0, 50.0, 52.3, 160.0, 400.0])
    ref = np.array([_direct(rotor, K, 0.0, fi, b)[outs] for fi in f])
    res = solve_hb(rotor, ck, 0.0, f, b, outs, 4, method="direct")
    assert np.abs(res.fundamental[:, :, 0] - ref).max() <= 1e-10 * np.abs(ref).max()


@needs_assembly
def test_non_rotating_open_crack_equals_assembly_with_reduced_i() -> None:
    from rotorcheck.fe.assembly import build_system

    cfg = load_config(CONFIGS / "crack_rig.yaml")
    sys0 = build_system(cfg)
    crack = RIG_CRACK.model_copy(update={"angle": np.pi})  # facing down at rest: fully open
    ck = crack_stiffness(sys0, crack, form="timoshenko")
    xp, yp = sys0.plane_dofs()
    kx = build_system(cfg, modulus_factors={4: 1 - ck.delta_eta}).matrices(0)[3]
    ky = build_system(cfg, modulus_factors={4: 1 - ck.delta_xi}).matrices(0)[3]
    K = np.zeros_like(kx)
    K[np.ix_(xp, xp)] = kx[np.ix_(xp, xp)]
    K[np.ix_(yp, yp)] = ky[np.ix_(yp, yp)]
    ind, outs = sys0.dof(8, "x"), [sys0.dof(6, "x"), sys0.dof(6, "y")]
    b = np.zeros(sys0.n_dof)
    b[ind] = 1.0
    b[sys0.dof(8, "y")] = -0.5
    f = np.array([30.0, 51.0, 54.0, 116.0, 172.0, 520.0])
    ref = np.array([_direct(sys0, K, 0.0, fi, b)[outs] for fi in f])
    res = solve_hb(sys0, ck, 0.0, f, b, outs, 3, method="direct")
    assert np.abs(res.fundamental[:, :, 0] - ref).max() <= 1e-10 * np.abs(ref).max()
    assert np.abs(np.delete(res.out, 3, axis=1)).max() == 0.0  # no sidebands at rest


def test_negative_frequency_is_the_conjugate_response(rotor: MechanicalSystem) -> None:
    """Real system: HB at -w is the conjugate of HB at +w with k -> -k (the conj(U) e^{-jwt} half
    of a real force produces the conjugate response)."""
    ck = crack_stiffness(rotor, JUN)
    ind, outs = rotor.dof(8, "x"), [rotor.dof(6, "x"), rotor.dof(6, "y")]
    pos = solve_hb(rotor, ck, 1000.0, 47.0, ind, outs, 7).out[0, :, :, 0]
    neg = solve_hb(rotor, ck, 1000.0, -47.0, ind, outs, 7).out[0, :, :, 0]
    assert np.abs(neg[::-1] - np.conj(pos)).max() <= 1e-10 * np.abs(pos).max()


def test_fold_tones_preserves_the_real_signal() -> None:
    rng = np.random.default_rng(3)
    tones = np.array([-50.0, -16.5, 0.0, 16.5, 33.0, 50.0, 66.5])
    amps = rng.normal(size=(7, 2)) + 1j * rng.normal(size=(7, 2))
    u = 0.7 - 0.4j
    t = np.linspace(0, 0.3, 500)
    sig = np.real(np.exp(2j * np.pi * np.outer(t, tones)) @ (u * amps))
    ff, aa = fold_tones(tones, amps, u)
    assert np.all(ff >= 0) and len(ff) == 5
    sig2 = np.real(np.exp(2j * np.pi * np.outer(t, ff)) @ aa)
    assert np.abs(sig - sig2).max() <= 1e-12 * np.abs(sig).max()


def test_harmonic_count_convergence(rig_system: MechanicalSystem) -> None:
    sys_ = rig_system
    ck = crack_stiffness(sys_, RIG_CRACK)
    tab = convergence_table(sys_, ck, 1000.0, [30.0, 54.5, 171.0, 511.0, 600.0], sys_.dof(8, "x"), sys_.dof(6, "x"))
    rel = tab["rel_to_ref"]  # (H = 1..10, f)
    assert np.all(rel[-1] < 1e-9)
    assert np.all(rel[7] < 1e-7)  # H = 8, the default
    assert np.all(rel[0] > 1e-6)  # H = 1 is visibly not converged
    assert np.all(rel[9] < rel[4]) and np.all(rel[4] < rel[1])


@needs_assembly
def test_plant_matches_the_simulators_independent_dense_hb() -> None:
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.sim.plants import dk_fourier, simulator_plant
    from rotorcheck.sim.simulator import StepSettings, simulate_fast

    cfg = load_config(CONFIGS / "crack_rig_truth.yaml")
    sys_ = build_system(cfg)
    ck = crack_stiffness(sys_, cfg.faults["breathing_crack"])
    ind, out = sys_.port_dof(cfg.ports.actuator), sys_.port_dof(cfg.ports.sensor)
    M, C, G, K = sys_.matrices(1000.0)
    b = np.zeros(sys_.n_dof)
    b[ind] = 1.0
    c = np.zeros((1, sys_.n_dof))
    c[0, out] = 1.0
    theirs = harmonic_balance_plant(M, C + 1000 * RPM_TO_RAD_S * G, K, dk_fourier(sys_, ck), 1000 / 60, b, c, 8)
    mine = cracked_tones(sys_, ck, 1000.0, ind, out, 8)
    for f in (30.0, 54.5, 200.0, 600.0):
        t1, a1 = theirs.tones(f)
        t2, a2 = mine(f)
        assert np.array_equal(t1, t2)
        assert np.abs(a1 - a2).max() <= 1e-8 * np.abs(a2).max()
    # and the simulator accepts the plant: noiseless fast sweep = HB within lock-in leakage
    plant = simulator_plant(sys_, ck, 1000.0, ind, out, 8)
    f = np.array([40.0, 90.0, 300.0])
    run = simulate_fast(plant, f, StepSettings(force_amplitude=1.0))
    got = run.output_phasor[:, 0] / run.input_phasor[:, 0]
    ref = mine.sweep(f).fundamental[:, 0, 0]
    assert np.all(np.abs(got - ref) <= 0.01 * np.abs(ref))


UB = [UnbalanceMass(station=3, amount=0.2e-3, phase=-np.pi / 2)]  # 0.2 g m facing down at t = 0


@needs_assembly
def test_unbalance_spectra_and_critical_speeds() -> None:
    from rotorcheck.faults.analysis import critical_speed_summary, unbalance_harmonics
    from rotorcheck.fe.assembly import build_system

    cfg = load_config(CONFIGS / "crack_rig_truth.yaml")
    sys_ = build_system(cfg)
    crack = cfg.faults["breathing_crack"]  # closed and facing up at t = 0
    outs = [sys_.dof(6, "x"), sys_.dof(6, "y")]
    o, h = unbalance_harmonics(sys_, None, 1000.0, UB, outs)
    amp_h = np.abs(h)
    one = amp_h[o == 1][0]
    assert np.all(amp_h[o != 1] <= 1e-12 * one)
    o, c = unbalance_harmonics(sys_, crack, 1000.0, UB, outs)
    a = {int(k): np.abs(v) for k, v in zip(o, c)}
    assert np.all(a[1] > 10 * a[2]) and np.all(a[1] > 10 * a[3])  # 1X dominant
    assert np.all(a[2] > 0.01 * a[1]) and np.all(a[3] > 0.01 * a[1])  # 2X, 3X present
    assert np.all(a[4] < a[3])
    o, c = unbalance_harmonics(sys_, crack, 750.0, UB, outs)
    a = np.abs(c[(o >= 1) & (o <= 6)])
    assert np.all(np.diff(a, axis=0) < 0)  # 750 rpm: monotonically decreasing harmonics
    summ = critical_speed_summary(sys_, crack, 1000.0, 10000.0, sys_.dof(8, "x"), sys_.dof(6, "x"))
    h_crit = summ["healthy"]["first_critical_rpm"]
    d_crit = summ["averaged"]["first_critical_rpm"]
    assert d_crit < h_crit
    assert 50.0 < d_crit / 60.0 < 56.0  # dissertation: damaged first critical about 55 Hz
    assert summ["hb_resonance_hz"]["cracked"] < summ["hb_resonance_hz"]["healthy"]
    assert summ["open_at_rest"]["modes_hz"][0] < summ["averaged"]["mode1_at_rest_hz"]


def test_small_rotor_fixture_has_the_rig_frequencies() -> None:
    from scipy.linalg import eigh

    M, _, _, K = small_rotor().matrices(0.0)
    f = np.sqrt(eigh(K, M, eigvals_only=True)[[0, 2, 4]]) / (2 * np.pi)
    assert np.allclose(f, [54.6, 172.9, 531.3], atol=0.1)  # rigs.md: 1.65e7 N/m bearings
