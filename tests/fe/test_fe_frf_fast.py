"""The fast paths of the receptance engine (issue 13): the half-size complex model of an isotropic
rotor, the closed-form modal pairs of an undamped-mode-diagonal state matrix, the numpy-only pencil
eigensolution, the residue evaluation, and no scipy.linalg / scipy.sparse on the small-model path."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from rotorcheck.fe import frf
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.dense import eigh_pencil
from rotorcheck.fe.frf import Receptance, system_receptance
from rotorcheck.fe.system import RPM_TO_RAD_S
from tests.oracles.frf import dense_receptance

F = np.linspace(30.0, 600.0, 262)
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def rig(crack_rig):
    return build_system(crack_rig)


@pytest.fixture(scope="module")
def truth(crack_rig_truth):
    return build_system(crack_rig_truth)


def _mdk(system, rpm: float):
    M, C, G, K = system.matrices(rpm)
    return M, C + rpm * RPM_TO_RAD_S * G, K


def _rel(got: np.ndarray, ref: np.ndarray) -> float:
    """Largest difference relative to the largest entry at the same frequency."""
    return float(np.max(np.abs(got - ref).max(axis=(-2, -1)) / np.abs(ref).max(axis=(-2, -1))))


def test_the_rig_is_isotropic_and_the_truth_rig_is_not(rig, truth) -> None:
    for rpm in (0.0, 1000.0):
        half = frf._isotropic_half(_mdk(rig, rpm), rig.plane_pairs())
        assert half is not None and all(h.shape == (rig.n_dof // 2,) * 2 for h in half)
        assert np.isrealobj(half[0]) and np.isrealobj(half[2])  # M, K: no x-y coupling
        assert np.iscomplexobj(half[1]) == (rpm != 0.0)  # D: the gyroscopic coupling at speed
        assert frf._isotropic_half(_mdk(truth, rpm), truth.plane_pairs()) is None  # kxx != kyy
    ix, iy, sign = rig.plane_pairs()
    assert frf._isotropic_half(_mdk(rig, 1000.0), (ix, iy, np.ones_like(sign))) is None  # wrong turn


@pytest.mark.parametrize("rpm", [0.0, 1000.0, -3000.0, 10000.0])
def test_isotropic_path_equals_the_full_path_and_dense_solves(rig, rpm: float) -> None:
    """DOF outputs/inputs in both planes and rotations, output rows and complex force vectors."""
    M, D, K = _mdk(rig, rpm)
    planes = rig.plane_pairs()
    out = [rig.dof(6, "x"), rig.dof(6, "y"), rig.dof(4, "theta"), rig.dof(3, "psi")]
    inp = [rig.dof(8, "x"), rig.dof(4, "y"), rig.dof(3, "psi")]
    half = Receptance(M, D, K, out, inp, planes=planes)
    full = Receptance(M, D, K, out, inp)
    assert half.method == full.method == "modal"
    assert half._lam.size == full._lam.size == 2 * rig.n_dof
    Hd = dense_receptance(rig, F, rpm, out, inp)
    assert _rel(half.at_hz(F), Hd) < 1e-9
    assert _rel(full.at_hz(F), Hd) < 1e-9
    # negative frequencies (the harmonic balance asks for them) and output rows / complex forces
    np.testing.assert_allclose(half.at_hz(-F[::17]), full.at_hz(-F[::17]), rtol=1e-7,
                               atol=1e-9 * np.abs(Hd).max())
    rng = np.random.default_rng(7)
    C = rng.standard_normal((2, rig.n_dof))
    B = rng.standard_normal((rig.n_dof, 2)) + 1j * rng.standard_normal((rig.n_dof, 2))
    ref = np.einsum("on,fnm,mi->foi", C, dense_receptance(rig, F[::13], rpm), B)
    got = Receptance(M, D, K, C, B, method="modal", planes=planes).at_hz(F[::13])
    assert _rel(got, ref) < 1e-9


def test_system_receptance_uses_the_half_model_of_an_isotropic_rotor(rig, truth) -> None:
    rec = system_receptance(rig, 1000.0, [rig.dof(6, "x")], [rig.dof(8, "x")])
    assert rec.method == "modal" and rec.planes is not None
    assert frf._isotropic_half((rec.M, rec.D, rec.K), rec.planes) is not None
    rec = system_receptance(truth, 1000.0, [truth.dof(6, "x")], [truth.dof(8, "x")])
    assert rec.method == "modal"
    np.testing.assert_allclose(rec.at_hz(F)[:, 0, 0], dense_receptance(truth, F, 1000.0, [truth.dof(6, "x")],
                                                                       [truth.dof(8, "x")])[:, 0, 0], rtol=1e-7)


def test_closed_form_modal_pairs_at_rest(rig) -> None:
    """At rest with modal damping the state matrix is 2x2 block diagonal in the undamped modes:
    its eigenpairs in closed form equal those of a general eigensolution."""
    Mh, Dh, Kh = frf._isotropic_half(_mdk(rig, 0.0), rig.plane_pairs())
    lam, V, phi, wn = frf._modal_state(Mh, Dh, Kh)
    m = wn.size
    assert np.count_nonzero(V) == 4 * m  # the closed form: two entries per vector
    A = np.zeros((2 * m, 2 * m))
    A[:m, m:] = np.diag(wn)
    A[m:, :m] = -(phi.T @ Kh @ phi) / wn[None, :]
    A[m:, m:] = -(phi.T @ Dh @ phi)
    ref = np.linalg.eigvals(A)
    np.testing.assert_allclose(np.sort_complex(lam), np.sort_complex(ref), rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_allclose(A @ V, V * lam[None, :], atol=1e-10 * np.abs(A).max() * np.abs(V).max())
    # at speed the gyroscopic coupling needs the general eigensolution
    lam, V, _, _ = frf._modal_state(*frf._isotropic_half(_mdk(rig, 1000.0), rig.plane_pairs()))
    assert np.count_nonzero(V) > 4 * m


def test_critically_damped_pair_falls_back_to_the_general_eigensolution() -> None:
    wn = np.array([10.0, 20.0])
    assert frf._decoupled_pairs(wn.copy(), np.array([20.0, 1.0]), wn) is None  # c^2 = 4 k wn
    lam, _ = frf._decoupled_pairs(wn.copy(), np.array([1.0, 1.0]), wn)
    assert lam.size == 4 and np.all(lam.real < 0)


@pytest.mark.parametrize("refine", [1, 4])
def test_eigh_pencil_equals_scipy(crack_rig, refine: int) -> None:
    shaft = [e.model_copy(update={"refine": refine}) for e in crack_rig.shaft]
    M, _, _, K = build_system(crack_rig.model_copy(update={"shaft": shaft})).matrices(0.0)
    Ks = 0.5 * (K + K.T)
    lam, X = eigh_pencil(Ks, M)
    ref, _ = sla.eigh(Ks, M)
    np.testing.assert_allclose(lam, ref, rtol=1e-8)
    np.testing.assert_allclose(X.T @ M @ X, np.eye(lam.size), atol=1e-12)
    # per-mode residuals at the level of scipy's own
    r = np.linalg.norm(Ks @ X - M @ X * lam, axis=0) / (np.abs(lam) * np.linalg.norm(M @ X, axis=0))
    assert r.max() < 1e-6


def test_eigh_pencil_complex_hermitian() -> None:
    rng = np.random.default_rng(3)
    n = 12
    a = rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n))
    b = rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n))
    A = a + a.conj().T
    B = b @ b.conj().T + n * np.eye(n)
    lam, X = eigh_pencil(A, B)
    np.testing.assert_allclose(lam, sla.eigh(A, B, eigvals_only=True), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(X.conj().T @ B @ X, np.eye(n), atol=1e-12)
    np.testing.assert_allclose(A @ X, B @ X * lam, atol=1e-10)
    with pytest.raises(np.linalg.LinAlgError):
        eigh_pencil(A, -B)


def test_residue_and_stacked_evaluations_agree(rig, monkeypatch) -> None:
    rec = system_receptance(rig, 1000.0, np.arange(rig.n_dof), np.arange(rig.n_dof))
    nu = 2 * np.pi * F[::7]
    a = rec(nu)  # few outputs x inputs: the residues
    monkeypatch.setattr(frf, "CHUNK_ELEMENTS", 64)  # forces the stacked products, one point per chunk
    b = rec(nu)
    np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-14 * np.abs(a).max())


def _python(code: str) -> str:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True, env=env,
                          cwd=ROOT).stdout


def test_scipy_linalg_and_sparse_load_only_when_used() -> None:
    """Importing the FE package loads neither (``import scipy.linalg`` costs 0.1-0.2 s); a 9-element
    rig's receptance loads scipy.linalg (its modal damping) but not scipy.sparse (large meshes)."""
    out = _python(
        "import sys, numpy as np\n"
        "from rotorcheck.config import load_config\n"
        "from rotorcheck.fe.assembly import build_system\n"
        "from rotorcheck.fe.frf import receptance\n"
        "import rotorcheck.fe.modal\n"
        "def loaded():\n"
        "    return sorted({m.split('.')[1] for m in sys.modules if m.startswith(('scipy.linalg', 'scipy.sparse'))})\n"
        "print(loaded())\n"
        "s = build_system(load_config('configs/crack_rig.yaml'))\n"
        "h = receptance(s, np.linspace(30, 600, 262), 1000.0, [s.dof(6, 'x')], [s.dof(8, 'x')])\n"
        "print(loaded())\n"
    )
    assert out.split("\n")[:2] == ["[]", "['linalg']"]


def test_lazy_module_imports_at_first_use_and_blas_limit_covers_it() -> None:
    out = _python(
        "import sys\n"
        "from rotorcheck.lazy import lazy_module\n"
        "from rotorcheck.fe.blas import one_blas_thread\n"
        "from threadpoolctl import threadpool_info\n"
        "with one_blas_thread():\n"
        "    pass\n"
        "sla = lazy_module('scipy.linalg')\n"
        "print('scipy.linalg' in sys.modules)\n"
        "print(callable(sla.eigh), 'scipy.linalg' in sys.modules)\n"
        "with one_blas_thread():\n"
        "    print(sorted({i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'}))\n"
    )
    assert out.split("\n")[:3] == ["False", "True True", "[1]"]
