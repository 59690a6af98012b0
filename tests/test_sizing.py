"""An element's loss from the measured pole shifts (rotorcheck.sizing, rotorcheck.modal_anchor.refit_poles).

References:
- a single mass on a spring and damper: ``|lambda|^2 = k (1 - a) / m`` exactly, so the loss's shift is ``-a`` and a
  stiffness factor's ``+1`` per unit;
- an undamped 4-mass chain: ``|lambda|^2`` are the eigenvalues of ``(K(a), M)`` (scipy.linalg.eigh);
- the profile on shifts made by the chain itself (loss and a benign stiffness factor): the estimate is the truth;
- the standard error of a refitted shift against the scatter of 24 noise draws (Monte Carlo);
- the simulator's truth rig (other supports, a disc hub, a coupling, its own damping: physics the nominal model
  does not share), open crack of element 2 at 10 % loss, sized with the nominal model: the interval holds 10 %
  (the FRF fit's profile read this case as 19 %, interval 14-24 %).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import eigh

from rotorcheck.config import load_config
from rotorcheck.modal_anchor import refit_poles
from rotorcheck.ranking import loss_model
from rotorcheck.resources import configs_dir
from rotorcheck.robust.affine import AffineModel, AffineParameter
from rotorcheck.signatures import benign_box, io_frf, modal_anchor
from rotorcheck.sizing import benign_shifts, profile, shift_curves, size_from_poles
from rotorcheck.variability import benign_at
from tests.robust.test_severity import K, _chain, _spring

F = np.linspace(30.0, 600.0, 400)


def _sdof(m: float = 2.0, c: float = 3.0, k: float = 4.0e5) -> AffineModel:
    one = np.ones((1, 1))
    return AffineModel(m * one, c * one, k * one, one[0], one[0],
                       (AffineParameter("E", (("K", k * one),), -0.02, 0.02),
                        AffineParameter("loss", (("K", -k * one),), 0.0, 0.8)))


def test_single_mass_shift_is_minus_the_loss() -> None:
    model = _sdof()
    ref = np.array([np.sqrt(4.0e5 / 2.0) * 1j])
    losses, curves = shift_curves(model, ref)
    assert curves[:, 0] == pytest.approx(-losses, abs=1e-9)
    assert benign_shifts(model, ref)[0, 0] == pytest.approx(1.0, rel=1e-6)


def test_chain_shifts_match_the_eigenvalues() -> None:
    M, _, K0 = _chain(0.0, {})
    A = K[2] * _spring(2)
    model = AffineModel(M, np.zeros_like(M), K0, np.eye(4)[3], np.eye(4)[1],
                        (AffineParameter("loss", (("K", -A),), 0.0, 0.8),))
    w0 = eigh(K0, M, eigvals_only=True)
    losses, curves = shift_curves(model, 1j * np.sqrt(w0))
    for a, c in zip(losses[::8], curves[::8]):
        w = eigh(K0 - a * A, M, eigvals_only=True)
        assert c == pytest.approx(w / w0 - 1.0, abs=1e-9)


def test_profile_recovers_the_chain_loss_beside_a_benign_change() -> None:
    M, _, K0 = _chain(0.0, {})
    A = K[2] * _spring(2)
    model = AffineModel(M, np.zeros_like(M), K0, np.eye(4)[3], np.eye(4)[1],
                        (AffineParameter("E", (("K", K0),), -0.02, 0.02),
                         AffineParameter("loss", (("K", -A),), 0.0, 0.8)))
    ref = 1j * np.sqrt(eigh(K0, M, eigvals_only=True))
    losses, curves = shift_curves(model, ref)
    S = benign_shifts(model, ref)
    truth = eigh(K0 * 1.013 - 0.27 * A, M, eigvals_only=True) / np.abs(ref) ** 2 - 1.0
    a, chi, _ = profile(truth, np.full(4, 1e-6), losses, curves, S, np.array([-0.02]), np.array([0.02]))
    assert a[int(np.argmin(chi))] == pytest.approx(0.27, abs=0.006)


@pytest.fixture(scope="module")
def nominal_rig():  # type: ignore[no-untyped-def]
    return load_config(configs_dir() / "crack_rig.yaml")


def _with_loss(config, element: int, loss: float):  # type: ignore[no-untyped-def]
    shaft = [e.model_copy(update={"modulus_factor": e.modulus_factor * (1.0 - loss)}) if e.start == element else e
             for e in config.shaft]
    return config.model_copy(update={"shaft": shaft})


def _noisy(t: np.ndarray, sd: float, rng: np.random.Generator) -> np.ndarray:
    return t + sd * (rng.standard_normal(t.size) + 1j * rng.standard_normal(t.size)) / np.sqrt(2.0)


def test_refit_standard_error_against_monte_carlo(nominal_rig) -> None:  # type: ignore[no-untyped-def]
    th0 = io_frf(nominal_rig, F, 0.0)
    td0 = io_frf(_with_loss(nominal_rig, 5, 0.1), F, 0.0)
    sd = 0.01 * float(np.median(np.abs(th0)))
    var = np.full(F.size, sd**2)
    rng = np.random.default_rng(11)
    shifts, ses = [], []
    for _ in range(24):
        th, td = _noisy(th0, sd, rng), _noisy(td0, sd, rng)
        anchor = modal_anchor(nominal_rig, F, 0.0, th, None, var)
        assert anchor is not None
        fit = refit_poles(anchor, td, var, th, var)
        assert fit.ok
        shifts.append(fit.shift)
        ses.append(fit.se_shift)
    scatter, stated = np.std(shifts, axis=0, ddof=1), np.median(ses, axis=0)
    # 24 draws: the sample standard deviation is within 0.7-1.3 of the true one at about 95 %
    assert np.all(scatter / stated > 0.6) and np.all(scatter / stated < 1.6), (scatter, stated)


def test_truth_rig_open_crack_sized_with_the_nominal_model(nominal_rig) -> None:  # type: ignore[no-untyped-def]
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    th0 = io_frf(truth, F, 0.0)
    sd = 1e-3 * float(np.median(np.abs(th0)))
    var = np.full(F.size, sd**2)
    rng = np.random.default_rng(5)
    th, td = _noisy(th0, sd, rng), _noisy(io_frf(_with_loss(truth, 2, 0.10), F, 0.0), sd, rng)
    anchor = modal_anchor(nominal_rig, F, 0.0, th, None, var)
    assert anchor is not None
    box = benign_box(nominal_rig, 0.0, benign_at(nominal_rig, 0.0))
    model = loss_model(nominal_rig, box, 2, 0.0, "open")
    size = size_from_poles(model, anchor, td, var, th, var, start=0.19)
    assert size is not None
    assert size.interval[0] <= 0.10 <= size.interval[1]
    assert size.estimate == pytest.approx(0.10, abs=0.02)
    assert size.interval[1] - size.interval[0] < 0.15
