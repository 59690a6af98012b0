"""Trend and prognosis: a weighted least-squares line through a machine's low-frequency stiffness change
over time, its slope with a confidence interval, and when it would cross a limit (the fourth level of
damage identification, prognosis).

Model: ``y_i = a + b (t_i - t_ref) + e_i`` with ``y`` the figure (N/m), ``t`` in days, ``e_i`` independent,
Gaussian, with standard deviations ``sigma_i`` known up to a common factor (``absolute_sigma=False``, the
default: the factor is estimated from the residuals, and intervals use Student's t with n - 2 degrees of
freedom) or exactly (``absolute_sigma=True``: the normal quantile). The crossing time of a limit ``L`` is
``t* = (L - a) / b``; its interval is the set of times at which the line's confidence band contains ``L``
(inverse regression, Fieller): bounded only when the slope differs from 0 at the stated confidence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

ASSUMPTIONS = (
    "linear growth of the low-frequency stiffness change with time over the fitted sweeps, and on to the "
    "crossing (a crack that accelerates crosses earlier: the crossing time is then late, not early)",
    "independent Gaussian errors between sweeps, each sweep's standard error (the scatter of Re D_u over the "
    "low band's points) known up to one common factor estimated from the residuals (Student's t, n - 2 "
    "degrees of freedom)",
    "the baseline's own noise shifts every sweep of a machine alike: it moves the level, not the slope",
    "fitted sweeps: those since the current run of damage verdicts began (at least the last 3), else all",
)


@dataclass(frozen=True)
class LineFit:
    """A weighted least-squares line ``a + b (t - t_ref)`` (t in days) and its covariance."""

    a: float
    b: float
    cov: np.ndarray  # (2, 2) covariance of (a, b)
    t_ref: float
    n: int
    dof: int
    scale: float  # sqrt of the reduced chi-square (the common factor of the sigmas; 1 when absolute)
    quantile: float  # two-sided quantile at ``confidence`` (t with dof, or normal)
    confidence: float

    @property
    def slope_se(self) -> float:
        return float(math.sqrt(self.cov[1, 1]))

    @property
    def slope_interval(self) -> tuple[float, float]:
        return (self.b - self.quantile * self.slope_se, self.b + self.quantile * self.slope_se)

    def value(self, t: float) -> float:
        return self.a + self.b * (t - self.t_ref)

    def value_se(self, t: float) -> float:
        x = t - self.t_ref
        return float(math.sqrt(max(self.cov[0, 0] + 2.0 * x * self.cov[0, 1] + x * x * self.cov[1, 1], 0.0)))

    def beyond(self, limit: float, t: float) -> bool:
        """The fitted line at ``t`` (days) exceeds ``limit`` (N/m) by more than its confidence half-width."""
        return self.value(t) - self.quantile * self.value_se(t) >= limit

    def crossing(self, limit: float) -> tuple[float | None, tuple[float | None, float | None]]:
        """``(t*, (lo, hi))``: when the line reaches ``limit`` (days, same origin as the data; None when
        the slope is 0) and the times whose confidence band contains ``limit``: ``(lo, hi)`` bounded when
        the slope is significant; an end is None where the set is unbounded (slope not significant)."""
        t_hat = None if self.b == 0.0 else self.t_ref + (limit - self.a) / self.b
        q2 = self.quantile**2
        d = self.a - limit
        va, vab, vb = float(self.cov[0, 0]), float(self.cov[0, 1]), float(self.cov[1, 1])
        A = self.b**2 - q2 * vb
        B = 2.0 * (self.b * d - q2 * vab)
        C = d * d - q2 * va
        if A <= 0.0:  # slope not significant: the set is unbounded (one or both sides)
            return t_hat, (None, None)
        disc = B * B - 4.0 * A * C
        r = math.sqrt(max(disc, 0.0))
        lo, hi = (-B - r) / (2.0 * A), (-B + r) / (2.0 * A)
        return t_hat, (self.t_ref + lo, self.t_ref + hi)


def _t_quantile(p: float, dof: int) -> float:
    from scipy.stats import t as student_t

    return float(student_t.ppf(p, dof))


def fit_line(t: Any, y: Any, sigma: Any, confidence: float = 0.95, absolute_sigma: bool = False,
             t_ref: float | None = None) -> LineFit:
    """Weighted least squares of ``y`` (any unit) on ``t`` (days) with standard deviations ``sigma``
    (module docstring); needs at least 3 points (2 with ``absolute_sigma``)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    s = np.asarray(sigma, dtype=float)
    n = t.size
    if n < (2 if absolute_sigma else 3) or y.size != n or s.size != n:
        raise ValueError(f"a line needs at least {2 if absolute_sigma else 3} points with y and sigma each")
    if not np.all(np.isfinite(s) & (s > 0)):
        raise ValueError("every sigma must be finite and > 0")
    ref = float(np.mean(t)) if t_ref is None else float(t_ref)
    X = np.column_stack([np.ones(n), t - ref])
    w = 1.0 / s**2
    XtW = X.T * w
    M = XtW @ X
    cov = np.linalg.inv(M)
    beta = cov @ (XtW @ y)
    dof = n - 2
    if absolute_sigma:
        from statistics import NormalDist

        scale, q = 1.0, NormalDist().inv_cdf(0.5 + confidence / 2.0)
    else:
        r = y - X @ beta
        scale = float(math.sqrt(float(np.sum(w * r * r)) / dof))
        cov = cov * scale**2
        q = _t_quantile(0.5 + confidence / 2.0, dof)
    return LineFit(float(beta[0]), float(beta[1]), cov, ref, n, dof, scale, float(q), confidence)


@dataclass(frozen=True)
class Trend:
    """A machine's trend: the fit over its chosen sweeps, and the limit crossing (days from ``origin``)."""

    machine: str
    fit: LineFit | None
    used: list[int]  # indices (time order) of the sweeps fitted
    origin: float  # days of the first sweep (the time axis' zero is the epoch; see :func:`days`)
    limit_n_per_m: float | None
    crossing_days: float | None
    crossing_interval_days: tuple[float | None, float | None]
    status: str  # what the prognosis says, in words
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        f = self.fit
        lo, hi = f.slope_interval if f is not None else (None, None)
        return {"machine": self.machine, "n_fitted": 0 if f is None else f.n, "fitted_sweeps": self.used,
                "slope_n_per_m_per_day": None if f is None else f.b,
                "slope_se_n_per_m_per_day": None if f is None else f.slope_se,
                "slope_interval_n_per_m_per_day": [lo, hi], "confidence": None if f is None else f.confidence,
                "residual_scale": None if f is None else f.scale, "limit_n_per_m": self.limit_n_per_m,
                "crossing_time": iso_of_days(self.crossing_days),
                "crossing_interval": [iso_of_days(x) for x in self.crossing_interval_days],
                "status": self.status, "note": self.note, "assumptions": list(ASSUMPTIONS)}


def days(iso: str) -> float:
    """Days since 1970-01-01 of an ISO time ``YYYY-MM-DDTHH:MM:SSZ``."""
    import datetime as dt

    d = dt.datetime.strptime(iso, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=dt.timezone.utc)
    return d.timestamp() / 86400.0


def datetime_of_days(x: float) -> Any:
    """The UTC time (aware ``datetime``) ``x`` days after 1970-01-01 (the inverse of :func:`days`)."""
    import datetime as dt

    return dt.datetime.fromtimestamp(x * 86400.0, dt.timezone.utc)


def iso_of_days(x: float | None) -> str | None:
    """The ISO time ``x`` days after 1970-01-01 (None stays None; far beyond year 9999 is None)."""
    from rotorcheck.fleet.layout import iso_utc

    if x is None or not math.isfinite(x) or abs(x) > 2.9e6:
        return None
    return iso_utc(datetime_of_days(x))


def fit_window(verdicts: list[str], min_points: int = 3) -> list[int]:
    """The sweeps to fit: the current run of damage verdicts at the end, extended back to at least
    ``min_points``; all sweeps when the latest is not damage."""
    n = len(verdicts)
    k = n
    while k > 0 and verdicts[k - 1] == "damage":
        k -= 1
    if k == n:
        return list(range(n))
    return list(range(min(k, max(n - min_points, 0)), n))


def machine_trend(machine: str, rows: list[dict[str, Any]], limit_n_per_m: float | None,
                  confidence: float = 0.95) -> Trend:
    """The trend of one machine's rows (time order; each with ``time``, ``verdict``,
    ``du_low_re_n_per_m``, ``du_low_se_n_per_m``)."""
    good = [i for i, r in enumerate(rows) if r.get("du_low_re_n_per_m") is not None and r.get("du_low_se_n_per_m")]
    sub = [rows[i] for i in good]
    window = [good[j] for j in fit_window([r["verdict"] for r in sub])]
    origin = days(rows[0]["time"]) if rows else 0.0
    if len(window) < 3:
        return Trend(machine, None, window, origin, limit_n_per_m, None, (None, None),
                     "too few sweeps to fit a trend (3 needed)")
    t = np.array([days(rows[i]["time"]) for i in window])
    y = np.array([rows[i]["du_low_re_n_per_m"] for i in window], dtype=float)
    s = np.array([rows[i]["du_low_se_n_per_m"] for i in window], dtype=float)
    fit = fit_line(t, y, s, confidence, t_ref=float(t[-1]))
    lo, hi = fit.slope_interval
    growing = lo > 0.0
    trend_words = (f"growing: {fit.b:.3g} N/m per day [{lo:.3g}, {hi:.3g}] ({confidence:.0%})" if growing else
                   f"no significant growth: slope {fit.b:.3g} N/m per day [{lo:.3g}, {hi:.3g}] ({confidence:.0%})")
    if limit_n_per_m is None:
        return Trend(machine, fit, window, origin, None, None, (None, None), trend_words)
    t_hat, (c_lo, c_hi) = fit.crossing(limit_n_per_m)
    last = float(t[-1])
    if fit.beyond(limit_n_per_m, last):
        status = f"{trend_words}; beyond the limit {limit_n_per_m:.4g} N/m already"
    elif not growing:
        status = f"{trend_words}; no crossing of {limit_n_per_m:.4g} N/m predicted"
        t_hat, c_lo, c_hi = None, None, None
    else:
        status = (f"{trend_words}; crosses {limit_n_per_m:.4g} N/m at {iso_of_days(t_hat)} "
                  f"[{iso_of_days(c_lo)}, {iso_of_days(c_hi)}]")
    return Trend(machine, fit, window, origin, limit_n_per_m, t_hat, (c_lo, c_hi), status)
