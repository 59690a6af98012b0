"""FRF engine: reciprocity, direct solve vs modal superposition, partitioned system."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import modal_receptance, partitioned_system, receptance

F = np.linspace(30.0, 600.0, 262)


@pytest.fixture(scope="module", params=["crack_rig", "crack_rig_truth"])
def system(request):
    return build_system(request.getfixturevalue(request.param))


def test_reciprocity_at_rest(system) -> None:
    """At zero speed M, C, K are symmetric, so H = H^T for every DOF pair."""
    H = receptance(system, F[::20], 0.0, method="solve")
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2), rtol=1e-9, atol=1e-12 * np.abs(H).max())
    i, o = system.dof(8, "x"), system.dof(6, "x")
    h = receptance(system, F, 0.0, [o, i], [o, i])
    np.testing.assert_allclose(h[:, 0, 1], h[:, 1, 0], rtol=1e-8)


def test_gyroscopic_breaks_reciprocity_but_reverses_with_spin(system) -> None:
    """At speed G (skew) makes H non-symmetric; H(Omega)^T = H(-Omega) holds instead."""
    H = receptance(system, F[::20], 1000.0, method="solve")
    asym = np.abs(H - np.swapaxes(H, 1, 2)).max() / np.abs(H).max()
    assert asym > 1e-6
    Hm = receptance(system, F[::20], -1000.0, method="solve")
    np.testing.assert_allclose(np.swapaxes(H, 1, 2), Hm, rtol=1e-8, atol=1e-12 * np.abs(H).max())


@pytest.mark.parametrize("rpm", [0.0, 1000.0, 8000.0])
def test_direct_solve_equals_modal_superposition(system, rpm: float) -> None:
    out = [system.dof(6, "x"), system.dof(6, "y"), system.dof(4, "x")]
    inp = [system.dof(8, "x"), system.dof(4, "x"), system.dof(3, "psi")]
    Hs = receptance(system, F, rpm, out, inp, method="solve")
    Hm = receptance(system, F, rpm, out, inp, method="modal")
    Hsup = modal_receptance(system, F, rpm, out, inp)
    scale = np.abs(Hs).max()
    np.testing.assert_allclose(Hm, Hs, rtol=1e-7, atol=1e-9 * scale)
    np.testing.assert_allclose(Hsup, Hs, rtol=1e-7, atol=1e-9 * scale)
    # and the naive per-frequency inverse of Z
    Z = system.dynamic_stiffness(F[::37], rpm)
    Hn = np.array([np.linalg.inv(z)[np.ix_(out, inp)] for z in Z])
    np.testing.assert_allclose(Hs[::37], Hn, rtol=1e-8, atol=1e-12 * scale)


def test_truncated_modal_superposition_converges(system) -> None:
    o, i = system.dof(6, "x"), system.dof(8, "x")
    Hs = receptance(system, F, 0.0, o, i, method="solve")[:, 0, 0]
    errs = [
        np.abs(modal_receptance(system, F, 0.0, o, i, n_modes=n)[:, 0, 0] - Hs).max() / np.abs(Hs).max()
        for n in (6, 10, 20, system.n_dof)
    ]
    assert errs[0] > errs[1] > errs[2] > errs[3] and errs[3] < 1e-9 and errs[0] > 1e-4


def test_partitioned_system_blocks(system, crack_rig) -> None:
    d, i, o = system.dof(4, "x"), system.dof(8, "x"), system.dof(6, "x")
    E = partitioned_system(system, F, 1000.0, d, i, o)
    H = receptance(system, F, 1000.0, [d, o], [d, i], method="solve")
    np.testing.assert_allclose(E.E11[:, 0, 0], H[:, 0, 0], rtol=1e-7)
    np.testing.assert_allclose(E.E12[:, 0, 0], H[:, 0, 1], rtol=1e-7)
    np.testing.assert_allclose(E.E21[:, 0, 0], H[:, 1, 0], rtol=1e-7)
    np.testing.assert_allclose(E.E22[:, 0, 0], H[:, 1, 1], rtol=1e-7)
    assert E.block().shape == (F.size, 2, 2)
    # E22 is the io receptance named by the config ports
    io = receptance(
        system, F, 1000.0, system.port_dof(crack_rig.ports.sensor), system.port_dof(crack_rig.ports.actuator)
    )
    np.testing.assert_allclose(E.E22, io, rtol=1e-7)


def test_receptance_is_inverse_of_dynamic_stiffness(system) -> None:
    f = np.array([55.0, 250.0])
    H = receptance(system, f, 1000.0)
    Z = system.dynamic_stiffness(f, 1000.0)
    np.testing.assert_allclose(Z @ H, np.broadcast_to(np.eye(system.n_dof), Z.shape), atol=1e-7)
