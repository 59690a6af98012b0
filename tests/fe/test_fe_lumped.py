"""The three-mass ECP 210a model through build_system against hand-written 3x3 matrices."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from fe_helpers import CONFIGS

from rotorcheck.config import load_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import receptance
from rotorcheck.fe.modal import modes, natural_frequencies_at_rest

M1, M2, M3 = 2.8113, 2.6396, 2.6074
K1, K2, K3, KD = 842.3, 806.5, 386.0, 350.0
C1, C2, C3 = 5.992, 1.9467, 10.7375


def hand_matrices(k3: float = K3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """k1/c1 join m1-m2, k2/c2 join m2-m3, k3/c3 join m3 to ground (rigs.md section 2)."""
    M = np.diag([M1, M2, M3])
    K = np.array([[K1, -K1, 0.0], [-K1, K1 + K2, -K2], [0.0, -K2, K2 + k3]])
    C = np.array([[C1, -C1, 0.0], [-C1, C1 + C2, -C2], [0.0, -C2, C2 + C3]])
    return M, C, K


@pytest.fixture(scope="module")
def truth():
    return load_config(CONFIGS / "three_mass_truth.yaml")


def test_natural_frequencies_equal_hand_model(truth) -> None:
    sys_ = build_system(truth)
    M, C, K = hand_matrices()
    ref = np.sqrt(sla.eigh(K, M, eigvals_only=True)) / (2 * np.pi)
    np.testing.assert_allclose(natural_frequencies_at_rest(sys_), ref, rtol=1e-9)
    # damped modes from the state space against the hand state space
    A = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(lam.imag)]
    md = modes(sys_)
    np.testing.assert_allclose(md.eigenvalues, lam, rtol=1e-9)
    assert md.whirl == ("none",) * 3


def test_frf_equals_hand_dynamic_stiffness_solve(truth) -> None:
    sys_ = build_system(truth)
    M, C, K = hand_matrices()
    f = np.linspace(0.5, 8.0, 151)
    w = 2 * np.pi * f
    H_ref = np.array([np.linalg.inv(K - wi**2 * M + 1j * wi * C) for wi in w])
    i1, i3 = sys_.dof(mass="m1"), sys_.dof(mass="m3")
    assert (i1, i3) == (0, 2)
    for method in ("direct", "modal", "reduced"):
        H = receptance(sys_, f, 0.0, [i1, i3], [i1, i3], method=method)
        np.testing.assert_allclose(
            H, H_ref[:, [0, 2]][:, :, [0, 2]], rtol=1e-9, atol=1e-12 * np.abs(H_ref).max()
        )


def test_stiffness_override_gives_damaged_truth(truth) -> None:
    sys_ = build_system(truth, stiffness_overrides={"k3": KD})
    M, _, K = hand_matrices(KD)
    np.testing.assert_allclose(sys_.matrices()[3], K, rtol=0, atol=0)
    ref = np.sqrt(sla.eigh(K, M, eigvals_only=True)) / (2 * np.pi)
    np.testing.assert_allclose(natural_frequencies_at_rest(sys_), ref, rtol=1e-9)
    with pytest.raises(KeyError):
        build_system(truth, stiffness_overrides={"k9": 1.0})
    with pytest.raises(ValueError):
        build_system(truth, modulus_factors={1: 0.5})
