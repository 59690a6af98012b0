"""Element matrices against independent references: shape-function quadrature, eq. 5.22, physics."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.fe.elements import (
    X_PLANE,
    Y_PLANE,
    RigidDisc,
    TimoshenkoBeam,
    beam_matrices,
    beam_shape_functions,
    shear_coefficient,
)

BEAM = TimoshenkoBeam(0.05, 2.1e11, 8.1e10, 7850.0, 0.03, 0.01, 0.29)


def _quadrature(beam: TimoshenkoBeam) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plane (Mt, Mr, K) by 8-point Gauss quadrature of the shape functions (exact for polynomials)."""
    L, phi = beam.length, beam.phi
    xg, wg = np.polynomial.legendre.leggauss(8)
    xi, w = (xg + 1) / 2, wg / 2 * L
    nw, nb = beam_shape_functions(xi, L, phi)
    # derivatives by complex-step-free exact polynomial differentiation: fit per column
    h = 1e-5
    nwp = (beam_shape_functions(xi + h, L, phi)[0] - beam_shape_functions(xi - h, L, phi)[0]) / (2 * h * L)
    nbp = (beam_shape_functions(xi + h, L, phi)[1] - beam_shape_functions(xi - h, L, phi)[1]) / (2 * h * L)
    A, I = beam.area, beam.second_moment
    kGA = beam.shear_coefficient * beam.shear_modulus * A
    Mt = np.einsum("q,qi,qj->ij", w * beam.density * A, nw, nw)
    Mr = np.einsum("q,qi,qj->ij", w * beam.density * I, nb, nb)
    gam = nwp - nb
    K = np.einsum("q,qi,qj->ij", w * beam.youngs_modulus * I, nbp, nbp) + np.einsum(
        "q,qi,qj->ij", w * kGA, gam, gam
    )
    return Mt, Mr, K


def test_hutchinson_shear_coefficient() -> None:
    nu = 0.3
    assert shear_coefficient(nu, 0.016) == pytest.approx(6 * 1.3**2 / (7 + 3.6 + 0.36), rel=1e-15)
    assert shear_coefficient(nu, 0.016) == pytest.approx(0.925182, abs=1e-6)
    # hollow: continuous to solid, and within 7 % of Cowper's (1966) hollow-circle formula over the
    # whole range of wall thickness (the two approximations differ by 4.4 % solid, 6.5 % thin)
    assert shear_coefficient(nu, 0.016, 1e-9) == pytest.approx(shear_coefficient(nu, 0.016), rel=1e-12)
    for m in np.linspace(0.0, 0.999, 12):
        cowper = 6 * (1 + nu) * (1 + m**2) ** 2 / ((7 + 6 * nu) * (1 + m**2) ** 2 + (20 + 12 * nu) * m**2)
        k = shear_coefficient(nu, 0.1, 0.1 * m)
        assert 1.0 < k / cowper < 1.07


def test_shear_parameter_definition() -> None:
    b = BEAM
    expect = (
        12
        * b.youngs_modulus
        * b.second_moment
        / (b.shear_coefficient * b.shear_modulus * b.area * b.length**2)
    )
    assert b.phi == pytest.approx(expect, rel=1e-15)
    assert b.phi > 0.1  # a stocky element, so the Phi terms matter in the checks below


def test_matrices_equal_shape_function_integrals() -> None:
    Mt, Mr, K = _quadrature(BEAM)
    M8, K8 = BEAM.mass(), BEAM.stiffness()
    # x plane [u1 psi1 u2 psi2] is the standard plane
    np.testing.assert_allclose(
        M8[np.ix_(X_PLANE, X_PLANE)], Mt + Mr, rtol=1e-12, atol=1e-14 * np.abs(Mt).max()
    )
    np.testing.assert_allclose(K8[np.ix_(X_PLANE, X_PLANE)], K, rtol=1e-7, atol=1e-7 * np.abs(K).max())
    # y plane [v1 theta1 v2 theta2] with theta = -dv/dz
    S = np.diag([1.0, -1.0, 1.0, -1.0])
    np.testing.assert_allclose(M8[np.ix_(Y_PLANE, Y_PLANE)], S @ (Mt + Mr) @ S, rtol=1e-12, atol=1e-20)
    # no coupling between planes in M and K
    assert np.abs(M8[np.ix_(X_PLANE, Y_PLANE)]).max() == 0.0
    assert np.abs(K8[np.ix_(X_PLANE, Y_PLANE)]).max() == 0.0


def test_euler_bernoulli_limit_is_eq_5_22() -> None:
    """Phi = 0 gives the stiffness matrix printed in the dissertation (eq. 5.22), signs included."""
    b = TimoshenkoBeam(0.1, 2e11, 8e10, 7800.0, 0.02, shear=False)
    l = b.length
    ref = np.array(
        [
            [12, 0, 0, 6 * l, -12, 0, 0, 6 * l],
            [0, 12, -6 * l, 0, 0, -12, -6 * l, 0],
            [0, -6 * l, 4 * l**2, 0, 0, 6 * l, 2 * l**2, 0],
            [6 * l, 0, 0, 4 * l**2, -6 * l, 0, 0, 2 * l**2],
            [-12, 0, 0, -6 * l, 12, 0, 0, -6 * l],
            [0, -12, 6 * l, 0, 0, 12, 6 * l, 0],
            [0, -6 * l, 2 * l**2, 0, 0, 6 * l, 4 * l**2, 0],
            [6 * l, 0, 0, 2 * l**2, -6 * l, 0, 0, 4 * l**2],
        ]
    ) * (b.youngs_modulus * b.second_moment / l**3)
    np.testing.assert_allclose(b.stiffness(), ref, rtol=1e-13, atol=1e-9)


def test_rigid_body_modes_carry_no_strain_energy() -> None:
    K = BEAM.stiffness()
    z = 0.5 * BEAM.length
    translate_x = np.array([1, 0, 0, 0, 1, 0, 0, 0], float)
    rotate_y = np.array([-z, 0, 0, 1, z, 0, 0, 1], float)  # u = (z_i - zc) psi, psi = 1
    rotate_x = np.array([0, z, 1, 0, 0, -z, 1, 0], float)  # v = -(z_i - zc) theta, theta = 1
    for q in (translate_x, rotate_y, rotate_x):
        assert np.abs(K @ q).max() < 1e-6 * np.abs(K).max()
    # kinetic energy of a rigid translation is the element mass
    M = BEAM.mass()
    mass = BEAM.density * BEAM.area * BEAM.length
    assert translate_x @ M @ translate_x == pytest.approx(mass, rel=1e-12)


def test_gyroscopic_is_skew_and_twice_the_cross_plane_rotary_inertia() -> None:
    G = BEAM.gyroscopic()
    np.testing.assert_allclose(G, -G.T, atol=1e-20)
    rot = (
        TimoshenkoBeam(**{**BEAM.__dict__}).mass()
        - TimoshenkoBeam(**{**BEAM.__dict__, "rotary": False}).mass()
    )
    # polar moment = 2 I: |G| entries on the (y, x) block equal 2 x rotary inertia entries (x, x)
    np.testing.assert_allclose(
        np.abs(G[np.ix_(Y_PLANE, X_PLANE)]), 2 * np.abs(rot[np.ix_(X_PLANE, X_PLANE)]), rtol=1e-12
    )


def test_gyroscopic_limit_of_short_element_is_a_disc() -> None:
    """The shaft gyroscopic matrix integrated over a rigid tilt equals a disc of polar inertia rho*Ip*L."""
    b = TimoshenkoBeam(0.01, 2e11, 8e10, 7800.0, 0.05)
    G = b.gyroscopic()
    tilt_theta = np.array([0, 0, 1, 0, 0, 0, 1, 0], float)  # rigid theta = 1 (v = 0 at both ends, short)
    tilt_psi = np.array([0, 0, 0, 1, 0, 0, 0, 1], float)
    ip = 2 * b.density * b.second_moment * b.length
    # leading order for a short element (shear-dominated rotations are uniform)
    assert tilt_theta @ G @ tilt_psi == pytest.approx(ip, rel=0.05)
    d = RigidDisc(1.0, 0.1, 0.2).gyroscopic()
    assert d[2, 3] == 0.2 and d[3, 2] == -0.2


def test_vectorised_matrices_equal_single_element() -> None:
    b = BEAM
    M, G, K = beam_matrices(
        np.array([b.length]),
        np.array([b.youngs_modulus]),
        np.array([b.shear_modulus]),
        np.array([b.density]),
        np.array([b.outer_diameter]),
        np.array([b.inner_diameter]),
        np.array([b.shear_coefficient]),
    )
    np.testing.assert_allclose(M[0], b.mass(), rtol=1e-14)
    np.testing.assert_allclose(G[0], b.gyroscopic(), rtol=1e-14)
    np.testing.assert_allclose(K[0], b.stiffness(), rtol=1e-14)
