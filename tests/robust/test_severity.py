"""The certified severity interval (robust.severity) against brute force on a spring-mass chain.

A 4-mass chain (springs k_1..k_4 from the ground), a benign stiffness factor on every spring (+-2 %), a
severity = the loss of one spring. Data: the chain with spring 3 weakened by 30 % and the benign factor at
+1 %, complex Gaussian noise. Checked: the true spring's interval holds 0.30; a dense grid over (benign,
loss) outside the certified interval explains no grid value at every point (each fails at one of the
points used); an excluded spring's excluding points alone reject every grid value (the explicit search of
issue 11); with nearly no noise and no benign parameter the interval shrinks to the step around the truth.
"""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.robust.affine import AffineModel, AffineParameter
from rotorcheck.robust.box_test import Points, point_ratios
from rotorcheck.robust.severity import severity_interval
from tests.robust.robust_helpers import CHAIN_K, CHAIN_MASS, chain_spring

K, MASS, _spring = CHAIN_K, CHAIN_MASS, chain_spring


def _chain(benign: float, loss: dict[int, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    Kt = sum(K[i] * (1.0 + benign) * (1.0 - loss.get(i, 0.0)) * _spring(i) for i in range(4))
    M = np.diag(MASS)
    D = 2e-4 * sum(K[i] * _spring(i) for i in range(4))  # light stiffness-proportional damping (held)
    return M, D, Kt


def _model(spring: int, benign: bool = True) -> AffineModel:
    M, D, K0 = _chain(0.0, {})
    b, c = np.eye(4)[3], np.eye(4)[1]
    params = [AffineParameter("E", (("K", K0),), -0.02, 0.02)] if benign else []
    params.append(AffineParameter("loss", (("K", -K[spring] * _spring(spring)),), 0.0, 0.8))
    return AffineModel(M, D, K0, b, c, tuple(params))


def _points(noise: float, seed: int = 0, benign_true: float = 0.01) -> tuple[Points, np.ndarray]:
    """Data of the chain with spring 3 (index 2) 30 % weaker at 40 frequencies; also the healthy FRF."""
    w = 2 * np.pi * np.linspace(20.0, 180.0, 40)
    b, c = np.eye(4)[3], np.eye(4)[1]

    def frf(benign: float, loss: dict[int, float]) -> np.ndarray:
        M, D, Kt = _chain(benign, loss)
        return np.array([c @ np.linalg.solve(Kt - x**2 * M + 1j * x * D, b) for x in w])

    th, tn = frf(0.0, {}), frf(benign_true, {2: 0.30})
    rng = np.random.default_rng(seed)
    var_n, var_h = (noise * np.abs(tn)) ** 2, (noise * np.abs(th)) ** 2
    tn = tn + np.sqrt(var_n / 2) * (rng.standard_normal(40) + 1j * rng.standard_normal(40))
    th = th + np.sqrt(var_h / 2) * (rng.standard_normal(40) + 1j * rng.standard_normal(40))
    z = float(np.sqrt(-np.log1p(-(0.99) ** (1 / 40))))
    pts = Points(w, th * 0 + frf(0.0, {}), tn, th, var_n, var_h, z, np.zeros(40), 1.0, 1.0, np.zeros(40),
                 np.zeros(40), np.tile(b, (40, 1)), np.tile(c, (40, 1)))
    return pts, w


def _grid_fails(model: AffineModel, pts: Points, losses: np.ndarray, which: list[int] | None = None) -> np.ndarray:
    """(n,) bool: every benign value on a fine grid fails at one of the points (``which``: only those)."""
    sub = pts if which is None else pts.take(np.asarray(which))
    out = []
    for s in losses:
        fails = True
        for e in np.linspace(-0.02, 0.02, 81):
            theta = np.array([e, s]) if len(model.parameters) == 2 else np.array([s])
            if np.all(point_ratios(model, sub, theta) <= 1.0):
                fails = False
                break
        out.append(fails)
    return np.array(out)


def test_true_spring_interval_holds_the_truth_and_the_grid_outside_it_fails() -> None:
    pts, _ = _points(0.005)
    model = _model(2)
    lo = np.array([-0.02, 0.0])
    hi = np.array([0.02, 0.8])
    res = severity_interval(model, pts, lo, hi, 1, tol=0.01, slices=16, max_boxes=48)
    assert res.status == "consistent"
    assert res.lower <= 0.30 <= res.upper
    assert res.upper - res.lower < 0.2, (res.lower, res.upper)
    outside = np.r_[np.linspace(0.0, res.lower, 12, endpoint=False), np.linspace(res.upper, 0.8, 12)[1:]]
    assert np.all(_grid_fails(model, pts, outside))
    # the grid inside holds values that explain every point (the interval is not empty of witnesses)
    inside = np.linspace(res.lower, res.upper, 15)
    assert not np.all(_grid_fails(model, pts, inside))


@pytest.mark.parametrize("spring", [0, 3])
def test_an_excluded_spring_cannot_reproduce_the_data_at_its_excluding_points(spring: int) -> None:
    """Springs 1 and 4 (a wrong location): excluded, and at the points named no grid value of (benign,
    loss) explains the data (the explicit search)."""
    pts, _ = _points(0.005)
    model = _model(spring)
    res = severity_interval(model, pts, np.array([-0.02, 0.0]), np.array([0.02, 0.8]), 1, tol=0.01, slices=16,
                            max_boxes=48)
    assert res.status == "excluded", (res.lower, res.upper)
    assert len(res.excluding) >= 1
    assert np.all(_grid_fails(model, pts, np.linspace(0.0, 0.8, 161), list(res.excluding)))


def test_nearly_noise_free_interval_shrinks_to_the_step() -> None:
    """Noise 1e-4 of |T|, no benign parameter: the interval is the halving step around 0.30, and a witness
    (a loss explaining every point, evaluated exactly) is found in an end slice."""
    pts, _ = _points(1e-4, benign_true=0.0)
    pts = Points(pts.w, pts.g0, pts.t_new, pts.t_healthy, pts.var_new, pts.var_healthy, pts.z, pts.a2, 1.0, 1.0,
                 pts.tolerance, pts.relative_error, pts.b, pts.c)
    model = _model(2, benign=False)
    res = severity_interval(model, pts, np.array([0.0]), np.array([0.8]), 0, tol=0.005, slices=16, max_boxes=16)
    assert res.status == "consistent"
    assert res.lower <= 0.30 <= res.upper and res.upper - res.lower <= 0.011
    assert np.any(np.isfinite(res.witness_interval))


def _gyro_model() -> AffineModel:
    """The chain with a skew-symmetric velocity coupling of masses 1 and 2 (a gyroscopic-like term, so Z is not
    symmetric), its size a parameter beside the benign factor and the loss of spring 3."""
    M, D, K0 = _chain(0.0, {})
    G = np.zeros((4, 4))
    G[0, 1], G[1, 0] = 40.0, -40.0  # N s/m per unit parameter
    params = (AffineParameter("E", (("K", K0),), -0.02, 0.02), AffineParameter("speed", (("D", G),), -1.0, 1.0),
              AffineParameter("loss", (("K", -K[2] * _spring(2)),), 0.0, 0.8))
    return AffineModel(M, D, K0, np.eye(4)[3], np.eye(4)[1], params)


@pytest.mark.parametrize("symmetric", [True, False])
def test_a_point_that_excludes_a_box_is_explained_by_no_member_of_it(symmetric: bool) -> None:
    """examine_points against brute force: wherever a box's margin is positive at a point, 400 members of the
    box drawn at random (corners included) all leave that point unexplained; and the receptance of each member
    stays inside the small-gain disc the margin assumed."""
    from rotorcheck.robust.box_test import BoxFactors, examine_points

    model = _model(2) if symmetric else _gyro_model()
    fac = BoxFactors.of(model)
    assert model.symmetric is symmetric
    pts, _ = _points(0.005)
    rng = np.random.default_rng(3)
    lo = np.array([q.lo for q in model.parameters])
    hi = np.array([q.hi for q in model.parameters])
    positives = 0
    for _ in range(40):
        c = lo + (hi - lo) * rng.uniform(size=lo.size)
        h = (hi - lo) / 2.0 ** rng.integers(2, 7, size=lo.size)
        ok, margin, _share, _ = examine_points(model, fac, pts, c, h)
        members = c + h * rng.uniform(-1.0, 1.0, size=(400, lo.size))
        members[:2 ** lo.size] = c + h * np.array(np.meshgrid(*[[-1.0, 1.0]] * lo.size)).reshape(lo.size, -1).T
        bad = np.flatnonzero(margin > 0)
        positives += bad.size
        for theta in members:
            assert np.all(point_ratios(model, pts, theta)[bad] > 1.0)
        # the centre's verdict is the exact one
        assert np.array_equal(ok, point_ratios(model, pts, c) <= 1.0)
    assert positives > 20  # the check bit: boxes were excluded


@pytest.mark.parametrize("symmetric", [True, False])
def test_ratio_jacobian_matches_central_differences(symmetric: bool) -> None:
    from rotorcheck.robust.box_test import BoxFactors, ratio_jacobian

    model = _model(2) if symmetric else _gyro_model()
    pts, _ = _points(0.005)
    theta = np.array([0.01, 0.2]) if symmetric else np.array([0.01, 0.3, 0.2])
    r, J = ratio_jacobian(model, BoxFactors.of(model), pts, theta)
    assert np.array_equal(r, point_ratios(model, pts, theta))
    fd = np.zeros_like(J)
    for i in range(theta.size):
        e = np.zeros(theta.size)
        e[i] = 1e-6
        fd[:, i] = (point_ratios(model, pts, theta + e) - point_ratios(model, pts, theta - e)) / 2e-6
    assert np.max(np.abs(J - fd)) <= 1e-4 * np.max(np.abs(fd))



def test_a_refinement_from_an_earlier_pass_ends_where_a_fresh_run_does() -> None:
    """A refinement that starts from an earlier, coarser pass (its excluded slices not examined again) certifies
    the same ends as a fresh run at the refined budget and width, and the truth stays inside."""
    pts, _ = _points(0.005)
    model = _model(2)
    lo, hi = np.array([-0.02, 0.0]), np.array([0.02, 0.8])
    coarse = severity_interval(model, pts, lo, hi, 1, tol=0.02, slices=16, max_boxes=8)
    refined = severity_interval(model, pts, lo, hi, 1, tol=0.01, slices=16, max_boxes=48, earlier=coarse)
    fresh = severity_interval(model, pts, lo, hi, 1, tol=0.01, slices=16, max_boxes=48)
    assert (refined.lower, refined.upper) == (fresh.lower, fresh.upper)
    assert refined.lower <= 0.30 <= refined.upper
    assert refined.boxes <= fresh.boxes
