"""Pinned-pinned uniform beam against closed forms (Euler-Bernoulli and Timoshenko); convergence."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from fe_helpers import reduced, rotor_config

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.elements import TimoshenkoBeam, shear_coefficient
from rotorcheck.fe.modal import modes, natural_frequencies_at_rest

E, RHO, NU = 2.0e11, 7800.0, 0.3
G = E / (2 * (1 + NU))


def euler_bernoulli_ss(L: float, d: float, n: int) -> float:
    """Simply supported Euler-Bernoulli beam: (n pi / L)^2 sqrt(E I / rho A) / 2 pi (Hz)."""
    A, I = np.pi * d**2 / 4, np.pi * d**4 / 64
    return (n * np.pi / L) ** 2 * np.sqrt(E * I / (RHO * A)) / (2 * np.pi)


def timoshenko_ss(L: float, d: float, n: int) -> float:
    """Simply supported Timoshenko beam (shear + rotary inertia), bending branch (Hz).

    With w = W sin(kz), phi = P cos(kz), k = n pi / L:
    (kGA k^2 - rho A w^2)(E I k^2 + kGA - rho I w^2) - (kGA k)^2 = 0, the lower root in w^2.
    """
    A, I = np.pi * d**2 / 4, np.pi * d**4 / 64
    kga = shear_coefficient(NU, d) * G * A
    k = n * np.pi / L
    a = RHO * A * RHO * I
    b = RHO * A * (E * I * k**2 + kga) + RHO * I * kga * k**2
    c = kga * E * I * k**4
    w2 = (b - np.sqrt(b * b - 4 * a * c)) / (2 * a)
    return np.sqrt(w2) / (2 * np.pi)


def pinned_beam_fe(L: float, d: float, n_el: int) -> np.ndarray:
    """Timoshenko FE through build_system (refine = n_el), u and v clamped at both ends (Hz)."""
    sys_ = build_system(rotor_config([0.0, L], d, RHO, E, G, NU, refine=n_el))
    last = 4 * n_el
    free = np.setdiff1d(np.arange(sys_.n_dof), [0, 1, last, last + 1])
    return natural_frequencies_at_rest(reduced(sys_, free))[::2]  # x/y pairs are degenerate


def pinned_beam_euler_bernoulli(L: float, d: float, n_el: int) -> np.ndarray:
    """Euler-Bernoulli elements (Phi = 0, no rotary inertia), x plane only (Hz)."""
    b = TimoshenkoBeam(L / n_el, E, G, RHO, d, poisson=NU, shear=False, rotary=False)
    Me, Ke = b.mass()[np.ix_([0, 3, 4, 7], [0, 3, 4, 7])], b.stiffness()[np.ix_([0, 3, 4, 7], [0, 3, 4, 7])]
    n = 2 * (n_el + 1)
    M, K = np.zeros((n, n)), np.zeros((n, n))
    for e in range(n_el):
        s = slice(2 * e, 2 * e + 4)
        M[s, s] += Me
        K[s, s] += Ke
    free = np.setdiff1d(np.arange(n), [0, n - 2])
    lam = sla.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)
    return np.sqrt(lam) / (2 * np.pi)


def test_slender_beam_euler_bernoulli_closed_form() -> None:
    L, d = 1.0, 0.01  # L/d = 100
    f = pinned_beam_euler_bernoulli(L, d, 20)[:3]
    ref = np.array([euler_bernoulli_ss(L, d, n) for n in (1, 2, 3)])
    assert np.max(np.abs(f / ref - 1)) < 1e-3
    # and the Timoshenko element on the same beam matches the Timoshenko closed form
    ft = pinned_beam_fe(L, d, 20)[:3]
    ref_t = np.array([timoshenko_ss(L, d, n) for n in (1, 2, 3)])
    assert np.max(np.abs(ft / ref_t - 1)) < 1e-3
    # on a slender beam the two theories agree to about (n pi r / L)^2 (1 + E / kappa G) / 2
    assert np.max(np.abs(ref_t / ref - 1)) < 2e-3


@pytest.mark.parametrize("L, d, n_el", [(0.2, 0.04, 48), (0.4, 0.04, 24)])
def test_stocky_beam_timoshenko_closed_form(L: float, d: float, n_el: int) -> None:
    """L/d = 5 (mode 3 25 % below Euler-Bernoulli) and L/d = 10 (9 % below)."""
    ref = np.array([timoshenko_ss(L, d, n) for n in (1, 2, 3)])
    ref_eb = np.array([euler_bernoulli_ss(L, d, n) for n in (1, 2, 3)])
    assert ref[2] / ref_eb[2] < 0.92  # the stocky case really tests the Timoshenko terms
    f = pinned_beam_fe(L, d, n_el)[:3]
    err = np.abs(f / ref - 1)
    assert np.max(err) < 1e-3, err


def _errors(L: float, d: float, counts: list[int]) -> np.ndarray:
    ref = np.array([timoshenko_ss(L, d, n) for n in (1, 2, 3)])
    return np.array([np.abs(pinned_beam_fe(L, d, n)[:3] / ref - 1) for n in counts])  # (c, 3)


def test_refinement_converges_slender_fourth_order() -> None:
    """Bending-dominated elements (Phi << 1): frequency error O(h^4) (cubic Hermite-like)."""
    errs = _errors(1.0, 0.01, [2, 4, 8, 16])
    assert np.all(np.diff(errs, axis=0) < 0), errs  # monotone decrease, every mode
    order = np.log2(errs[:-1] / errs[1:])
    assert np.all(order[-1] > 3.6) and np.all(order[-1] < 4.3), order


def test_refinement_converges_stocky_second_order() -> None:
    """Shear-dominated elements (Phi = 12 E I / kappa G A h^2 >> 1 once h << d): the interdependent
    shape functions tend to linear ones, and the error tends to O(h^2)."""
    errs = _errors(0.2, 0.04, [4, 8, 16, 32, 64])
    assert np.all(np.diff(errs, axis=0) < 0), errs
    order = np.log2(errs[:-1] / errs[1:])
    assert np.all(order > 1.9) and np.all(order[-1] < 2.1), order
    assert np.all(errs[-1] < 4e-4)


def test_pinned_beam_modes_from_state_space_equal_undamped() -> None:
    L, d = 0.2, 0.04
    sys_ = build_system(rotor_config([0.0, L], d, RHO, E, G, NU, refine=10))
    free = np.setdiff1d(np.arange(sys_.n_dof), [0, 1, 40, 41])
    red = reduced(sys_, free)
    f_ss = modes(red, 0.0).frequency_hz[::2][:3]
    np.testing.assert_allclose(f_ss, natural_frequencies_at_rest(red)[::2][:3], rtol=1e-9)
