r"""Detection centred on the measured healthy response (the default detection mode).

Step 4 of the method with the healthy uncertain set centred on what was measured: of the eq. 3.12
set of systems the healthy sweep is consistent with, take the member the healthy data selects
(``E22 := T_h``, the measured healthy FRF), keep the model's damage-port channels ``E11, E12,
E21`` (they say how a local change at the port can move the outputs:
``T - E22 = E21 D (I - E11 D)^-1 E12``), and let the uncertainty be the noise of both sweeps.
A point of a new sweep is a *certified fault point* iff its FRF cannot be explained as the healthy
FRF plus the noise of the two sweeps, at a stated family-wise confidence.

Statistics (complex circular Gaussian noise on the averaged phasors, independent between sweeps,
periods and points; noiseless input phasor):

* per point and output channel the difference ``d = T_new - T_h`` has variance ``a + b`` with
  ``a = var_new / |W_new|^2``, ``b = var_h / |W_h|^2`` (m^2/N^2, each the variance of an averaged
  FRF). With the variances known, ``|d|^2 / (a + b) ~ Exp(1)`` (= F(2, inf)); with each estimated
  from ``nu_a``, ``nu_b`` real degrees of freedom (``2 (N - 1)`` for N periods, fewer after
  removing shaft harmonics), the tail of ``|d|^2 / (a_hat + b_hat)`` is exactly
  ``(1 + 2tw/nu_a)^(-nu_a/2) (1 + 2t(1-w)/nu_b)^(-nu_b/2)`` with ``w = a/(a + b)`` the new sweep's
  share of the variance (:func:`difference_log_sf`). ``w`` is unknown, so the p-value is the
  largest over a 90 % interval for ``w`` (from the F(nu_a, nu_b) law of the variance ratio).
  Welch's F(2, nu) plug-in measured 0.985 coverage at 4 periods for a stated 0.99; this rule
  measures 0.997 / 0.995 / 0.992 / 0.991 at 2 / 4 / 8 / 64 periods (Monte Carlo, 262 points, 3000
  draws each) and tends to the exact test as the periods grow;
* the per-point miss probability is Sidak's ``1 - confidence^(1/n_tests)`` over all points (and
  channels, and the two tests below), so that a healthy repeat has no fault point anywhere with
  probability ``>= confidence``;
* one output: fault iff ``|d| > r = sqrt((a_hat + b_hat) t_miss)`` (``t_miss`` where the tail above
  equals the per-point miss probability): exactly the certified model-free comparison of two sweeps;
* several outputs: per channel as above, plus the test along the direction a damage at the port
  can move the outputs (``e = E21``; whitened projection ``|e^H S^-1 d|^2 / (e^H S^-1 e)``,
  one complex degree of freedom, F(2, min nu)). The directional test collects the evidence of all
  channels that a local change moves together, so it is at least as sensitive to such a change as
  the channel tests.

Several healthy sweeps: ``T_h`` is their mean; its variance ``sum b_i / K^2`` with Welch's
degrees of freedom over the sweeps.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rotorcheck.robust.noise import point_miss
from rotorcheck.robust.validation import STATUS_EXCLUDED, Verdict, longest_run

__all__ = [
    "MEASURED_RULE",
    "FrfEstimate",
    "MeasuredDetection",
    "combine_sweeps",
    "frf_estimate",
    "measured_detect",
    "measured_verdict",
    "welch_dof",
]

STATUS_OK = "ok"
STATUS_FAULT = "fault"
STATUS_UNDECIDED = "undecided"


@dataclass
class FrfEstimate:
    """An averaged FRF and its noise: ``frf`` (f, n_out) m/N, ``var`` (f, n_out) m^2/N^2 (variance of
    the mean FRF), ``dof`` (f, n_out) real degrees of freedom of ``var`` (``inf``: known)."""

    frf: np.ndarray
    var: np.ndarray
    dof: np.ndarray

    def __post_init__(self) -> None:
        self.frf = _col(np.asarray(self.frf, dtype=complex))
        self.var = _col(np.asarray(self.var, dtype=float))
        self.dof = np.broadcast_to(_col(np.asarray(self.dof, dtype=float)), self.frf.shape).copy()
        if self.var.shape != self.frf.shape:
            raise ValueError(f"var has shape {self.var.shape}, frf {self.frf.shape}")
        if np.any(self.var[np.isfinite(self.var)] < 0):
            raise ValueError("variances must be >= 0")


def _col(x: np.ndarray) -> np.ndarray:
    return x[:, None] if x.ndim == 1 else x


def frf_estimate(W: np.ndarray, Z: np.ndarray, output_var: np.ndarray, dof: np.ndarray) -> FrfEstimate:
    """FRF ``Z / W`` of one SISO or SIMO sweep with its variance ``output_var / |W|^2``.

    ``W`` (f,) N input phasor (taken as noiseless), ``Z`` (f, n_out) or (f,) m output phasors,
    ``output_var`` m^2 variance of the mean output phasor, ``dof`` its real degrees of freedom.
    """
    W = np.asarray(W, dtype=complex).reshape(-1)
    Zc = _col(np.asarray(Z, dtype=complex))
    v = _col(np.asarray(output_var, dtype=float))
    d = _col(np.asarray(dof, dtype=float))
    return FrfEstimate(Zc / W[:, None], v / np.abs(W[:, None]) ** 2, np.broadcast_to(d, Zc.shape))


def welch_dof(variances: Sequence[np.ndarray], dofs: Sequence[np.ndarray]) -> np.ndarray:
    """Welch-Satterthwaite degrees of freedom of a sum of independent variance estimates."""
    tot = sum(np.asarray(v, dtype=float) for v in variances)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = sum(np.asarray(v, dtype=float) ** 2 / np.asarray(n, dtype=float)
                  for v, n in zip(variances, dofs, strict=True))
        nu = np.asarray(tot, dtype=float) ** 2 / np.asarray(den, dtype=float)
    # all variances zero: nothing is estimated, the sum is known exactly
    return np.where(np.asarray(tot) > 0, nu, np.inf)


def combine_sweeps(estimates: Sequence[FrfEstimate]) -> FrfEstimate:
    """Mean of several sweeps' FRFs on one grid; variance ``sum var_i / K^2``, Welch's dof."""
    if not estimates:
        raise ValueError("need at least one sweep")
    if len(estimates) == 1:
        return estimates[0]
    k = len(estimates)
    frf = np.sum([e.frf for e in estimates], axis=0) / k
    parts = [e.var / k**2 for e in estimates]
    return FrfEstimate(frf, np.sum(parts, axis=0), welch_dof(parts, [e.dof for e in estimates]))


@dataclass
class MeasuredDetection:
    """Per-point result of :func:`measured_detect` (arrays over the f points).

    ``distance`` (f, n_out) ``|T_new - T_h|`` m/N; ``radius`` (f, n_out) the allowance at the per-point
    level (m/N); ``statistic`` (f,) the largest ratio test statistic / threshold over the tests
    (> 1: fault); ``p_value`` (f,) the point's smallest per-test p-value times its number of tests;
    ``fault`` (f,) bool; ``status`` 'ok' | 'fault' | 'undecided' (no finite variance or data);
    ``dof`` (f, n_out) Welch degrees of freedom; ``point_miss`` per-test miss probability;
    ``confidence`` family-wise; ``n_tests`` tests in the family.
    """

    distance: np.ndarray
    radius: np.ndarray
    statistic: np.ndarray
    p_value: np.ndarray
    fault: np.ndarray
    status: np.ndarray
    dof: np.ndarray
    point_miss: float
    confidence: float
    n_tests: int
    direction_statistic: np.ndarray | None = None

    @property
    def n_fault(self) -> int:
        """Number of fault points."""
        return int(np.count_nonzero(self.fault))

    @property
    def family_p_value(self) -> float:
        """Smallest Sidak-adjusted p-value over the points: the sweep's p-value for 'any change'."""
        p = self.p_value[np.isfinite(self.p_value)]
        if p.size == 0:
            return float("nan")
        pmin = min(float(p.min()), 1.0)
        return 1.0 if pmin >= 1.0 else float(-np.expm1(self.n_tests * np.log1p(-pmin)))


#: coverage of the interval for the new sweep's share of the difference's variance (see the module doc)
SHARE_INTERVAL = 0.90


def _log_chi2_mgf(x: np.ndarray, nu: np.ndarray, infinite: np.ndarray, half: np.ndarray) -> np.ndarray:
    """``ln E[exp(-x chi2_nu / nu)] = -(nu/2) ln(1 + 2x/nu)`` (``nu = inf``: ``-x``); ``infinite = isinf(nu)`` and
    ``half = -0.5 nu`` given (computed once per bisection). Call inside ``np.errstate(divide, invalid ignored)``."""
    return np.where(infinite, -x, half * np.log1p(2.0 * x / nu))


def share_interval(a_hat: np.ndarray, b_hat: np.ndarray, nu_a: np.ndarray, nu_b: np.ndarray,
                   coverage: float = SHARE_INTERVAL) -> tuple[np.ndarray, np.ndarray]:
    """Interval for ``w = a / (a + b)`` from the estimates (``(a_hat/a)/(b_hat/b) ~ F(nu_a, nu_b)``)."""
    from scipy.special import fdtri  # lazy: scipy.special (not scipy.stats: ~0.3 s) only for the inverse F cdf

    big = 1e12
    na = np.where(np.isinf(nu_a), big, nu_a)
    nb = np.where(np.isinf(nu_b), big, nu_b)
    tail = 0.5 * (1.0 - coverage)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = a_hat / b_hat
        lo = rho / fdtri(na, nb, 1.0 - tail)
        hi = rho / fdtri(na, nb, tail)
        w_lo = np.where(b_hat > 0, lo / (1.0 + lo), 1.0)
        w_hi = np.where(b_hat > 0, np.where(np.isinf(hi), 1.0, hi / (1.0 + hi)), 1.0)
    return w_lo, w_hi


def difference_log_sf(t: np.ndarray, w_lo: np.ndarray, w_hi: np.ndarray, nu_a: np.ndarray,
                      nu_b: np.ndarray) -> np.ndarray:
    """``ln P(|d|^2 / (a_hat + b_hat) > t)``, the largest over the share ``w`` in ``[w_lo, w_hi]``.

    With ``|d|^2/(a + b) ~ Exp(1)`` independent of ``a_hat = a chi2_a/nu_a``, ``b_hat = b chi2_b/nu_b``:
    ``P = E[exp(-t (w chi2_a/nu_a + (1-w) chi2_b/nu_b))] = (1 + 2tw/nu_a)^(-nu_a/2) (1 + 2t(1-w)/nu_b)^(-nu_b/2)``
    exactly; its logarithm is convex in ``w``, so the largest over an interval sits at an end.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        return _difference_log_sf_of(w_lo, w_hi, nu_a, nu_b)(t)


def _difference_log_sf_of(w_lo: np.ndarray, w_hi: np.ndarray, nu_a: np.ndarray, nu_b: np.ndarray
                          ) -> Callable[[np.ndarray], np.ndarray]:
    """:func:`difference_log_sf` as a function of ``t``, what does not depend on ``t`` computed once (the
    quantile's bisection calls it 56 times). Call it inside ``np.errstate(divide, invalid ignored)``."""
    inf_a, inf_b = np.isinf(nu_a), np.isinf(nu_b)
    half_a, half_b = -0.5 * nu_a, -0.5 * nu_b
    ends = ((w_lo, 1.0 - w_lo), (w_hi, 1.0 - w_hi))

    def log_sf(t: np.ndarray) -> np.ndarray:
        lo, hi = (_log_chi2_mgf(t * w, nu_a, inf_a, half_a) + _log_chi2_mgf(t * v, nu_b, inf_b, half_b)
                  for w, v in ends)
        return np.maximum(lo, hi)

    return log_sf


def difference_quantile(miss: float, w_lo: np.ndarray, w_hi: np.ndarray, nu_a: np.ndarray,
                        nu_b: np.ndarray) -> np.ndarray:
    """``t`` with ``difference_log_sf(t) = ln(miss)`` (bisection in log t between the Exp(1) and
    the F(2, min nu) quantiles, which bracket it)."""
    target = np.log(miss)
    shape = np.broadcast(w_lo, nu_a, nu_b).shape
    lo = np.full(shape, -np.log(miss))
    hi = np.maximum(_f_isf(miss, np.minimum(nu_a, nu_b)), lo) * 1.0000001
    with np.errstate(divide="ignore", invalid="ignore"):
        log_sf = _difference_log_sf_of(w_lo, w_hi, nu_a, nu_b)
        for _ in range(56):  # the bracket spans < 2^30 in ratio: 56 halvings of ln t reach rounding
            mid = np.sqrt(lo * hi)
            above = log_sf(mid) > target
            lo = np.where(above, mid, lo)
            hi = np.where(above, hi, mid)
    return np.sqrt(lo * hi)


def _f_sf(x: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Survival function of F(2, nu) (``nu = inf``: Exp(1)); closed form ``(1 + 2x/nu)^(-nu/2)``."""
    x = np.asarray(x, dtype=float)
    nu = np.asarray(nu, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        finite = np.exp(-0.5 * nu * np.log1p(2.0 * x / nu))
    return np.where(np.isinf(nu), np.exp(-x), finite)


def _f_isf(miss: float, nu: np.ndarray) -> np.ndarray:
    """Quantile ``q`` of F(2, nu) with ``P(X > q) = miss``: ``(nu/2)(miss^(-2/nu) - 1)``."""
    nu = np.asarray(nu, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        finite = 0.5 * nu * np.expm1(-2.0 / nu * np.log(miss))
    return np.where(np.isinf(nu), -np.log(miss), finite)


def measured_detect(new: FrfEstimate, healthy: FrfEstimate, confidence: float = 0.99,
                    e21: np.ndarray | None = None, exclude: np.ndarray | None = None) -> MeasuredDetection:
    """Certified fault points of ``new`` against the measured healthy ``healthy`` (module docstring).

    ``e21`` (f, n_out) complex: the model's damage-port to output receptances (used with several
    outputs for the directional test; ignored with one output, where the test is the same).
    ``exclude`` (f,) bool: points not tested (status 'excluded', no fault, no p-value, not in the Sidak
    family), e.g. points on a shaft harmonic.
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError("confidence must be in (0, 1)")
    if new.frf.shape != healthy.frf.shape:
        raise ValueError(f"new sweep has shape {new.frf.shape}, healthy {healthy.frf.shape}")
    _nf, n_out = new.frf.shape
    d = new.frf - healthy.frf
    s = new.var + healthy.var
    nu = welch_dof([new.var, healthy.var], [new.dof, healthy.dof])
    good = (np.all(np.isfinite(d), axis=1) & np.all(np.isfinite(s), axis=1)
            & np.all(np.isfinite(healthy.frf), axis=1))
    out = np.zeros(good.shape, dtype=bool) if exclude is None else np.asarray(exclude, dtype=bool).reshape(-1)
    good = good & ~out
    use_dir = e21 is not None and n_out > 1
    n_tests = int(np.count_nonzero(good)) * (n_out + (1 if use_dir else 0))
    miss = point_miss(confidence, max(n_tests, 1), "sidak")
    w_lo, w_hi = share_interval(new.var, healthy.var, new.dof, healthy.dof)
    q = difference_quantile(miss, w_lo, w_hi, new.dof, healthy.dof)
    dist = np.abs(d)
    with np.errstate(invalid="ignore", divide="ignore"):
        radius = np.sqrt(s * q)
        # noiseless (s = 0): any difference beyond rounding is certain
        exact = s <= 0
        tiny = 1e-12 * np.maximum(np.abs(new.frf), np.abs(healthy.frf))
        stat_c = np.where(exact, np.where(dist > tiny, np.inf, 0.0), dist**2 / np.where(exact, 1.0, s))
        ratio_c = np.where(exact, np.where(dist > tiny, np.inf, 0.0), stat_c / q)
        p_c = np.where(exact, np.where(dist > tiny, 0.0, 1.0),
                       np.exp(difference_log_sf(stat_c, w_lo, w_hi, new.dof, healthy.dof)))
    ratio = np.max(ratio_c, axis=1)
    p_point = np.min(p_c, axis=1)
    dir_stat = None
    if use_dir:
        assert e21 is not None
        e = _col(np.asarray(e21, dtype=complex))
        with np.errstate(invalid="ignore", divide="ignore"):
            w = 1.0 / s
            num = np.abs(np.sum(np.conj(e) * w * d, axis=1)) ** 2
            den = np.sum(np.abs(e) ** 2 * w, axis=1)
            t = num / den
            nu_min = np.min(nu, axis=1)
            q_dir = _f_isf(miss, nu_min)
            dir_stat = t / q_dir
        ratio = np.fmax(ratio, np.where(np.isfinite(dir_stat), dir_stat, 0.0))
        p_point = np.minimum(p_point, _f_sf(t, nu_min))
    fault = good & (ratio > 1.0)
    status = np.where(out, STATUS_EXCLUDED, np.where(~good, STATUS_UNDECIDED, np.where(fault, STATUS_FAULT,
                                                                                     STATUS_OK))).astype("<U13")
    p_point = np.where(good, np.minimum(p_point, 1.0), np.nan)
    ratio = np.where(good, ratio, np.nan)
    return MeasuredDetection(dist, radius, ratio, p_point, fault, status, nu, miss, confidence,
                             n_tests, dir_stat)


@dataclass
class AnchoredDamageBound:
    """Bound of the anchored damage dynamics per frequency (f,), N/m.

    ``estimate`` ``D = [E12 E21 / (T - T_h) + E11]^-1`` (eq. 3.11 with E22 := T_h); the set is
    every D for ``T - T_h`` within ``noise_radius`` of the measured difference and the model's
    damage-port channels ``E11``, ``E12 E21`` within a relative error ``channel_error``:
    ``kind`` 'disk' (``|D - centre| <= radius``) or 'unbounded' (contains a neighbourhood of 0 or of
    infinity: ``max_abs = inf`` or ``min_abs = 0``); ``min_abs``/``max_abs``/``phase_min``/``phase_max``
    (rad) of that set (outer bounds: the two channel errors and the noise are combined as discs).
    """

    estimate: np.ndarray
    kind: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    min_abs: np.ndarray
    max_abs: np.ndarray
    phase_min: np.ndarray
    phase_max: np.ndarray
    channel_error: np.ndarray

    def contains(self, z: np.ndarray) -> np.ndarray:
        """Whether ``z`` (f,) lies inside the bound (disk points: the disk; others: the |D| range)."""
        z = np.asarray(z, dtype=complex)
        in_disk = np.abs(z - self.centre) <= self.radius * (1 + 1e-12)
        in_range = (np.abs(z) >= self.min_abs * (1 - 1e-12)) & (np.abs(z) <= self.max_abs * (1 + 1e-12))
        return np.where(self.kind == "disk", in_disk, in_range)


def anchored_damage_bound(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, T_healthy: np.ndarray,
                          T_new: np.ndarray, noise_radius: np.ndarray, channel_error: np.ndarray | float = 0.0
                          ) -> AnchoredDamageBound:
    """Anchored D_u with its bound (SISO, arrays (f,); m/N in, N/m out). See :class:`AnchoredDamageBound`.

    Construction (all discs): ``1/q`` over the disc ``|q - q0| <= r`` (``q = T_new - T_h``) is the
    disc of centre ``conj(q0)/(|q0|^2 - r^2)`` and radius ``r/(|q0|^2 - r^2)`` when ``|q0| > r``;
    times ``c = E12 E21 (1 + eps)`` and plus ``E11 (1 + eps')`` with ``|eps|, |eps'| <= rho``, the
    denominator lies in a disc (radii add); its inverse is a disc when it excludes 0. With
    ``channel_error = 0`` and the noise only this is the exact eq. 3.12 set of the anchored member.
    """
    E11, E12, E21, Th, Tn = (np.asarray(x, dtype=complex).reshape(-1) for x in (E11, E12, E21, T_healthy, T_new))
    r = np.asarray(noise_radius, dtype=float).reshape(-1)
    rho = np.broadcast_to(np.asarray(channel_error, dtype=float), r.shape)
    c = E12 * E21
    q0 = Tn - Th
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        est = 1.0 / (c / q0 + E11)
        den_q = np.abs(q0) ** 2 - r**2
        q_ok = den_q > 0
        cu = c * np.conj(q0) / den_q
        ru = np.abs(c) * r / den_q
        d0 = cu + E11
        R = ru + rho * (np.abs(cu) + ru) + rho * np.abs(E11)
        den = np.abs(d0) ** 2 - R**2
        disk = q_ok & (den > 0)
        centre = np.where(disk, np.conj(d0) / den, np.nan + 0j)
        radius = np.where(disk, R / den, np.inf)
        min_abs = np.where(disk, 1.0 / (np.abs(d0) + R), 0.0)
        max_abs = np.where(disk, 1.0 / (np.abs(d0) - R), np.inf)
        # q-disc holding 0 (the new data within the noise of the healthy): D = q / (c + E11 q) holds 0
        qmax = np.abs(q0) + r
        denom_max = np.abs(c) * (1 - rho) - np.abs(E11) * (1 + rho) * qmax
        max_abs = np.where(q_ok, max_abs, np.where(denom_max > 0, qmax / denom_max, np.inf))
        half = np.where(disk, np.arcsin(np.clip(radius / np.abs(centre), 0.0, 1.0)), np.pi)
        ang = np.where(disk, np.angle(centre), 0.0)
    bad = ~np.isfinite(q0) | ~np.isfinite(r)
    kind = np.where(bad, "undecided", np.where(disk, "disk", "unbounded")).astype("<U9")
    return AnchoredDamageBound(est, kind, centre, radius, min_abs, max_abs, ang - half, ang + half,
                               np.asarray(rho, dtype=float))


def io_model_error(model_frf: np.ndarray, healthy_frf: np.ndarray, halfwidth: int = 2) -> np.ndarray:
    """Relative error of the model's io channel on the healthy data, ``|T_h - G| / |G|`` (f,), as a
    running maximum over ``+-halfwidth`` points: the assumed relative error of the damage-port
    channels (the model is taken to err no more on those than on the one it can be checked on)."""
    G = np.asarray(model_frf, dtype=complex).reshape(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.abs(np.asarray(healthy_frf, dtype=complex).reshape(-1) - G) / np.abs(G)
    e = np.where(np.isfinite(e), e, np.inf)
    padded = np.pad(e, halfwidth, constant_values=-np.inf)
    return np.lib.stride_tricks.sliding_window_view(padded, 2 * halfwidth + 1).max(axis=1)


MEASURED_RULE = (
    "damage if at least one point is a certified fault point: the new FRF differs from the measured healthy "
    "FRF by more than the noise of both sweeps allows (per point: the exact tail of |d|^2 / (var_new + var_healthy) "
    "with both variances estimated, taken at the least favourable variance share in a 90 % interval; Sidak over "
    "all points and channels at the stated family-wise confidence: a healthy repeat is called damage with "
    "probability at most 1 - confidence); otherwise inconclusive if some point could not be tested; "
    "otherwise healthy"
)


def measured_verdict(fault: np.ndarray, status: np.ndarray, confidence: float, n_tests: int) -> Verdict:
    """Sweep verdict of measured detection (:data:`MEASURED_RULE`)."""
    fault = np.asarray(fault, dtype=bool)
    n = fault.size
    n_fault = int(np.count_nonzero(fault))
    undecided = int(np.count_nonzero(~np.isin(np.asarray(status), [STATUS_OK, STATUS_FAULT, STATUS_EXCLUDED])))
    if n_fault:
        why = (f"{n_fault} certified fault points at {confidence:.0%} family-wise confidence "
               f"(Sidak over {n_tests} tests)")
        return Verdict("damage", why, n, n_fault, undecided, longest_run(fault), 1)
    if undecided:
        return Verdict("inconclusive", f"no fault point, {undecided} points could not be tested", n, 0,
                       undecided, 0, 1)
    return Verdict("healthy", f"no point differs beyond the noise of both sweeps at {confidence:.0%} "
                   f"family-wise confidence ({n_tests} tests)", n, 0, 0, 0, 1)
