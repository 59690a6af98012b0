"""Crack stiffness: eq. 5.25 numbers, eq. 5.24 matrix, rotation (eq. 5.3/5.26), steering sign,
Fourier coefficients, open crack through the assembly."""

from __future__ import annotations

import numpy as np
import pytest
from faults_helpers import CONFIGS, HAVE_ASSEMBLY, RIG_CRACK, eq_5_24, small_rotor, t8

from rotorcheck.config import Crack, load_config
from rotorcheck.faults.breathing import (
    gasch_steering,
    jun_reduction,
    mayes_davies_steering,
)
from rotorcheck.faults.crack import crack_stiffness, delta_i_ratio, rotating_reduction

needs_assembly = pytest.mark.skipif(not HAVE_ASSEMBLY, reason="rotorcheck.fe.assembly missing")


def test_eq_5_25_reproduces_published_reductions() -> None:
    # R = 8 mm, l = 20 mm, nu = 0.3, F_xi = 3.0, F_eta = 0.47 -> 52.2 % and 14.6 % (rigs.md)
    d_xi = delta_i_ratio(3.0, 0.008, 0.020, 0.3)
    d_eta = delta_i_ratio(0.47, 0.008, 0.020, 0.3)
    assert round(100 * d_xi, 1) == 52.2
    assert round(100 * d_eta, 1) == 14.6
    # independent arithmetic: x = 0.4 * 0.91 * F, x / (1 + x)
    assert d_xi == pytest.approx(1.092 / 2.092, rel=1e-12)
    assert d_eta == pytest.approx(0.171080 / 1.171080, rel=1e-12)
    ck = crack_stiffness(small_rotor(), RIG_CRACK)
    assert (ck.delta_xi, ck.delta_eta) == (d_xi, d_eta)


def test_rotating_matrix_is_eq_5_24() -> None:
    sys_ = small_rotor()
    ck = crack_stiffness(sys_, RIG_CRACK)
    el = sys_.elements[3]
    i0 = el.second_moment
    ref = eq_5_24(el.youngs_modulus, el.length, ck.delta_xi * i0, ck.delta_eta * i0)
    got = ck.rotating_matrix(np.pi)[0]  # fully open: f(pi) = 1
    assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max()
    half = ck.rotating_matrix(np.pi / 2)[0]  # Mayes-Davies: f(pi/2) = 1/2
    assert np.abs(half - 0.5 * ref).max() <= 1e-12 * np.abs(ref).max()


def test_fixed_frame_is_eq_5_20_with_eq_5_26_rotation() -> None:
    sys_ = small_rotor()
    for up in (np.pi / 2, 0.3):
        crack = RIG_CRACK.model_copy(update={"angle": 0.7})
        ck = crack_stiffness(sys_, crack, up_angle=up)
        for rot in (0.0, 0.4, 2.0, 4.5):
            theta = 0.7 + rot
            ref = t8(up + theta) @ ck.rotating_matrix(theta)[0] @ t8(up + theta).T
            got = ck.at_rotation(rot)[0]
            assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max() + 1e-9


def test_steering_sign_closed_at_zero_open_at_pi() -> None:
    # eq. 5.13: k_R = (k0 + kc)/2 + (k0 - kc)/2 cos(theta) = k0 - (k0 - kc) f(theta)
    th = np.linspace(-7.0, 7.0, 101)
    k0, kc = 3.0, 1.2
    k_r = 0.5 * (k0 + kc) + 0.5 * (k0 - kc) * np.cos(th)
    assert np.allclose(k_r, k0 - (k0 - kc) * mayes_davies_steering(th), rtol=0, atol=1e-14)
    assert mayes_davies_steering(0.0) == 0.0 and mayes_davies_steering(np.pi) == 1.0
    assert gasch_steering(0.0) == 0.0 and gasch_steering(np.pi) == 1.0
    assert gasch_steering(np.pi / 2) == 1.0 and gasch_steering(1.5 * np.pi) == 0.0
    sys_ = small_rotor()
    ck = crack_stiffness(sys_, RIG_CRACK)  # angle 0: closed at t = 0
    assert np.abs(ck.at_rotation(0.0)).max() == 0.0
    # at theta = pi (crack facing down, xi along -y) the big reduction acts on vertical bending
    k_open = ck.at_rotation(np.pi)[0]
    u1, v1 = 0, 1  # local DOF u1, v1 of the cracked element
    assert k_open[v1, v1] / k_open[u1, u1] == pytest.approx(ck.delta_xi / ck.delta_eta, rel=1e-12)
    assert abs(k_open[u1, v1]) <= 1e-12 * k_open[v1, v1]


def test_fig56_normalized_stiffness() -> None:
    red = rotating_reduction(RIG_CRACK, np.array([0.0, np.pi / 2, np.pi]), 0.3, 0.008)
    assert np.allclose(1 - red[:, 0, 0], [1.0, 1 - 0.5 * 0.5219885, 1 - 0.5219885], atol=1e-7)
    assert round(1 - red[2, 1, 1], 3) == 0.854
    assert round(1 - red[2, 0, 0], 3) == 0.478


@pytest.mark.parametrize(
    "crack",
    [
        RIG_CRACK.model_copy(update={"angle": 0.9}),
        Crack(
            element=4,
            model="jun",
            angle=0.3,
            jun_b_xi=[0.75, 0.2, 0.04, 0.01],
            jun_b_eta=[0.93, 0.06],
            jun_a=[0.03, 0.01],
        ),
    ],
)
def test_fourier_coefficients_reconstruct_exactly(crack: Crack) -> None:
    sys_ = small_rotor()
    ck = crack_stiffness(sys_, crack)
    orders, kp = ck.harmonics()
    if crack.model == "mayes_davies":
        assert set(orders.tolist()) == {-3, -2, -1, 0, 1, 2, 3}
    for p, k in zip(orders, kp):
        other = kp[np.flatnonzero(orders == -p)[0]]
        assert np.abs(other - np.conj(k)).max() <= 1e-12 * np.abs(kp).max()
    rot = np.random.default_rng(1).uniform(0, 2 * np.pi, 9)
    rec = np.einsum("tp,pij->tij", np.exp(1j * np.outer(rot, orders)), kp)
    ref = ck.at_rotation(rot)
    assert np.abs(rec.imag).max() <= 1e-9 * np.abs(ref).max()
    assert np.abs(rec.real - ref).max() <= 1e-12 * np.abs(ref).max()


def test_jun_series_direct() -> None:
    th = np.array([0.0, 1.0])
    r = jun_reduction(th, [0.8, 0.1], [0.9], [0.05])
    assert r[0, 0, 0] == pytest.approx(1 - 0.9)
    assert r[1, 0, 0] == pytest.approx(1 - 0.8 - 0.1 * np.cos(1.0))
    assert r[1, 0, 1] == pytest.approx(-0.05 * np.sin(1.0))
    assert r[1, 1, 0] == r[1, 0, 1]


def test_gasch_series_converges() -> None:
    sys_ = small_rotor()
    crack = RIG_CRACK.model_copy(update={"model": "gasch"})
    rot = np.linspace(0, 2 * np.pi, 2001)[:-1]
    ref = crack_stiffness(sys_, crack).at_rotation(rot)  # exact square wave
    errs = []
    for n in (5, 21, 81):
        ck = crack_stiffness(sys_, crack, n_terms=n)
        orders, kp = ck.harmonics()
        assert np.abs(orders).max() == n + 2  # odd steering harmonics +- the 2X rotation
        rec = np.einsum("tp,pij->tij", np.exp(1j * np.outer(rot, orders)), kp).real
        errs.append(np.sqrt(np.mean((rec - ref) ** 2)) / np.sqrt(np.mean(ref**2)))
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 0.12  # L2 error of a square-wave partial sum ~ 1/sqrt(n)


def test_isotropic_crack_has_only_steering_harmonics() -> None:
    sys_ = small_rotor()
    crack = RIG_CRACK.model_copy(update={"compliance_eta": 3.0})
    ck = crack_stiffness(sys_, crack)
    orders, _ = ck.harmonics()
    assert set(orders.tolist()) == {-1, 0, 1}
    full = ck.rotating_matrix(np.pi)[0]  # isotropic: rotation invariant
    assert np.abs(ck.mean() - 0.5 * full).max() <= 1e-12 * np.abs(full).max()


@needs_assembly
def test_timoshenko_open_crack_equals_element_with_reduced_i() -> None:
    from rotorcheck.fe.assembly import build_system

    cfg = load_config(CONFIGS / "crack_rig.yaml")
    sys0 = build_system(cfg)
    ck = crack_stiffness(sys0, RIG_CRACK, form="timoshenko")
    k0 = sys0.matrices(0)[3]
    # crack facing down (theta = pi): xi along -y, so y plane loses dI_xi, x plane dI_eta
    kx = build_system(cfg, modulus_factors={4: 1 - ck.delta_eta}).matrices(0)[3]
    ky = build_system(cfg, modulus_factors={4: 1 - ck.delta_xi}).matrices(0)[3]
    xp, yp = sys0.plane_dofs()
    ref = np.zeros_like(k0)
    ref[np.ix_(xp, xp)] = kx[np.ix_(xp, xp)]
    ref[np.ix_(yp, yp)] = ky[np.ix_(yp, yp)]
    got = k0 - ck.scatter(ck.at_rotation(np.pi)[0], sys0.n_dof)
    assert np.abs(got - ref).max() <= 1e-10 * np.abs(k0).max()


@needs_assembly
def test_open_crack_system_and_open_model() -> None:
    from rotorcheck.faults.crack import open_crack_system
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.modal import modes

    cfg = load_config(CONFIGS / "crack_rig_truth.yaml")
    crack = cfg.faults["open_crack"]
    sys_open = open_crack_system(cfg)
    ref = build_system(cfg, modulus_factors={4: 0.46})
    assert np.array_equal(sys_open.matrices(0)[3], ref.matrices(0)[3])
    healthy = build_system(cfg)
    ck = crack_stiffness(healthy, crack, form="timoshenko")
    dk = ck.scatter(ck.at_rotation(0.0)[0], healthy.n_dof)
    k_h = healthy.matrices(0)[3]
    assert np.abs(k_h - dk - ref.matrices(0)[3]).max() <= 1e-10 * np.abs(k_h).max()
    f_h = modes(healthy, 0.0, 1).frequency_hz[0]
    f_o = modes(sys_open, 0.0, 1).frequency_hz[0]
    assert f_o < f_h
