"""Modal and Rayleigh damping: ratios per distinct mode (x/y pairs), speed-dependent bearings."""

from __future__ import annotations

import numpy as np
import pytest
from fe_helpers import rotor_config

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.damping import modal_damping_matrix, ratio_per_mode, undamped_modes
from rotorcheck.fe.modal import modes

RATIOS = [0.01, 0.02, 0.03, 0.04]


def _rotor(kxx: float, kyy: float, kxy: float = 0.0, damping: dict | None = None, kxx_table=None):
    brg = {"kxx": kxx_table or kxx, "kyy": kyy, "kxy": kxy, "kyx": -kxy}
    return build_system(
        rotor_config(
            [0.0, 0.1, 0.3, 0.5, 0.6],
            0.02,
            refine=2,
            discs=[{"station": 3, "mass": 2.0, "polar_inertia": 0.01, "transverse_inertia": 0.006}],
            bearings=[{"station": s, **brg} for s in (2, 4)],
            damping=damping or {"kind": "modal", "ratios": RATIOS},
        )
    )


def test_ratio_list_last_value_repeats() -> None:
    np.testing.assert_array_equal(ratio_per_mode([0.1, 0.2], 4), [0.1, 0.2, 0.2, 0.2])
    np.testing.assert_array_equal(ratio_per_mode([0.1, 0.2, 0.3], 2), [0.1, 0.2])


@pytest.mark.parametrize("kyy", [1e7, 2.5e7])
def test_modal_damping_per_mode_pair(kyy: float) -> None:
    """Isotropic (degenerate pairs) and anisotropic (split pairs): the i-th mode of each plane gets
    ratio i, and the damped eigenvalues at rest show exactly those ratios (classical damping)."""
    sys_ = _rotor(1e7, kyy)
    md = modes(sys_, 0.0, n_modes=8)
    if kyy == 1e7:
        np.testing.assert_allclose(md.damping_ratio, np.repeat(RATIOS, 2), rtol=1e-9)
    else:  # planar modes: rank within each plane (x and y orders interleave in frequency)
        ix, iy = sys_.plane_dofs()
        in_x = np.linalg.norm(md.shapes[ix], axis=0) > np.linalg.norm(md.shapes[iy], axis=0)
        assert in_x.sum() == 4
        np.testing.assert_allclose(md.damping_ratio[in_x], RATIOS, rtol=1e-9)
        np.testing.assert_allclose(md.damping_ratio[~in_x], RATIOS, rtol=1e-9)
    # Phi^T C Phi = diag(2 zeta w) over the whole x plane
    M, C, _, K = sys_.matrices(0.0)
    ix, _ = sys_.plane_dofs()
    w, phi = undamped_modes(M[np.ix_(ix, ix)], K[np.ix_(ix, ix)])
    modal_c = phi.T @ C[np.ix_(ix, ix)] @ phi
    np.testing.assert_allclose(
        modal_c, np.diag(2 * ratio_per_mode(RATIOS, w.size) * w), atol=1e-9 * np.abs(modal_c).max()
    )
    if kyy != 1e7:
        f = md.frequency_hz
        assert abs(f[1] / f[0] - 1) > 1e-3  # pairs are really split, yet share their ratio


def test_cross_coupled_bearings_fall_back_to_frequency_pairs() -> None:
    sys_ = _rotor(1e7, 1.2e7, kxy=2e6)
    M, C, _, K = sys_.matrices(0.0)
    w, phi = undamped_modes(M, K)
    expect = 2 * ratio_per_mode(RATIOS, w.size)[np.arange(w.size) // 2] * w
    np.testing.assert_allclose(phi.T @ C @ phi, np.diag(expect), atol=1e-9 * expect.max())


def test_lumped_ratios_per_mode() -> None:
    M = np.diag([1.0, 2.0, 3.0])
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]]) * 1e3
    C = modal_damping_matrix(M, K, [0.05, 0.1])
    w, phi = undamped_modes(M, K)
    np.testing.assert_allclose(phi.T @ C @ phi, np.diag(2 * np.array([0.05, 0.1, 0.1]) * w), atol=1e-12)


def test_modal_damping_follows_speed_dependent_bearings() -> None:
    table = {"speed_rpm": [0.0, 10000.0], "values": [1e7, 4e7]}
    sys_ = _rotor(1e7, 1e7, kxx_table=table)
    M, C0, _, K0 = sys_.matrices(0.0)
    _, C1, _, K1 = sys_.matrices(5000.0)
    assert K1[sys_.dof(2, "x"), sys_.dof(2, "x")] - K0[sys_.dof(2, "x"), sys_.dof(2, "x")] == pytest.approx(
        1.5e7
    )
    assert not np.allclose(C0, C1)
    ix, _ = sys_.plane_dofs()
    w, phi = undamped_modes(M[np.ix_(ix, ix)], K1[np.ix_(ix, ix)])
    np.testing.assert_allclose(
        np.diag(phi.T @ C1[np.ix_(ix, ix)] @ phi), 2 * ratio_per_mode(RATIOS, w.size) * w, rtol=1e-8
    )
    # cache returns equal, independent copies
    a = sys_.matrices(5000.0)[1]
    a[:] = 0.0
    np.testing.assert_array_equal(sys_.matrices(5000.0)[1], C1)


def test_rayleigh_damping_ratios() -> None:
    alpha, beta = 2.0, 1e-5
    sys_ = _rotor(1e7, 1e7, damping={"kind": "rayleigh", "alpha": alpha, "beta": beta})
    md = modes(sys_, 0.0, n_modes=6)
    wn = np.abs(md.eigenvalues)
    np.testing.assert_allclose(md.damping_ratio, alpha / (2 * wn) + beta * wn / 2, rtol=1e-9)


def test_bearing_damping_adds_to_structural() -> None:
    sys_ = _rotor(1e7, 1e7)
    cfg_c = rotor_config(
        [0.0, 0.1, 0.3, 0.5, 0.6],
        0.02,
        refine=2,
        discs=[{"station": 3, "mass": 2.0, "polar_inertia": 0.01, "transverse_inertia": 0.006}],
        bearings=[{"station": s, "kxx": 1e7, "kyy": 1e7, "cxx": 100.0, "cyy": 200.0} for s in (2, 4)],
        damping={"kind": "modal", "ratios": RATIOS},
    )
    C = build_system(cfg_c).matrices(0.0)[1] - sys_.matrices(0.0)[1]
    d = sys_.dof(2, "x")
    assert C[d, d] == pytest.approx(100.0) and C[d + 1, d + 1] == pytest.approx(200.0)
    assert np.abs(C).sum() == pytest.approx(600.0)
