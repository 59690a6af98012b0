"""The receptance engine: reciprocity, its methods against each other and against the oracles (dense
per-frequency solves, state-space modal superposition, tests/oracles/frf.py), the partitioned system,
the reduced (Ritz) path on refined meshes, and memory that does not grow with points x n^2."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import N_FULL, Receptance, partitioned_system, receptance, state_matrix, system_receptance
from rotorcheck.fe.modal import modes
from rotorcheck.fe.system import RPM_TO_RAD_S
from tests.oracles.frf import dense_receptance, modal_receptance

F = np.linspace(30.0, 600.0, 262)


@pytest.fixture(scope="module", params=["crack_rig", "crack_rig_truth"])
def system(request):
    return build_system(request.getfixturevalue(request.param))


def _refined(config, refine: int):
    shaft = [e.model_copy(update={"refine": refine}) for e in config.shaft]
    return build_system(config.model_copy(update={"shaft": shaft}))


@pytest.fixture(scope="module")
def fine(crack_rig):
    """The crack rig with every element split in 8: 72 elements, 292 DOF (the reduced path)."""
    sys_ = _refined(crack_rig, 8)
    assert sys_.n_dof > N_FULL
    return sys_


def test_reciprocity_at_rest(system) -> None:
    """At zero speed M, C, K are symmetric, so H = H^T for every DOF pair."""
    H = receptance(system, F[::20], 0.0, method="direct")
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2), rtol=1e-9, atol=1e-12 * np.abs(H).max())
    i, o = system.dof(8, "x"), system.dof(6, "x")
    h = receptance(system, F, 0.0, [o, i], [o, i])
    np.testing.assert_allclose(h[:, 0, 1], h[:, 1, 0], rtol=1e-8)


def test_gyroscopic_breaks_reciprocity_but_reverses_with_spin(system) -> None:
    """At speed G (skew) makes H non-symmetric; H(Omega)^T = H(-Omega) holds instead."""
    H = receptance(system, F[::20], 1000.0, method="direct")
    asym = np.abs(H - np.swapaxes(H, 1, 2)).max() / np.abs(H).max()
    assert asym > 1e-6
    Hm = receptance(system, F[::20], -1000.0, method="direct")
    np.testing.assert_allclose(np.swapaxes(H, 1, 2), Hm, rtol=1e-8, atol=1e-12 * np.abs(H).max())


@pytest.mark.parametrize("rpm", [0.0, 1000.0, 8000.0])
def test_engine_methods_equal_the_oracles(system, rpm: float) -> None:
    out = [system.dof(6, "x"), system.dof(6, "y"), system.dof(4, "x")]
    inp = [system.dof(8, "x"), system.dof(4, "x"), system.dof(3, "psi")]
    Hd = dense_receptance(system, F, rpm, out, inp)  # oracle: per-frequency dense solves
    scale = np.abs(Hd).max()
    for method in ("auto", "modal", "direct", "reduced"):
        H = receptance(system, F, rpm, out, inp, method=method)
        np.testing.assert_allclose(H, Hd, rtol=1e-7, atol=1e-9 * scale, err_msg=method)
    np.testing.assert_allclose(modal_receptance(system, F, rpm, out, inp), Hd, rtol=1e-7, atol=1e-9 * scale)
    # and the naive per-frequency inverse of Z
    Z = system.dynamic_stiffness(F[::37], rpm)
    Hn = np.array([np.linalg.inv(z)[np.ix_(out, inp)] for z in Z])
    np.testing.assert_allclose(Hd[::37], Hn, rtol=1e-8, atol=1e-12 * scale)


def test_auto_is_modal_on_the_nine_element_rig(system) -> None:
    rec = system_receptance(system, 1000.0, [system.dof(6, "x")], [system.dof(8, "x")])
    assert rec.method == "modal"


def test_truncated_modal_superposition_converges(system) -> None:
    o, i = system.dof(6, "x"), system.dof(8, "x")
    Hs = receptance(system, F, 0.0, o, i, method="direct")[:, 0, 0]
    errs = [
        np.abs(modal_receptance(system, F, 0.0, o, i, n_modes=n)[:, 0, 0] - Hs).max() / np.abs(Hs).max()
        for n in (6, 10, 20, system.n_dof)
    ]
    assert errs[0] > errs[1] > errs[2] > errs[3] and errs[3] < 1e-9 and errs[0] > 1e-4


def test_partitioned_system_blocks(system, crack_rig) -> None:
    d, i, o = system.dof(4, "x"), system.dof(8, "x"), system.dof(6, "x")
    E = partitioned_system(system, F, 1000.0, d, i, o)
    H = dense_receptance(system, F, 1000.0, [d, o], [d, i])
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


def test_output_rows_and_force_vectors(system) -> None:
    """Outputs as rows C (n_out, n) and complex force vectors B: C H B by superposition."""
    n = system.n_dof
    rng = np.random.default_rng(4)
    C = rng.standard_normal((2, n))
    B = rng.standard_normal((n, 2)) + 1j * rng.standard_normal((n, 2))
    M, Cd, G, K = system.matrices(1000.0)
    D = Cd + 1000.0 * RPM_TO_RAD_S * G
    full = dense_receptance(system, F[::13], 1000.0)
    ref = np.einsum("on,fnm,mi->foi", C, full, B)
    for method in ("modal", "direct", "reduced"):
        got = Receptance(M, D, K, C, B, method=method, band_hz=600.0).at_hz(F[::13])
        np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9 * np.abs(ref).max(), err_msg=method)


# --------------------------------------------------------------------------------------------
# refined meshes: the reduced (Ritz) path


@pytest.mark.parametrize("rpm", [0.0, 1000.0, 10000.0])
def test_reduced_path_equals_dense_solves_on_72_elements(fine, rpm: float) -> None:
    """72 elements: merely rescaling Z moves a dense solve by ~3e-9 here (cond(Z) ~ 1e8), and the
    engine agrees with dense solves to that level at every point and at the HB's signed tones."""
    out = [fine.dof(4, "x"), fine.dof(6, "x"), fine.dof(6, "y")]
    inp = [fine.dof(4, "x"), fine.dof(8, "x")]
    rec = system_receptance(fine, rpm, out, inp, band_hz=600.0)
    assert rec.method == "reduced"
    H = rec.at_hz(F)
    Hd = dense_receptance(fine, F, rpm, out, inp)
    err = np.abs(H - Hd).max(axis=(1, 2)) / np.abs(Hd).max(axis=(1, 2))
    assert err.max() < 2e-8, err.max()
    tones = np.linspace(-130.0, 730.0, 23)  # wider than the band: the basis is rebuilt for it
    Ht, Hdt = rec.at_hz(tones), dense_receptance(fine, tones, rpm, out, inp)
    assert rec.band_hz >= 730.0
    err = np.abs(Ht - Hdt).max(axis=(1, 2)) / np.abs(Hdt).max(axis=(1, 2))
    assert err.max() < 2e-8, err.max()


def test_reduced_modes_equal_the_full_eigendecomposition(fine) -> None:
    M, C, G, K = fine.matrices(10000.0)
    lam = np.linalg.eigvals(state_matrix(M, C + 10000.0 * RPM_TO_RAD_S * G, K))
    lam = np.sort(lam[lam.imag > 0].imag) / (2 * np.pi)
    md = modes(fine, 10000.0, n_modes=6)
    assert len(md) == 6
    np.testing.assert_allclose(md.frequency_hz, lam[:6], rtol=1e-8)
    assert list(md.whirl) == ["backward", "forward"] * 3


def test_engine_memory_does_not_grow_with_points_times_n_squared(fine) -> None:
    """262 points x 292^2 complex would be 357 MB as one dynamic-stiffness stack; the engine needs a
    few n x n matrices and the Ritz basis."""
    d, i, o = fine.dof(4, "x"), fine.dof(8, "x"), fine.dof(6, "x")
    fine.matrices(1000.0)
    tracemalloc.start()
    try:
        receptance(fine, F, 1000.0, [d, o], [d, i])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    stack = F.size * fine.n_dof**2 * 16
    assert peak < 0.05 * stack, (peak, stack)
