"""Time integration of the cracked rotor: the Magnus integrator against scipy's DOP853, and harmonic
balance against time integration (steady state, the simulator's lock-in) and for unbalance orbits."""

from __future__ import annotations

import numpy as np
import pytest
from faults_helpers import RIG_CRACK, small_rotor

from rotorcheck.config import UnbalanceMass
from rotorcheck.faults.analysis import unbalance_orbit
from rotorcheck.faults.crack import crack_stiffness
from rotorcheck.faults.harmonic_balance import solve_hb, unbalance_force
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.signal.lockin import tone_lockin
from rotorcheck.sim.time_sim import LTPIntegrator, steady_revolution, steady_state_lockin
from tests.oracles.time_domain import simulate_ivp

U = 0.8 - 0.5j  # a complex input phasor: checks the conj(U) half of the real force


def test_magnus_matches_dop853_from_rest() -> None:
    # coarse mesh without the short overhangs, so that the explicit reference stays affordable
    sys_ = small_rotor(
        stations=(0.015, 0.175, 0.295, 0.335, 0.450, 0.615),
        discs={2: (0.9299, 0.0025, 0.0011), 5: (0.7521, 2.39e-4, 3.53e-4)},
        bearings={1: 1.65e7, 6: 1.65e7},
    )
    ck = crack_stiffness(sys_, RIG_CRACK.model_copy(update={"angle": 0.5, "element": 3}))
    b = np.zeros(sys_.n_dof, complex)
    b[sys_.dof(5, "x")] = U
    f, rpm = 47.0, 1000.0
    integ = LTPIntegrator(sys_, ck, rpm, b, f, steps_per_rev=1024)
    n_steps = 2 * integ.steps_per_rev  # two revolutions: 0.12 s
    states = integ.march(integ.initial_state(), n_steps)
    t = np.arange(n_steps + 1) * integ.h
    outs = [sys_.dof(5, "x"), sys_.dof(5, "y"), sys_.dof(2, "y")]
    y_m = integ.displacements(states, outs)
    ref = simulate_ivp(sys_, ck, rpm, b, f, t[1::8], rtol=1e-10, atol=1e-20)
    y_r = ref[:, outs]
    assert np.abs(y_m[1::8] - y_r).max() <= 1e-6 * np.abs(y_r).max()


@pytest.mark.slow
def test_harmonic_balance_agrees_with_time_integration(rig_system: MechanicalSystem) -> None:
    sys_ = rig_system
    ck = crack_stiffness(sys_, RIG_CRACK)
    ind = sys_.dof(8, "x")
    outs = [sys_.dof(6, "x"), sys_.dof(6, "y")]
    # 54.5 Hz: first resonance; 171 Hz: second; 30 Hz: 2X crack sideband region.
    # 64 periods (the window that sets the sidebands' leakage), 16 samples per period: every tone
    # f + k Omega of the 10-harmonic balance (at most 6.6 f, at 30 Hz) stays below the 8 f Nyquist
    # limit, and the errors below match 64 samples per period to within 20 % (a sample costs one
    # matrix exponential: 64 samples took 4x the time for the same figures)
    for f in (30.0, 54.5, 100.0, 171.0, 300.0, 600.0):
        hb = solve_hb(sys_, ck, 1000.0, f, ind, outs, 10)
        ti = steady_state_lockin(sys_, ck, 1000.0, f, ind, outs, phasor=U, steps_per_rev=512, samples_per_period=16)
        same = tone_lockin(hb.tones_hz[0], U * hb.out[0, :, :, 0], f, ti.t_start, 64, 16).mean(0)
        assert abs(ti.phasor[0] - same[0]) <= 1e-3 * abs(same[0])  # identical lock-in
        tone = U * hb.fundamental[0, 0, 0]
        assert abs(ti.phasor[0] - tone) <= 1e-2 * abs(tone)  # HB k = 0 tone vs lock-in: 1 %
        if f == 54.5:  # the time series itself: Re{U sum_k Q_k e^{j (w + k Omega) t}}
            syn = np.real(np.exp(2j * np.pi * np.outer(ti.t, hb.tones_hz[0])) @ (U * hb.out[0, :, :, 0]))
            assert np.abs(ti.y - syn).max() <= 1e-2 * np.abs(syn).max()


def test_unbalance_orbit_time_integration_vs_harmonic_balance(rig_system: MechanicalSystem) -> None:
    sys_ = rig_system
    ub = [UnbalanceMass(station=3, amount=0.2e-3, phase=-np.pi / 2)]
    rpm = 1000.0
    force = unbalance_force(sys_, 3, 0.2e-3, -np.pi / 2, rpm)
    outs = [sys_.dof(6, "x"), sys_.dof(6, "y")]
    t, y = steady_revolution(sys_, RIG_CRACK, rpm, force, rpm / 60.0, outs, steps_per_rev=512)
    period = 60.0 / rpm
    _, xy = unbalance_orbit(sys_, RIG_CRACK, rpm, ub, 6, n_points=t.size)
    # HB orbit is sampled on [0, T]; the TI revolution starts at a whole number of periods
    assert abs(t[0] / period - round(t[0] / period)) < 1e-9
    assert np.abs(y - xy).max() <= 1e-3 * np.abs(xy).max()
    spec = np.fft.rfft(y[:-1], axis=0) * 2 / (t.size - 1)
    one, two, three = (np.abs(spec[k]) for k in (1, 2, 3))
    assert np.all(one > 10 * two) and np.all(two > 0.01 * one) and np.all(three > 0.01 * one)
    # healthy: a circle-like orbit with only 1X
    _, y_h = steady_revolution(sys_, None, rpm, force, rpm / 60.0, outs, steps_per_rev=256)
    spec_h = np.abs(np.fft.rfft(y_h[:-1], axis=0))
    assert np.all(spec_h[2:6] <= 1e-6 * spec_h[1])


def test_integrator_is_stable_and_converges(rotor: MechanicalSystem) -> None:
    ck = crack_stiffness(rotor, RIG_CRACK)
    b = np.zeros(rotor.n_dof, complex)
    b[rotor.dof(8, "x")] = 1.0
    vals = []
    for n in (128, 256, 512, 1024):
        integ = LTPIntegrator(rotor, ck, 1000.0, b, 40.0, steps_per_rev=n)
        assert integ.floquet_radius() < 1.0
        x = integ.march(integ.initial_state(), n // 2)  # to t = 0.03 s
        vals.append(integ.displacements(x[-1], [rotor.dof(6, "x")])[0])
    d = np.abs(np.diff(vals))
    assert np.all(d[1:] < d[:-1] / 8)  # fourth order: ~16x per halving of the step
    assert d[-1] < 1e-5 * abs(vals[-1])
