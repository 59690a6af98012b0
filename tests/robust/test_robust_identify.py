"""Identified damage dynamics (eq. 3.11) and its exact Moebius uncertainty set."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.robust import closed_form as cf
from rotorcheck.robust import identify as idf
from rotorcheck.robust import lft


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def test_damage_dynamics_inverts_the_damage_lft() -> None:
    rng = np.random.default_rng(0)
    f = 20
    E11, E12, E21, E22 = (cplx(rng, f) for _ in range(4))
    D = cplx(rng, f)
    T = E22 + E21 * D / (1 - E11 * D) * E12
    np.testing.assert_allclose(idf.damage_dynamics(E11, E12, E21, E22, T), D, rtol=1e-10)
    # matrix version: 2 damage ports, 2 x 2 io
    E11m, E12m, E21m, E22m = (cplx(rng, f, 2, 2) for _ in range(4))
    Dm = 0.3 * cplx(rng, f, 2, 2)
    E = np.concatenate([np.concatenate([E11m, E12m], 2), np.concatenate([E21m, E22m], 2)], 1)
    Tm = lft.lft_upper(E, Dm)
    np.testing.assert_allclose(idf.damage_dynamics(E11m, E12m, E21m, E22m, Tm), Dm, rtol=1e-9)


def _sample_boundary(fun, r: float, n: int = 200_001) -> np.ndarray:  # type: ignore[no-untyped-def]
    th = np.linspace(-np.pi, np.pi, n)
    return fun(r * np.exp(1j * th))


def _check_against_sampling(ds: idf.DamageSet, i: int, fun, r: float) -> str:  # type: ignore[no-untyped-def]
    """min/max |D| and phase range of set i vs dense sampling of |Delta| = r and of the interior."""
    zb = _sample_boundary(fun, r)
    rr = np.linspace(0, r, 301)[:, None]
    th = np.linspace(-np.pi, np.pi, 721)[None, :]
    zi = fun((rr * np.exp(1j * th)).ravel())
    zi = zi[np.isfinite(zi)]
    allz = np.concatenate([zb[np.isfinite(zb)], zi])
    assert ds.contains_at(i, allz).all()
    assert ds.contains(ds.nominal)[i]
    kind = ds.kind[i]
    scale = max(abs(ds.nominal[i]), 1e-300)
    if kind == "disk":
        assert np.max(np.abs(np.abs(zb - ds.centre[i]) - ds.radius[i])) <= 1e-8 * ds.radius[i]
        # holomorphic without zeros/poles inside (unless 0 is in the set): extremes on the boundary
        assert abs(np.abs(zb).max() - ds.max_abs[i]) <= 1e-8 * ds.max_abs[i]
        if ds.min_abs[i] > 0:
            assert abs(np.abs(zb).min() - ds.min_abs[i]) <= 1e-8 * ds.max_abs[i]
            ang = np.unwrap(np.angle(zb / ds.centre[i])) + np.angle(ds.centre[i])
            assert abs(ang.min() - ds.phase_min[i]) < 1e-5
            assert abs(ang.max() - ds.phase_max[i]) < 1e-5
        else:
            assert np.abs(allz).min() <= 2e-2 * ds.max_abs[i]
            assert ds.phase_max[i] - ds.phase_min[i] == pytest.approx(2 * np.pi)
        assert np.abs(allz).max() <= ds.max_abs[i] * (1 + 1e-9)
        assert np.abs(allz).min() >= ds.min_abs[i] * (1 - 1e-9) - 1e-12 * scale
    elif kind == "outside":
        assert np.isinf(ds.max_abs[i])
        zf = zb[np.isfinite(zb)]
        # the boundary images lie on the circle, the image of Delta = 0 outside it
        assert np.max(np.abs(np.abs(zf - ds.centre[i]) - ds.radius[i])) <= 1e-7 * ds.radius[i]
        assert abs(ds.nominal[i] - ds.centre[i]) > ds.radius[i]
        assert np.abs(allz).min() >= ds.min_abs[i] * (1 - 1e-9) - 1e-12 * scale
        if ds.min_abs[i] > 0:
            assert abs(np.abs(zf).min() - ds.min_abs[i]) <= 1e-7 * ds.radius[i]
        assert ds.phase_max[i] - ds.phase_min[i] == pytest.approx(2 * np.pi)
    return str(kind)


def test_additive_moebius_set_vs_method_md_and_sampling() -> None:
    rng = np.random.default_rng(1)
    f = 40
    E11, E12, E21, E22 = (cplx(rng, f) for _ in range(4))
    T = E22 + 0.5 * cplx(rng, f)
    gamma = 0.2 * np.abs(cplx(rng, f))
    W = 10 * cplx(rng, f)
    V = 0.3
    ds = idf.damage_set_io(E11, E12, E21, E22, T, gamma, V, W)
    r = gamma + V / np.abs(W)
    C, R, valid = cf.damage_disk_additive(T, E11, E12, E21, E22, r)
    assert np.array_equal(valid, ds.kind == "disk")
    np.testing.assert_allclose(ds.centre[valid], C[valid], rtol=1e-10)
    np.testing.assert_allclose(ds.radius[valid], R[valid], rtol=1e-10)
    np.testing.assert_allclose(ds.nominal, idf.damage_dynamics(E11, E12, E21, E22, T), rtol=1e-12)
    kinds = set()
    for i in range(f):
        def fun(d: np.ndarray, i: int = i) -> np.ndarray:
            with np.errstate(divide="ignore", invalid="ignore"):
                return 1 / (E12[i] * E21[i] / (T[i] - E22[i] - d) + E11[i])
        kinds.add(_check_against_sampling(ds, i, fun, float(r[i])))
    assert {"disk", "outside"} <= kinds


def test_parametric_moebius_set_vs_sampling_and_origin_cases() -> None:
    """Engineering system uncertain through a mass (rank-1 parametric LFT), several radii so that
    bounded disks, disks holding the origin and unbounded sets all occur."""
    rng = np.random.default_rng(2)
    f, n = 8, 4
    Z0 = cplx(rng, f, n, n) + 2 * np.eye(n)
    L, R = lft.mass_factor(np.linspace(1, 3, f), 0, n, scale=0.7)
    meE = lft.engineering_me(Z0, L, R, 2, 1, 1)
    T = lft.engineering_system(Z0 - 0.8 * np.eye(n)[None] * (np.arange(n) == 2), 2, 1, 1)[3][:, 0, 0]
    kinds = set()
    for rad in (0.05, 0.5, 3.0):
        ds = idf.damage_set(meE, T, rad)
        for i in range(f):
            def fun(d: np.ndarray, i: int = i) -> np.ndarray:
                E = lft.lft_upper(np.broadcast_to(meE[i], (d.size, 3, 3)), d[:, None, None])
                with np.errstate(divide="ignore", invalid="ignore"):
                    return 1 / (E[:, 0, 1] * E[:, 1, 0] / (T[i] - E[:, 1, 1]) + E[:, 0, 0])
            kinds.add(_check_against_sampling(ds, i, fun, rad))
            if ds.kind[i] == "disk" and ds.min_abs[i] == 0:
                kinds.add("disk_with_origin")
    assert {"disk", "outside"} <= kinds


def test_halfplane_and_point_cases() -> None:
    rng = np.random.default_rng(3)
    E11, E12, E21, E22 = (cplx(rng, 1) for _ in range(4))
    T = E22 + cplx(rng, 1)
    q = T - E22
    delta = E11 * q + E12 * E21
    r_pole = float(np.abs(delta / E11)[0])  # the pole of D(eta) lies on |eta| = r
    ds = idf.damage_set_io(E11, E12, E21, E22, T, np.array([r_pole]), 0.0, np.ones(1))
    assert ds.kind[0] == "halfplane" and np.isinf(ds.max_abs[0])
    th = np.linspace(-np.pi, np.pi, 100_001)[1:-1]
    eta = r_pole * np.exp(1j * (th + np.angle(delta / E11)[0]))
    z = 1 / (E12 * E21 / (q - eta) + E11)
    z = z[np.isfinite(z) & (np.abs(z) < 1e6)]
    # the boundary images lie on the half-plane's line, the centre image inside
    line = (np.conj(ds.normal[0]) * z).real - ds.offset[0]
    assert np.max(np.abs(line)) < 1e-6 * max(1.0, abs(ds.offset[0]))
    assert (np.conj(ds.normal[0]) * ds.nominal[0]).real > ds.offset[0]
    assert abs(np.abs(z).min() - ds.min_abs[0]) < 1e-6 * max(1.0, ds.min_abs[0])
    pt = idf.damage_set_io(E11, E12, E21, E22, T, np.array([0.0]), 0.0, np.ones(1))
    assert pt.kind[0] == "point" and pt.radius[0] == 0
    assert pt.min_abs[0] == pt.max_abs[0] == pytest.approx(abs(pt.nominal[0]))
