"""Rigid rotor on springs, Jeffcott rotor and an overhung disc against their closed forms,
including the gyroscopic forward/backward splitting and the whirl-direction convention."""

from __future__ import annotations

import numpy as np
import pytest
from fe_helpers import condensed, rotor_config

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.elements import shear_coefficient
from rotorcheck.fe.modal import RPM_TO_RAD_S, modes

TWO_PI = 2 * np.pi
MASSLESS = 1e-9  # kg/m^3: shaft mass negligible against the disc (relative 1e-12)

# rigid rotor: disc at the centre, bearings at +-a
M_R, IT_R, IP_R, A_R, K_R = 10.0, 0.4, 0.2, 0.1, 1.0e6


def rigid_rotor():
    """Stiff, massless shaft; bearings at stations 1 and 3, disc at 2; condensed to the disc node."""
    cfg = rotor_config(
        [0.0, A_R, 2 * A_R],
        0.05,
        density=MASSLESS,
        youngs_modulus=2e17,
        poisson=0.3,
        discs=[{"station": 2, "mass": M_R, "polar_inertia": IP_R, "transverse_inertia": IT_R}],
        bearings=[{"station": s, "kxx": K_R, "kyy": K_R} for s in (1, 3)],
    )
    return condensed(build_system(cfg), [1])


def rigid_rotor_closed_form(omega: float) -> tuple[float, float, float]:
    """(cylindrical, conical backward, conical forward) in rad/s at spin omega (rad/s).

    Cylindrical: w^2 = 2k/m, no gyroscopic coupling. Conical: It w^2 -+ Ip Omega w - 2 k a^2 = 0.
    """
    kt = 2 * K_R * A_R**2
    root = np.sqrt((IP_R * omega) ** 2 + 4 * IT_R * kt)
    return np.sqrt(2 * K_R / M_R), (-IP_R * omega + root) / (2 * IT_R), (IP_R * omega + root) / (2 * IT_R)


@pytest.mark.parametrize("rpm", [0.0, 3000.0, 9000.0, 20000.0])
def test_rigid_rotor_gyroscopic_splitting(rpm: float) -> None:
    md = modes(rigid_rotor(), rpm)
    cyl, back, fwd = rigid_rotor_closed_form(rpm * RPM_TO_RAD_S)
    w = md.eigenvalues.imag
    whirl = np.array(md.whirl)
    # cylindrical pair: degenerate, one forward and one backward after circularisation
    # the "rigid" shaft is ~1e8 x stiffer than the bearings: flexibility and round-off ~1e-8
    cyl_idx = np.nonzero(np.isclose(w, cyl, rtol=1e-7))[0]
    assert cyl_idx.size == 2 and sorted(whirl[cyl_idx]) == ["backward", "forward"]
    # conical: the forward-labelled one is the higher root, as gyroscopic stiffening requires
    con = np.setdiff1d(np.arange(4), cyl_idx)
    f_con = w[con][whirl[con] == "forward"]
    b_con = w[con][whirl[con] == "backward"]
    assert f_con == pytest.approx(fwd, rel=1e-7)
    assert b_con == pytest.approx(back, rel=1e-7)
    np.testing.assert_allclose(np.abs(md.whirl_ratio), 1.0, atol=1e-9)  # circular orbits


def test_jeffcott_rotor_closed_form() -> None:
    """Disc at mid-span of a massless simply supported Timoshenko shaft.

    Translation: k = 1 / (L^3 / 48 E I + L / 4 kappa G A), speed independent.
    Tilt: k_t = 1 / (L / 12 E I + 1 / (kappa G A L)); It w^2 -+ Ip Omega w - k_t = 0.
    """
    L, d, E, nu = 0.6, 0.02, 2.0e11, 0.3
    G = E / (2 * (1 + nu))
    m, It, Ip = 5.0, 0.02, 0.035
    cfg = rotor_config(
        [0.0, L / 2, L],
        d,
        density=MASSLESS,
        youngs_modulus=E,
        shear_modulus=G,
        poisson=nu,
        discs=[{"station": 2, "mass": m, "polar_inertia": Ip, "transverse_inertia": It}],
    )
    sys_ = condensed(build_system(cfg), [1], clamp=[0, 1, 8, 9])  # pinned ends: u = v = 0
    A, I = np.pi * d**2 / 4, np.pi * d**4 / 64
    kga = shear_coefficient(nu, d) * G * A
    k = 1 / (L**3 / (48 * E * I) + L / (4 * kga))
    kt = 1 / (L / (12 * E * I) + 1 / (kga * L))
    for rpm in (0.0, 5000.0, 30000.0):
        om = rpm * RPM_TO_RAD_S
        md = modes(sys_, rpm)
        w = np.sort(md.eigenvalues.imag)
        root = np.sqrt((Ip * om) ** 2 + 4 * It * kt)
        ref = np.sort([np.sqrt(k / m)] * 2 + [(root - Ip * om) / (2 * It), (root + Ip * om) / (2 * It)])
        np.testing.assert_allclose(w, ref, rtol=1e-9)


def overhung_quartic(k: np.ndarray, m: float, It: float, Ip: float, om: float, sign: int) -> np.ndarray:
    """Positive roots of det([[k11 - m w^2, k12], [k12, k22 - It w^2 + sign Ip Omega w]]) = 0.

    sign = +1: forward whirl (gyroscopic stiffening), -1: backward.
    """
    k11, k12, k22 = k[0, 0], k[0, 1], k[1, 1]
    # (k11 - m w^2)(k22 - It w^2 + s Ip om w) - k12^2
    p1 = np.array([-m, 0.0, k11])
    p2 = np.array([-It, sign * Ip * om, k22])
    poly = np.polysub(np.polymul(p1, p2), [k12**2])
    r = np.roots(poly)
    return np.sort(r[(np.abs(r.imag) < 1e-9 * np.abs(r)) & (r.real > 0)].real)


@pytest.mark.parametrize("rpm", [0.0, 6000.0, 24000.0])
def test_overhung_disc_on_massless_cantilever(rpm: float) -> None:
    """Disc at the tip of a clamped massless Timoshenko shaft: 2 forward + 2 backward roots."""
    L, d, E, nu = 0.3, 0.025, 2.1e11, 0.3
    G = E / (2 * (1 + nu))
    m, It, Ip = 2.0, 0.004, 0.008  # a thin disc, Ip = 2 It: strong gyroscopic effect
    cfg = rotor_config(
        [0.0, L],
        d,
        density=MASSLESS,
        youngs_modulus=E,
        shear_modulus=G,
        poisson=nu,
        discs=[{"station": 2, "mass": m, "polar_inertia": Ip, "transverse_inertia": It}],
    )
    sys_ = condensed(build_system(cfg), [1], clamp=[0, 1, 2, 3])
    A, I = np.pi * d**2 / 4, np.pi * d**4 / 64
    kga = shear_coefficient(nu, d) * G * A
    # tip flexibility of a Timoshenko cantilever (force P, moment Q) -> (u, psi)
    flex = np.array([[L**3 / (3 * E * I) + L / kga, L**2 / (2 * E * I)], [L**2 / (2 * E * I), L / (E * I)]])
    ktip = np.linalg.inv(flex)
    om = rpm * RPM_TO_RAD_S
    md = modes(sys_, rpm)
    whirl = np.array(md.whirl)
    w = md.eigenvalues.imag
    fwd = np.sort(w[whirl == "forward"])
    bwd = np.sort(w[whirl == "backward"])
    np.testing.assert_allclose(fwd, overhung_quartic(ktip, m, It, Ip, om, +1), rtol=1e-9)
    np.testing.assert_allclose(bwd, overhung_quartic(ktip, m, It, Ip, om, -1), rtol=1e-9)
    if rpm > 0:
        # the gyroscopic effect really splits the pair (the test is not trivially satisfied)
        assert fwd[1] / bwd[1] > 1.05


def test_whirl_label_matches_orbit_direction_in_time() -> None:
    """Independent of the formula: play the mode in time and measure the orbit's turning sense.

    Spin is positive from +x towards +y; a forward mode's orbit must turn the same way.
    """
    sys_ = rigid_rotor()
    md = modes(sys_, 12000.0)
    t = np.linspace(0.0, 1.0, 401)
    for i in range(len(md)):
        shape, lam = md.shapes[:, i], md.eigenvalues[i]
        # a bearing node has no translation here (condensed), so use the tilt (psi, -theta) when the
        # mode has no translation: both are what whirl_ratio looks at
        u, v = shape[0], shape[1]
        if abs(u) + abs(v) < 1e-9:
            u, v = shape[3], -shape[2]
        ph = TWO_PI * t
        x = np.real(u * np.exp(1j * ph))
        y = np.real(v * np.exp(1j * ph))
        turn = np.unwrap(np.arctan2(y, x))
        sense = np.sign(turn[-1] - turn[0])
        assert (sense > 0) == (md.whirl[i] == "forward"), (i, lam, md.whirl[i])
