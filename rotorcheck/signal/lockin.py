r"""Lock-in phasor extraction, per excitation period, and its closed form for multi-tone signals.

Convention (``method.md``): ``x(t) = Re{X exp(j 2 pi f t)}``, ``X`` the peak complex amplitude.
The lock-in phasor of period ``k`` of ``T = 1/f`` starting at ``t_k`` is

    X_k = (2/T) \int_{t_k}^{t_k+T} x(t) exp(-j 2 pi f t) dt                      (continuous)
    X_k = (2/M) \sum_{i=0}^{M-1} x(t_k + i T/M) exp(-j 2 pi f (t_k + i T/M))    (M samples)

The time reference is absolute (``t`` as given), so ``x = Re{X e^{jwt}}`` returns ``X`` in every
period. With an integer number ``M >= 3`` of samples per period the sum is exact quadrature for the
tone at ``f`` (and rejects DC and harmonics ``2..M-2`` of ``f`` exactly).

Averaging over ``N`` periods: ``mean = (1/N) sum X_k``; variance of the mean
``var = sum |X_k - mean|^2 / (N (N - 1))``, an unbiased estimate of ``E|mean - truth|^2``.

Noise. White Gaussian noise of standard deviation ``sigma`` per sample, ``M = fs T`` samples per
period, gives a per-period phasor ``n = (2/M) sum w_i exp(-j theta_i)`` with
``Var(Re n) = (4 sigma^2/M^2) sum cos^2 theta_i = 2 sigma^2/M``, ``Var(Im n) = 2 sigma^2/M``,
``Cov = (4 sigma^2/M^2) sum cos theta_i sin theta_i = 0`` (for ``M >= 3``), so ``n`` is circular
complex Gaussian with ``E|n|^2 = 4 sigma^2 / M = 4 sigma^2 / (fs T)``, independent between disjoint
periods. See :func:`white_noise_phasor_var`.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "SHAFT_ORDERS",
    "average_periods",
    "lockin_periods",
    "remove_shaft_harmonics",
    "samples_per_period",
    "shaft_harmonic_fit",
    "tone_lockin",
    "white_noise_phasor_var",
]

#: Shaft-speed orders fitted out of the per-period phasors of a rotating run (1X .. 4X).
SHAFT_ORDERS = 4


def samples_per_period(fs_hz: float, f_exc_hz: float, rtol: float = 1e-9) -> int:
    """Integer ``M = fs/f``; raise ``ValueError`` if ``fs/f`` is not an integer >= 3."""
    m_real = fs_hz / f_exc_hz
    m = round(m_real)
    if m < 3 or abs(m_real - m) > rtol * m_real:
        raise ValueError(
            f"fs/f = {m_real!r} must be an integer >= 3 for exact lock-in quadrature "
            f"(fs = {fs_hz!r} Hz, f = {f_exc_hz!r} Hz)"
        )
    return m


def lockin_periods(
    x: np.ndarray,
    fs_hz: float,
    f_exc_hz: float,
    t0: float = 0.0,
    n_periods: int | None = None,
    skip_periods: int = 0,
) -> np.ndarray:
    """Per-period lock-in phasors of sampled signals.

    ``x``: samples (n_samples, ...) at ``t_i = t0 + i/fs`` (s); ``fs/f`` must be an integer
    ``M >= 3``. The first ``skip_periods`` periods are dropped, then ``n_periods`` (default: all
    complete remaining periods) are analysed. Returns (n_periods, ...) complex phasors in the
    units of ``x``, time reference absolute ``t``.
    """
    x = np.asarray(x)
    m = samples_per_period(fs_hz, f_exc_hz)
    total = x.shape[0] // m
    avail = total - skip_periods
    if n_periods is None:
        n_periods = avail
    if n_periods < 1 or n_periods > avail:
        raise ValueError(f"need {skip_periods} + {n_periods} periods, signal has {total}")
    start = skip_periods * m
    seg = x[start : start + n_periods * m]
    seg = seg.reshape(n_periods, m, *x.shape[1:])
    i = np.arange(m)
    # period k starts at t0 + (skip + k) T, and exp(-j w (t0 + n T)) = exp(-j w t0) for integer n,
    # so the reference is one phase factor times the per-sample phases 2 pi i / M (exact)
    theta = 2.0 * np.pi * i / m
    flat = seg.reshape(n_periods, m, -1)
    if np.iscomplexobj(flat):
        ph = np.exp(-1j * theta) @ flat
    else:
        ph = np.cos(theta) @ flat - 1j * (np.sin(theta) @ flat)  # (P, R), real matmuls
    ph = ph.reshape(n_periods, *x.shape[1:]) * np.exp(-1j * 2.0 * np.pi * f_exc_hz * t0)
    return (2.0 / m) * ph


def average_periods(per_period: np.ndarray, axis: int = 0) -> tuple[np.ndarray, np.ndarray, int]:
    """Mean phasor, variance of the mean ``sum|X_k - mean|^2 / (N (N-1))`` and ``N``.

    The variance is NaN when ``N < 2`` (no scatter to estimate it from).
    """
    x = np.asarray(per_period)
    n = x.shape[axis]
    mean = x.mean(axis=axis)
    if n < 2:
        return mean, np.full(mean.shape, np.nan), n
    dev = x - np.expand_dims(mean, axis)
    var = (np.abs(dev) ** 2).sum(axis=axis) / (n * (n - 1))
    return mean, var, n


def _dirichlet(x: np.ndarray, m: int) -> np.ndarray:
    """``sin(m x) / (m sin x)`` with its limit ``(-1)^(n (m-1))`` at ``x = n pi``."""
    s = np.sin(x)
    near = np.abs(s) < 1e-12
    safe = np.where(near, 1.0, s)
    val = np.sin(m * x) / (m * safe)
    n = np.rint(x / np.pi)
    lim = np.where(np.mod(n * (m - 1), 2) == 0, 1.0, -1.0)
    return np.where(near, lim, val)


def _kernel(a: np.ndarray, t_k: np.ndarray, period: float, m: int | None) -> np.ndarray:
    """Average of ``exp(j a t)`` over each period [t_k, t_k + T]: continuous or M-sample.

    ``a`` (rad/s) shape (n_tone,), ``t_k`` (n_periods,); returns (n_periods, n_tone).
    """
    a = a[None, :]
    tk = t_k[:, None]
    if m is None:
        return np.exp(1j * a * (tk + period / 2.0)) * np.sinc(a * period / (2.0 * np.pi))
    dt = period / m
    return np.exp(1j * a * (tk + (m - 1) * dt / 2.0)) * _dirichlet(a * dt / 2.0, m)


def tone_lockin(
    tone_freqs_hz: np.ndarray,
    tone_amps: np.ndarray,
    f_exc_hz: float,
    t_start: float,
    n_periods: int,
    samples_per_period: int | None = None,
) -> np.ndarray:
    r"""Exact per-period lock-in phasors of ``x(t) = Re sum_m Y_m exp(j 2 pi F_m t)``.

    ``tone_freqs_hz`` (n_tone,) Hz (any real values, also negative or zero); ``tone_amps``
    (n_tone, ...) peak complex amplitudes; the lock-in runs at ``f_exc_hz`` over ``n_periods``
    consecutive periods starting at ``t_start`` (s), with absolute time reference.

    With ``w = 2 pi f``, ``nu_m = 2 pi F_m`` and ``g(a)`` the average of ``exp(j a t)`` over
    period k (``exp(j a (t_k + T/2)) sinc(a T / 2 pi)`` continuous, or
    ``exp(j a (t_k + (M-1) dt/2)) sin(M a dt/2) / (M sin(a dt/2))`` for ``M`` samples,
    ``dt = T/M``):

        X_k = sum_m [ Y_m g(nu_m - w) + conj(Y_m) g(-nu_m - w) ].

    ``samples_per_period=None`` gives the continuous-time integral; an integer ``M`` gives the
    exact value of the ``M``-sample lock-in (what :func:`lockin_periods` computes on samples).
    Returns (n_periods, ...) complex.
    """
    nu = 2.0 * np.pi * np.atleast_1d(np.asarray(tone_freqs_hz, dtype=np.float64))
    amps = np.asarray(tone_amps, dtype=np.complex128)
    if amps.ndim == 0:
        amps = amps.reshape(1)
    if amps.shape[0] != nu.shape[0]:
        raise ValueError(f"tone_amps has {amps.shape[0]} rows for {nu.shape[0]} tone frequencies")
    if samples_per_period is not None and samples_per_period < 3:
        raise ValueError("samples_per_period must be >= 3")
    w = 2.0 * np.pi * f_exc_hz
    period = 1.0 / f_exc_hz
    t_k = t_start + np.arange(n_periods) * period
    g_pos = _kernel(nu - w, t_k, period, samples_per_period)  # (P, n_tone)
    g_neg = _kernel(-nu - w, t_k, period, samples_per_period)
    flat = amps.reshape(amps.shape[0], -1)
    out = g_pos @ flat + g_neg @ np.conj(flat)
    return out.reshape(n_periods, *amps.shape[1:])


def white_noise_phasor_var(sample_std: float | np.ndarray, samples_per_period: float) -> np.ndarray:
    """``E|n|^2 = 4 sigma^2 / M`` of the per-period lock-in phasor of white noise (std ``sigma``
    per sample, ``M = fs T`` samples per period); real and imaginary parts each ``2 sigma^2/M``.
    """
    s = np.asarray(sample_std, dtype=np.float64)
    return 4.0 * s**2 / float(samples_per_period)


def shaft_harmonic_fit(
    per_period: np.ndarray,
    f_exc_hz: float,
    shaft_hz: float,
    orders: int = 4,
    rtol: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray, int]:
    r"""Mean phasor with the shaft-speed harmonics removed, the variance of that mean and its dof.

    A tone at ``F = k * shaft_hz`` (unbalance 1X, misalignment 2X, a cracked rotor's harmonics, or
    the sidebands ``f + k * shaft_hz`` of a periodic plant) is not synchronous with the excitation
    ``f``; over consecutive periods of ``T = 1/f`` its lock-in phasor is a geometric sequence
    (see :func:`tone_lockin`: ``g(a)`` carries ``exp(j a t_k)``, ``t_k = t_0 + k T``):

        X_p = X + sum_k ( b_k z_k^p + c_k conj(z_k)^p ) + noise_p,   z_k = exp(j 2 pi k shaft_hz / f),

    whatever the shaft angle at the start. Least squares over the ``N`` periods with these known
    ratios estimates ``X`` free of the leak (which a plain mean keeps, and which a random start
    angle turns into a false difference between two sweeps). Regressors that are numerically
    dependent on the ones before them (``z = 1``: ``k shaft_hz / f`` an integer, where the tone is
    either rejected exactly by the lock-in or indistinguishable from ``X``; ``z`` real; two orders
    aliasing to one ratio) are dropped.

    ``per_period``: ``(N, ...)`` complex per-period phasors of one point. Returns ``(mean (...),
    var_of_mean (...), dof)``: ``var = s^2 [(A^H A)^{-1}]_{00}`` with the residual variance
    ``s^2 = |r|^2 / (N - q)`` for ``q`` kept regressors (``E|mean - X|^2`` for circular complex
    Gaussian noise, independent periods), and ``dof = 2 (N - q)`` real degrees of freedom of that
    variance estimate (``|mean - X|^2 / var ~ F(2, dof)``). With ``orders = 0``, ``shaft_hz = 0``
    or too few periods (``N < q + 3`` after dropping) the plain mean is returned with ``dof =
    2 (N - 1)`` (:func:`average_periods`).
    """
    x = np.asarray(per_period, dtype=np.complex128)
    return _harmonic_fit(x, _harmonic_design(x.shape[0], f_exc_hz, shaft_hz, orders, rtol))


def _harmonic_columns(n: int, f_exc_hz: float, shaft_hz: float, orders: int) -> list[np.ndarray]:
    """The candidate regressors of :func:`shaft_harmonic_fit`: ones, then ``z_k^p``, ``conj(z_k)^p``."""
    p = np.arange(n)
    cols = [np.ones(n, dtype=np.complex128)]
    for k in range(1, orders + 1):
        z = np.exp(2j * np.pi * k * shaft_hz / f_exc_hz)
        cols += [z**p, np.conj(z) ** p]
    return cols


def _design_of(kept: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """``(A, g00)`` of the kept regressors."""
    q = len(kept)
    A = np.stack(kept, axis=1)  # (N, q)
    # [(A^H A)^-1]_00 = |row 0 of R^-1|^2 (A = QR): never negative, unlike inverting a near-singular Gram
    # matrix (a speed so low that its harmonics nearly alias gave negative variances that way)
    _, R = np.linalg.qr(A)
    g00 = float(np.sum(np.abs(np.linalg.solve(R, np.eye(q))[0]) ** 2))
    return A, g00


#: relative distance from the keep threshold below which :func:`_harmonic_designs` leaves a point's choice of
#: regressors to the point-by-point Gram-Schmidt (the batched one differs from it by round-off only, ~1e-9 of
#: the threshold at worst: far inside this band)
_GUARD = 1e-6


def _harmonic_designs(n_periods: np.ndarray, frequency_hz: np.ndarray, shaft_hz: float, orders: int = SHAFT_ORDERS,
                      rtol: float = 1e-6) -> list[tuple[np.ndarray, float] | None]:
    """:func:`_harmonic_design` of every point (``n_periods`` (f,), ``frequency_hz`` (f,)). The greedy
    Gram-Schmidt that chooses the regressors runs on all points of equal period count at once; a point whose
    norm ratio falls within :data:`_GUARD` of the threshold is chosen point by point, so the choice, and the
    regressors (the same columns), are those of :func:`_harmonic_design`."""
    nf = frequency_hz.size
    out: list[tuple[np.ndarray, float] | None] = [None] * nf
    if orders <= 0 or shaft_hz <= 0.0:
        return out
    ns = np.asarray(n_periods, dtype=int)
    for n in np.unique(ns):
        idx = np.flatnonzero(ns == n)
        if n < 5:
            continue
        cols = [_harmonic_columns(int(n), float(frequency_hz[j]), shaft_hz, orders) for j in idx]
        C = np.array(cols)  # (P, m, n)
        P, m = C.shape[0], C.shape[1]
        basis = np.zeros((P, m, n), dtype=np.complex128)  # orthonormal vectors kept so far, per point
        n_kept = np.zeros(P, dtype=int)
        keep = np.zeros((P, m), dtype=bool)
        done = np.zeros(P, dtype=bool)
        close = np.zeros(P, dtype=bool)
        for i in range(m):
            r = C[:, i].copy()
            for j in range(i):
                qj = basis[:, j]  # zero where fewer than j + 1 were kept
                r -= np.sum(qj.conj() * r, axis=1)[:, None] * qj
            nr = np.linalg.norm(r, axis=1)
            thr = rtol * np.linalg.norm(C[:, i], axis=1)
            close |= ~done & (np.abs(nr - thr) <= _GUARD * thr)
            add = ~done & (nr > thr)
            keep[:, i] = add
            slot = n_kept[add]
            basis[np.flatnonzero(add), slot] = r[add] / nr[add, None]
            n_kept += add
            done |= n_kept >= n - 3
        for t, point in enumerate(idx.tolist()):
            if close[t]:
                out[point] = _harmonic_design(int(n), float(frequency_hz[point]), shaft_hz, orders, rtol)
                continue
            q = int(n_kept[t])
            if q == 1 or n < q + 3:
                continue
            out[point] = _design_of([cols[t][i] for i in range(m) if keep[t, i]])
    return out


def _harmonic_design(n: int, f_exc_hz: float, shaft_hz: float, orders: int = SHAFT_ORDERS, rtol: float = 1e-6
                     ) -> tuple[np.ndarray, float] | None:
    """The regressors ``A`` (N, q) that :func:`shaft_harmonic_fit` keeps for ``n`` periods and ``g00 =
    [(A^H A)^{-1}]_00``; None where it returns the plain mean. They depend on the point, not on the
    channel: computed once for every channel of a point (:func:`fit_shaft_harmonics`)."""
    if orders <= 0 or shaft_hz <= 0.0 or n < 5:
        return None
    cols = _harmonic_columns(n, f_exc_hz, shaft_hz, orders)
    # greedy Gram-Schmidt: keep a column only if it adds a direction (relative to its own norm)
    kept: list[np.ndarray] = []
    basis: list[tuple[np.ndarray, np.ndarray]] = []  # (q, conj(q)): the conjugate taken once per vector
    for c in cols:
        r = c.copy()
        for q_, qc in basis:
            r -= (qc @ r) * q_
        nr = float(np.linalg.norm(r))
        if nr > rtol * np.linalg.norm(c):
            kept.append(c)
            q_ = r / nr
            basis.append((q_, q_.conj()))
        if len(kept) >= n - 3:
            break
    q = len(kept)
    if q == 1 or n < q + 3:
        return None
    return _design_of(kept)


def _harmonic_fit(x: np.ndarray, design: tuple[np.ndarray, float] | None) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`shaft_harmonic_fit` of the per-period phasors ``x`` (N, ...) with the point's
    :func:`_harmonic_design`."""
    n = x.shape[0]
    if design is None:
        mean, var, _ = average_periods(x)
        return mean, var, 2 * (n - 1)
    A, g00 = design
    q = A.shape[1]
    flat = x.reshape(n, -1)
    coef, *_ = np.linalg.lstsq(A, flat, rcond=None)
    resid = flat - A @ coef
    s2 = np.sum(np.abs(resid) ** 2, axis=0) / (n - q)
    mean = coef[0].reshape(x.shape[1:])
    var = (s2 * g00).reshape(x.shape[1:])
    return mean, var, 2 * (n - q)


def fit_shaft_harmonics(
    period_phasor: np.ndarray, n_periods: np.ndarray, frequency_hz: np.ndarray, shaft_hz: float,
    cols: list[int], orders: int = SHAFT_ORDERS,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For the channels ``cols`` of a sweep's ``period_phasor`` (f, p, n_chan): the phasor (N or m), the
    variance of that mean and its real dof per point, (f, len(cols)) each, with the shaft-speed harmonics
    1X..``orders``X fitted out (:func:`shaft_harmonic_fit`; a free-running start angle then leaves no
    leak)."""
    nf = frequency_hz.size
    mean = np.empty((nf, len(cols)), complex)
    var = np.empty((nf, len(cols)))
    dof = np.empty((nf, len(cols)))
    n_per = np.array([period_phasor[j, : int(n_periods[j])].shape[0] for j in range(nf)], dtype=int)
    designs = _harmonic_designs(n_per, np.asarray(frequency_hz, dtype=float), shaft_hz, orders)  # one per point
    for j in range(nf):
        per = np.asarray(period_phasor[j, : int(n_periods[j]), :], dtype=np.complex128)
        for k, c in enumerate(cols):
            mean[j, k], var[j, k], dof[j, k] = _harmonic_fit(per[:, c], designs[j])
    return mean, var, dof


def remove_shaft_harmonics(
    period_phasor: np.ndarray, n_periods: np.ndarray, frequency_hz: np.ndarray, shaft_hz: float,
    in_col: int, out_col: int, orders: int = SHAFT_ORDERS,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Input and output phasors (N, m), output variance of the mean (m^2) and its real dof per
    point of a sweep's ``period_phasor`` (f, p, n_chan; columns ``in_col``/``out_col``), with the
    shaft-speed harmonics fitted out (:func:`fit_shaft_harmonics`)."""
    mean, var, dof = fit_shaft_harmonics(period_phasor, n_periods, frequency_hz, shaft_hz, [in_col, out_col], orders)
    return mean[:, 0], mean[:, 1], var[:, 1], dof[:, 1]
