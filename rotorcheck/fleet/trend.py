"""Trend and prognosis: a straight line through a machine's low-frequency stiffness change over time since
its last change point, the line's slope with a confidence interval, and when it would cross a limit (the
fourth level of damage identification, prognosis).

Model: ``y_i = a + b (t_i - t_ref) + e_i`` over the sweeps since the last change point
(:mod:`rotorcheck.fleet.changepoint`), ``y`` the figure (N/m), ``t`` in days, ``e_i`` independent, Gaussian, of
one common variance estimated from the residuals: ordinary least squares, the slope's interval from Student's
t with n - 2 degrees of freedom (:func:`fit_line` with equal sigmas). Equal variances rather than each sweep's
own standard error: the scatter between sweeps (benign change such as temperature) dominates the scatter
within a sweep. The crossing time of a limit ``L`` is ``t* = (L - a) / b``; its interval is the set of times
at which the line's confidence band contains ``L`` (inverse regression, Fieller): bounded only when the slope
differs from 0 at the stated confidence. A crossing is forecast only for a machine whose latest verdict is
damage: a change that the rig's benign ranges explain (verdict healthy) is not extrapolated to a limit.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotorcheck.fleet.changepoint import CHANGE_ALPHA, MIN_TAIL, ChangePoint, kink_times, last_change_point

ASSUMPTIONS = (
    "the figure follows a straight line in time since the last change point, and on to the crossing (a crack "
    "that accelerates crosses earlier: the crossing time is then late, not early)",
    "independent Gaussian errors between sweeps of one common variance, estimated from the residuals (ordinary "
    "least squares; Student's t with n - 2 degrees of freedom): the scatter between sweeps, above all benign "
    "change such as temperature, dominates each sweep's own standard error",
    "the last change point: the largest share of the line's residuals that one kink (a change of slope) or one "
    "step (a change of level) explains, a change when its p-value (simulated for the sweep times) is at most "
    "1 %, repeated on the sweeps after it; the interval is conditional on that change point (it does not "
    "count the uncertainty of where the change is)",
    "the baseline's own noise shifts every sweep of a machine alike: it moves the level, not the slope",
    "a crossing is forecast only when the latest verdict is damage: a change the benign ranges explain (verdict "
    "healthy) is not extrapolated to the limit",
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
    profile_interval: tuple[float, float] | None = None  # the slope's interval when profiled (fit_kink)
    kink_days: float | None = None  # the kink (change of slope) the line begins at (fit_kink)

    @property
    def slope_se(self) -> float:
        return float(math.sqrt(self.cov[1, 1]))

    @property
    def slope_interval(self) -> tuple[float, float]:
        if self.profile_interval is not None:
            return self.profile_interval
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
    from scipy.stats import t as student_t  # lazy: scipy.stats (~0.3 s) only for Student's t

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
        from statistics import NormalDist  # lazy: statistics only with absolute sigmas

        scale, q = 1.0, NormalDist().inv_cdf(0.5 + confidence / 2.0)
    else:
        r = y - X @ beta
        scale = float(math.sqrt(float(np.sum(w * r * r)) / dof))
        cov = cov * scale**2
        q = _t_quantile(0.5 + confidence / 2.0, dof)
    return LineFit(float(beta[0]), float(beta[1]), cov, ref, n, dof, scale, float(q), confidence)


def fit_kink(t: Any, y: Any, taus: Any, confidence: float = 0.95, t_ref: float | None = None) -> LineFit:
    """The line after a kink at an unknown time: ``y = c + b1 min(t - tau, 0) + b2 max(t - tau, 0) + e``
    (a line before the kink, one after it, continuous; e independent Gaussian of one variance), ``tau`` the
    least-squares one of ``taus`` (days); ``b2`` (N/m per day) with its profile-likelihood interval: the
    slopes whose least residual sum of squares over every ``tau`` and the other parameters is at most
    ``RSS_min (1 + F / (n - 4))``, F the ``confidence`` quantile of F(1, n - 4) (the hull when the set is
    not one interval). The line's covariance (for its band and the crossing) is that at the best ``tau``,
    scaled by ``RSS_min / (n - 3)``, with Student's t on n - 3 degrees of freedom. Needs 5 points."""
    from scipy.special import fdtri  # lazy: scipy only for a kink's fit

    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    tau = np.asarray(taus, dtype=float)
    n = t.size
    if n < 5 or tau.size == 0:
        raise ValueError("a kink fit needs at least 5 points and a kink time")
    d = t[None, :] - tau[:, None]  # (G, n)
    X = np.stack([np.ones_like(d), np.minimum(d, 0.0), np.maximum(d, 0.0)], axis=2)  # (G, n, 3)
    inv = np.linalg.pinv(np.einsum("gni,gnj->gij", X, X))
    beta = np.einsum("gij,gnj,n->gi", inv, X, y)
    rss = np.sum((y[None, :] - np.einsum("gni,gi->gn", X, beta)) ** 2, axis=1)
    g = int(np.argmin(rss))
    crit = rss[g] * (1.0 + float(fdtri(1, n - 4, confidence)) / (n - 4))
    ok = rss <= crit
    half = np.sqrt(np.maximum(crit - rss[ok], 0.0) * inv[ok, 2, 2])
    interval = (float(np.min(beta[ok, 2] - half)), float(np.max(beta[ok, 2] + half)))
    ref = float(t[-1]) if t_ref is None else float(t_ref)
    s2 = float(rss[g]) / (n - 3)
    J = np.array([[1.0, 0.0, ref - tau[g]], [0.0, 0.0, 1.0]])  # (value at t_ref, b2) from (c, b1, b2)
    cov = J @ (inv[g] * s2) @ J.T
    c, b2 = float(beta[g, 0]), float(beta[g, 2])
    return LineFit(c + b2 * (ref - tau[g]), b2, cov, ref, n, n - 3, math.sqrt(s2),
                   _t_quantile(0.5 + confidence / 2.0, n - 3), confidence, interval, float(tau[g]))


@dataclass(frozen=True)
class Trend:
    """A machine's trend: the fit since its last change point, and the limit crossing (days since 1970)."""

    machine: str
    fit: LineFit | None
    used: list[int]  # indices (time order) of the sweeps since the last change point
    origin: float  # days of the first sweep (the time axis' zero is the epoch; see :func:`days`)
    limit_n_per_m: float | None
    crossing_days: float | None
    crossing_interval_days: tuple[float | None, float | None]
    status: str  # the trend and the prognosis, in words
    note: str = ""
    change_points: tuple[ChangePoint, ...] = ()
    change_times: tuple[str, ...] = ()  # the time (ISO) of the first sweep after each change point
    trend_words: str = ""  # "growing by X N/m per day [lo, hi] (95 %) since ..."
    forecast_words: str = ""  # the crossing, or why there is none
    latest_verdict: str = ""

    @property
    def forecast(self) -> bool:
        """A limit crossing is forecast (a time, with its interval)."""
        return self.crossing_days is not None

    def to_dict(self) -> dict[str, Any]:
        f = self.fit
        lo, hi = f.slope_interval if f is not None else (None, None)
        return {"machine": self.machine, "n_fitted": 0 if f is None else f.n, "n_since_change": len(self.used),
                "sweeps_since_change": self.used, "kink_time": iso_of_days(None if f is None else f.kink_days),
                "fit_start_time": self.change_times[-1] if self.change_times else None,
                "change_points": [{"time": iso_of_days(c.time), "kind": c.kind, "first_sweep_after": tm,
                                   "f_statistic": c.statistic, "p_value": c.p_value, "sweeps_scanned": c.points}
                                  for c, tm in zip(self.change_points, self.change_times)],
                "slope_n_per_m_per_day": None if f is None else f.b,
                "slope_se_n_per_m_per_day": None if f is None else f.slope_se,
                "slope_interval_n_per_m_per_day": [lo, hi], "confidence": None if f is None else f.confidence,
                "residual_sd_n_per_m": None if f is None else f.scale, "limit_n_per_m": self.limit_n_per_m,
                "latest_verdict": self.latest_verdict, "forecast": self.forecast,
                "crossing_time": iso_of_days(self.crossing_days),
                "crossing_interval": [iso_of_days(x) for x in self.crossing_interval_days],
                "trend": self.trend_words, "prognosis": self.forecast_words, "status": self.status,
                "note": self.note, "assumptions": list(ASSUMPTIONS)}


def days(iso: str) -> float:
    """Days since 1970-01-01 of an ISO time ``YYYY-MM-DDTHH:MM:SSZ``."""
    d = dt.datetime.strptime(iso, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=dt.timezone.utc)
    return d.timestamp() / 86400.0


def datetime_of_days(x: float) -> Any:
    """The UTC time (aware ``datetime``) ``x`` days after 1970-01-01 (the inverse of :func:`days`)."""
    return dt.datetime.fromtimestamp(x * 86400.0, dt.timezone.utc)


def iso_of_days(x: float | None) -> str | None:
    """The ISO time ``x`` days after 1970-01-01 (None stays None; far beyond year 9999 is None)."""
    from rotorcheck.fleet.layout import iso_utc  # lazy: fleet.layout (fileio, hashlib) only to format a time

    if x is None or not math.isfinite(x) or abs(x) > 2.9e6:
        return None
    return iso_utc(datetime_of_days(x))


def _date(x: float | None) -> str:
    iso = iso_of_days(x)
    return "unbounded" if iso is None else iso[:10]


def slope_words(fit: LineFit) -> str:
    """``growing by X N/m per day [lo, hi] (95 %)``, ``falling by ...`` or ``no significant change: ...``."""
    lo, hi = fit.slope_interval
    conf = f"({fit.confidence * 100:g} %)"
    if lo > 0.0:
        return f"growing by {fit.b:.3g} N/m per day [{lo:.3g}, {hi:.3g}] {conf}"
    if hi < 0.0:
        return f"falling by {-fit.b:.3g} N/m per day [{-hi:.3g}, {-lo:.3g}] {conf}"
    return f"no significant change: {fit.b:+.3g} N/m per day [{lo:.3g}, {hi:.3g}] {conf}"


def prognosis(fit: LineFit, limit: float | None, t_last: float, verdict: str
              ) -> tuple[str, float | None, tuple[float | None, float | None]]:
    """``(words, t*, (lo, hi))``: the crossing of ``limit`` (N/m) forecast from ``fit`` for a machine whose
    latest sweep (at ``t_last`` days) has ``verdict``; no crossing unless the verdict is damage and the slope
    is significantly positive (module docstring)."""
    if limit is None:
        return "no limit set (--limit)", None, (None, None)
    if fit.beyond(limit, t_last):
        return f"beyond the limit {limit:.4g} N/m already", None, (None, None)
    if verdict != "damage":
        why = ("the benign ranges explain the change" if verdict == "healthy" else
               f"the latest verdict is {verdict}, not damage")
        return f"no forecast of the limit {limit:.4g} N/m: {why}", None, (None, None)
    if fit.slope_interval[0] <= 0.0:
        return f"no crossing of {limit:.4g} N/m forecast: no significant growth", None, (None, None)
    t_hat, (c_lo, c_hi) = fit.crossing(limit)
    return (f"crosses the limit {limit:.4g} N/m on {_date(t_hat)} [{_date(c_lo)}, {_date(c_hi)}] "
            f"({fit.confidence * 100:g} %)", t_hat, (c_lo, c_hi))


def trend_fit(t: Any, y: Any, start: int, changes: list[ChangePoint], confidence: float = 0.95) -> LineFit:
    """The line since the last change point (:func:`last_change_point`'s ``start`` and ``changes``): after a
    kink (a change of slope), :func:`fit_kink` over the segment the kink was found in, its time profiled over
    the same candidates (the interval counts the uncertainty of where the change is); after a step, or when
    the segment is too short for a kink fit, ordinary least squares over the sweeps since ``start``; with no
    change, over every sweep."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    c = changes[-1] if changes else None
    if c is not None and c.kind == "kink" and t.size - c.segment_start >= 5:
        s0 = c.segment_start
        taus = kink_times(t, s0, MIN_TAIL, c.last_first)
        return fit_kink(t[s0:], y[s0:], taus, confidence, t_ref=float(t[-1]))
    return fit_line(t[start:], y[start:], np.ones(t.size - start), confidence, t_ref=float(t[-1]))


def machine_trend(machine: str, rows: list[dict[str, Any]], limit_n_per_m: float | None,
                  confidence: float = 0.95, change_alpha: float = CHANGE_ALPHA) -> Trend:
    """The trend of one machine's rows (time order; each with ``time``, ``verdict`` and
    ``du_low_re_n_per_m``): the line since the last change point and the prognosis (module docstring)."""
    good = [i for i, r in enumerate(rows) if r.get("du_low_re_n_per_m") is not None]
    origin = days(rows[0]["time"]) if rows else 0.0
    verdict = rows[good[-1]]["verdict"] if good else ""
    if len(good) < 3:
        words = "too few sweeps to fit a trend (3 needed)"
        return Trend(machine, None, good, origin, limit_n_per_m, None, (None, None), words, trend_words=words,
                     latest_verdict=verdict)
    t = np.array([days(rows[i]["time"]) for i in good])
    y = np.array([rows[i]["du_low_re_n_per_m"] for i in good], dtype=float)
    # the current run of damage verdicts (error rows are not in ``good``): a change known to have begun by its
    # first sweep, located there (changepoint.last_change_point)
    d = len(good)
    while d > 0 and rows[good[d - 1]]["verdict"] == "damage":
        d -= 1
    start, changes = last_change_point(t, y, change_alpha, known_by=d if d < len(good) else None)
    fit = trend_fit(t, y, start, changes, confidence)
    times = tuple(rows[good[c.index]]["time"] for c in changes)
    if changes:
        c = changes[-1]
        what = "a change of slope" if c.kind == "kink" else "a change of level"
        how = "located before the first damage verdict" if d < len(good) else f"p = {c.p_value:.2g}"
        span = (f"over the {len(good) - start} sweeps since the last change point ({what} about {_date(c.time)}, "
                f"{how})")
    else:
        span = f"over all {fit.n} sweeps (no change point at p <= {change_alpha:g})"
    words = f"{slope_words(fit)} {span}"
    forecast, t_hat, (c_lo, c_hi) = prognosis(fit, limit_n_per_m, float(t[-1]), verdict)
    return Trend(machine, fit, good[start:], origin, limit_n_per_m, t_hat, (c_lo, c_hi), f"{words}; {forecast}",
                 change_points=tuple(changes), change_times=times, trend_words=words, forecast_words=forecast,
                 latest_verdict=verdict)
