"""The line fit against closed forms and brute force, and its intervals' coverage by Monte Carlo (the change
point and the kink fit: test_fleet_changepoint.py)."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.fleet.trend import fit_line, machine_trend


def _data(rng: np.random.Generator, n: int = 8, a: float = 120.0, b: float = 35.0) -> tuple[np.ndarray, ...]:
    t = np.sort(rng.uniform(0.0, 70.0, n))
    sigma = rng.uniform(20.0, 80.0, n)
    return t, a + b * t, sigma


def test_fit_matches_polyfit() -> None:
    """Estimates and both covariances against numpy.polyfit (w = 1/sigma; cov 'unscaled' and scaled)."""
    rng = np.random.default_rng(1)
    t, mean, sigma = _data(rng)
    y = mean + sigma * rng.standard_normal(t.size)
    p, cov_u = np.polyfit(t, y, 1, w=1.0 / sigma, cov="unscaled")
    _, cov_s = np.polyfit(t, y, 1, w=1.0 / sigma, cov=True)
    fa = fit_line(t, y, sigma, absolute_sigma=True, t_ref=0.0)
    fr = fit_line(t, y, sigma, absolute_sigma=False, t_ref=0.0)
    for f in (fa, fr):
        assert f.b == pytest.approx(p[0], rel=1e-10) and f.a == pytest.approx(p[1], rel=1e-10)
    assert fa.cov[1, 1] == pytest.approx(cov_u[0, 0], rel=1e-9)
    assert fa.cov[0, 1] == pytest.approx(cov_u[0, 1], rel=1e-9)
    assert fr.cov[1, 1] == pytest.approx(cov_s[0, 0], rel=1e-9)
    assert fr.quantile == pytest.approx(2.446911851, rel=1e-8)  # Student t, 6 dof, 97.5 %
    assert fa.quantile == pytest.approx(1.959963985, rel=1e-8)


@pytest.mark.parametrize("absolute", [True, False])
def test_slope_and_crossing_coverage(absolute: bool) -> None:
    """95 % intervals of the slope and of the crossing time cover the truth 95 % of the time (2000 fleets
    of 8 sweeps, known line and sigmas): binomial band 0.95 +- 0.012 (2.5 sd)."""
    rng = np.random.default_rng(7)
    a, b, limit = 120.0, 35.0, 4000.0
    t_cross = (limit - a) / b
    hits_s = hits_c = 0
    n = 2000
    for _ in range(n):
        t, mean, sigma = _data(rng, a=a, b=b)
        f = fit_line(t, mean + sigma * rng.standard_normal(t.size), sigma, absolute_sigma=absolute)
        lo, hi = f.slope_interval
        hits_s += lo <= b <= hi
        _, (c_lo, c_hi) = f.crossing(limit)
        hits_c += (c_lo is None or c_lo <= t_cross) and (c_hi is None or t_cross <= c_hi)
    assert abs(hits_s / n - 0.95) < 0.012
    assert abs(hits_c / n - 0.95) < 0.012


def test_crossing_against_brute_force() -> None:
    """The crossing interval equals the set of times whose confidence band holds the limit (a fine grid)."""
    rng = np.random.default_rng(3)
    t, mean, sigma = _data(rng)
    f = fit_line(t, mean + sigma * rng.standard_normal(t.size), sigma)
    limit = 3500.0
    t_hat, (lo, hi) = f.crossing(limit)
    assert t_hat == pytest.approx((limit - f.a) / f.b + f.t_ref)
    grid = np.linspace(0.0, 400.0, 400_001)
    val = f.a + f.b * (grid - f.t_ref)
    x = grid - f.t_ref
    se = np.sqrt(f.cov[0, 0] + 2 * x * f.cov[0, 1] + x * x * f.cov[1, 1])
    inside = grid[np.abs(val - limit) <= f.quantile * se]
    assert lo is not None and hi is not None
    assert lo == pytest.approx(inside.min(), abs=2e-3) and hi == pytest.approx(inside.max(), abs=2e-3)


def test_flat_trend_has_no_bounded_crossing() -> None:
    rng = np.random.default_rng(5)
    t = np.arange(8) * 7.0
    sigma = np.full(8, 50.0)
    f = fit_line(t, 10.0 + sigma * rng.standard_normal(8), sigma)
    lo, hi = f.slope_interval
    assert lo < 0 < hi
    assert f.crossing(3000.0)[1] == (None, None)


def test_machine_trend_crossing_in_calendar_time() -> None:
    """Rows on an exact line (tiny scatter): slope per day and the crossing date from the closed form."""
    rows = [{"time": f"2026-03-{1 + 7 * k:02d}T02:00:00Z", "verdict": "damage", "du_low_re_n_per_m": 100.0 + 70.0 * k
             + (1.0 if k % 2 else -1.0), "du_low_se_n_per_m": 1.0} for k in range(4)]
    tr = machine_trend("m", rows, 1500.0)
    assert tr.fit is not None
    assert tr.fit.b == pytest.approx(10.0, rel=0.01)  # 70 N/m per 7 days
    d = tr.to_dict()
    # 100 + 10 N/m/day reaches 1500 after 140 days: 2026-03-01 + 140 d = 2026-07-19
    assert d["crossing_time"].startswith("2026-07-1")
    assert d["crossing_interval"][0] <= d["crossing_time"] <= d["crossing_interval"][1]
