"""Stepped-sine simulator, independent of the FE code.

Two engines share one timeline and one lock-in, so their results can be compared point by point.

Timeline. Point ``j`` (excitation ``f_j``, period ``T_j = 1/f_j``) starts at absolute time
``t0_j = t_start_s + sum_{i<j} ((S_i + N_i) T_i + dwell_s)``; the drive is
``u(t) = Re{F_j exp(j w_j (t - t0_j))}`` (N), ``S_j = max(settle_periods, ceil(settle_s f_j))``
periods are skipped, then
``N_j`` periods are locked in with the local time reference ``tau = t - t0_j`` (so the mean input
phasor is ``F_j``). The sample clock is locked to the excitation: ``M = samples_per_period``
samples per period, ``fs_j = M f_j``.

Fast path (:func:`simulate_fast`): the steady-state output is a sum of tones: the plant's response
per unit input force (``Plant.tones``), scaled by the force, plus fixed synchronous disturbance
tones (1X unbalance, 2X misalignment responses, not scaled by the input). The per-period lock-in of
that sum is exact in closed form (:func:`rotorcheck.sweep.lockin.tone_lockin`); noise is added per
period as circular complex Gaussian phasors with ``E|n|^2 = 4 sigma^2 / M`` (white noise of std
``sigma`` per sample; derivation in :mod:`rotorcheck.sweep.lockin`).

Time-domain path (:func:`simulate_time_domain`): integrates ``M q'' + C q' + (K + dK(t)) q =
b_in u(t) + f_dist(t)`` from rest through the whole sweep (state carried across steps), samples
``y = c_out q`` (plus white noise) and runs the same lock-in on the samples. Without ``dK`` it is
exact: particular sinusoidal solutions plus the homogeneous part propagated by the state
transition matrix ``expm(A dt)``; with ``dK`` it uses DOP853 at tight tolerance.

Time-varying stiffness hook (for the cracked rotor): ``stiffness_perturbation(t) -> dK`` with
``t`` absolute time (s) and ``dK`` an (n_dof, n_dof) array (N/m) added to ``K``. For a breathing
crack, ``dK(t) = -f(Omega t) * dK_open(Omega t)`` (rotating-frame loss rotated into the fixed
frame). The matching fast-path plant is :func:`harmonic_balance_plant` with the Fourier
coefficients of ``dK`` over one shaft revolution.

Conventions: SI units, frequencies in Hz at interfaces, phasors ``x = Re{X exp(j 2 pi f t)}``
(peak). One input (the actuator force); ``n_out`` outputs. Random numbers come only from a seeded
``numpy.random.Generator``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from rotorcheck.sweep.format import Channel, Run
from rotorcheck.sweep.lockin import (
    average_periods,
    lockin_periods,
    tone_lockin,
    white_noise_phasor_var,
)

__all__ = [
    "Plant",
    "StepSettings",
    "SteppedSineResult",
    "TimeRecord",
    "Tone",
    "dynamic_stiffness",
    "harmonic_balance_plant",
    "lti_plant",
    "matrix_plant",
    "point_start_times",
    "receptance",
    "response_tones",
    "settle_counts",
    "simulate_fast",
    "simulate_time_domain",
]

ToneFn = Callable[[float], tuple[np.ndarray, np.ndarray]]
ForceSpec = complex | float | Callable[[float], complex]


@dataclass(frozen=True)
class Tone:
    """A fixed tone ``Re{amplitude exp(j 2 pi freq_hz t)}`` in absolute time ``t``.

    For :func:`simulate_fast` ``amplitude`` is the output response (n_out,) in m; for
    :func:`simulate_time_domain` it is a force vector (n_dof,) in N.
    """

    freq_hz: float
    amplitude: np.ndarray


@dataclass
class Plant:
    """Steady-state response of the rig per unit input force phasor.

    ``tones(f_exc_hz) -> (tone_freqs_hz (m,), amps (m, n_out))``: the output is
    ``Re sum_m amps[m] exp(j 2 pi tone_freqs_hz[m] t)`` when the input is ``Re{exp(j 2 pi f t)}``,
    both in absolute time ``t`` (shaft angle ``Omega t``). A time-invariant plant returns one tone
    at ``f_exc_hz`` with the FRF; a linear time-periodic plant tones at ``f_exc + k * speed``.
    """

    tones: ToneFn
    n_out: int
    name: str = ""


@dataclass
class StepSettings:
    """How each stepped-sine point is measured.

    ``n_periods``: periods averaged (int or one per point, >= 2); ``settle_periods`` and
    ``settle_s``: skipped after each frequency step, at least that many periods and at least that
    many seconds; ``samples_per_period`` ``M`` (>= 3; ``None`` = continuous
    lock-in integral, fast path only); ``force_amplitude``: input force phasor (N), constant or
    ``f -> F``; ``output_noise_std`` (m, scalar or (n_out,)) / ``input_noise_std`` (N): white
    noise std per sample; alternatively ``output_phasor_noise_std`` / ``input_phasor_noise_std``:
    ``sqrt(E|n|^2)`` of the per-period phasor noise (fast path; overrides the per-sample values);
    ``keep_periods``: keep per-period phasors; ``t_start_s``: absolute start time (s);
    ``dwell_s``: idle time between points (s; drive off, disturbances and state continue).
    """

    n_periods: int | Sequence[int] = 64
    settle_periods: int = 16
    settle_s: float = 0.0
    samples_per_period: int | None = 64
    force_amplitude: ForceSpec = 1.0
    output_noise_std: float | Sequence[float] = 0.0
    input_noise_std: float = 0.0
    output_phasor_noise_std: float | Sequence[float] | None = None
    input_phasor_noise_std: float | None = None
    keep_periods: bool = False
    t_start_s: float = 0.0
    dwell_s: float = 0.0


@dataclass
class TimeRecord:
    """Samples of one point (time-domain path): local time ``tau`` (s), input (N), outputs (m)."""

    frequency_hz: float
    t0_s: float
    tau: np.ndarray
    u: np.ndarray
    y: np.ndarray


@dataclass
class SteppedSineResult:
    """Averaged phasors per point (shapes: f points, n_out outputs, one input).

    ``input_phasor`` (f, 1) N; ``output_phasor`` (f, n_out) m; ``output_var`` (f, n_out) m^2 and
    ``input_var`` (f, 1) N^2 (variance of the mean from the period scatter); ``n_periods`` (f,);
    ``period_input`` (f, p, 1), ``period_output`` (f, p, n_out) per-period phasors (NaN padded)
    when kept; ``t0_s`` (f,) absolute start time of each point; ``records`` time samples
    (time-domain path, when requested).
    """

    frequency_hz: np.ndarray
    input_phasor: np.ndarray
    output_phasor: np.ndarray
    output_var: np.ndarray
    input_var: np.ndarray
    n_periods: np.ndarray
    t0_s: np.ndarray
    period_input: np.ndarray | None = None
    period_output: np.ndarray | None = None
    records: list[TimeRecord] | None = field(default=None, repr=False)

    def to_run(
        self,
        run_id: str,
        speed_rpm: float,
        channels: Sequence[Channel] | None = None,
        notes: str = "",
    ) -> Run:
        """A :class:`~rotorcheck.sweep.format.Run`; ``period_phasor`` columns follow ``channels``
        (required when per-period phasors were kept)."""
        pp = None
        if self.period_input is not None and self.period_output is not None:
            if channels is None:
                raise ValueError("channels are needed to order period_phasor columns")
            ins = [j for j, c in enumerate(channels) if c.role == "input"]
            outs = [j for j, c in enumerate(channels) if c.role == "output"]
            if len(ins) != self.period_input.shape[2] or len(outs) != self.period_output.shape[2]:
                raise ValueError(
                    f"channels have {len(ins)} inputs/{len(outs)} outputs, result has "
                    f"{self.period_input.shape[2]}/{self.period_output.shape[2]}"
                )
            nf, p = self.period_input.shape[:2]
            pp = np.full((nf, p, len(channels)), np.nan + 1j * np.nan, dtype=np.complex128)
            pp[:, :, ins] = self.period_input
            pp[:, :, outs] = self.period_output
        return Run.from_phasors(
            run_id,
            speed_rpm,
            self.frequency_hz,
            self.input_phasor,
            self.output_phasor,
            self.output_var,
            self.n_periods,
            period_phasor=pp,
            notes=notes,
        )


# ------------------------------------------------------------------------------------------
# plants
# ------------------------------------------------------------------------------------------


def dynamic_stiffness(m: np.ndarray, c: np.ndarray, k: np.ndarray, f_hz: float) -> np.ndarray:
    """``Z = K - w^2 M + j w C`` at ``f_hz`` (N/m)."""
    w = 2.0 * np.pi * f_hz
    return k - w**2 * m + 1j * w * c


def receptance(
    m: np.ndarray, c: np.ndarray, k: np.ndarray, b_in: np.ndarray, c_out: np.ndarray, f_hz: float
) -> np.ndarray:
    """FRF ``c_out Z(w)^-1 b_in`` (n_out,) in m/N."""
    q = np.linalg.solve(dynamic_stiffness(m, c, k, f_hz), np.asarray(b_in, dtype=np.complex128))
    return np.asarray(c_out) @ q


def lti_plant(frf: Callable[[float], np.ndarray], n_out: int, name: str = "lti") -> Plant:
    """Time-invariant plant from an FRF callable ``f_hz -> (n_out,)`` (m/N)."""

    def tones(f_hz: float) -> tuple[np.ndarray, np.ndarray]:
        h = np.asarray(frf(f_hz), dtype=np.complex128).reshape(1, n_out)
        return np.array([f_hz]), h

    return Plant(tones=tones, n_out=n_out, name=name)


def matrix_plant(m: np.ndarray, c: np.ndarray, k: np.ndarray, b_in: np.ndarray, c_out: np.ndarray) -> Plant:
    """Time-invariant plant ``c_out (K - w^2 M + j w C)^-1 b_in`` from dense matrices."""
    c_out = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    return lti_plant(lambda f: receptance(m, c, k, b_in, c_out, f), n_out=c_out.shape[0], name="matrix")


def response_tones(
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    c_out: np.ndarray,
    force_tones: Sequence[Tone],
) -> list[Tone]:
    """Steady-state output tones (m) of an LTI system driven by force tones (N) in absolute time."""
    c_out = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    out = []
    for t in force_tones:
        q = np.linalg.solve(
            dynamic_stiffness(m, c, k, t.freq_hz), np.asarray(t.amplitude, dtype=np.complex128)
        )
        out.append(Tone(t.freq_hz, c_out @ q))
    return out


def harmonic_balance_plant(
    m: np.ndarray,
    c: np.ndarray,
    k0: np.ndarray,
    dk_fourier: dict[int, np.ndarray],
    speed_hz: float,
    b_in: np.ndarray,
    c_out: np.ndarray,
    n_harmonics: int = 8,
) -> Plant:
    """Linear time-periodic plant by harmonic balance.

    ``dK(t) = sum_l dk_fourier[l] exp(j l Omega t)`` (``Omega = 2 pi speed_hz``; include both
    ``l`` and ``-l`` with ``dk_fourier[-l] = conj(dk_fourier[l])`` for a real ``dK``). For the
    drive ``Re{exp(j w t)}`` the response is ``Re sum_k Q_k exp(j (w + k Omega) t)``,
    ``|k| <= n_harmonics``, with ``Z(w + k Omega) Q_k + sum_l dK_l Q_{k-l} = b delta_k0``.
    """
    n = k0.shape[0]
    c_out = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    b = np.asarray(b_in, dtype=np.complex128).reshape(n)
    ks = np.arange(-n_harmonics, n_harmonics + 1)
    h = len(ks)

    def tones(f_hz: float) -> tuple[np.ndarray, np.ndarray]:
        big = np.zeros((h * n, h * n), dtype=np.complex128)
        for a, ka in enumerate(ks):
            big[a * n : (a + 1) * n, a * n : (a + 1) * n] += dynamic_stiffness(m, c, k0, f_hz + ka * speed_hz)
            for bcol, kb in enumerate(ks):
                lk = int(ka - kb)
                if lk in dk_fourier:
                    big[a * n : (a + 1) * n, bcol * n : (bcol + 1) * n] += dk_fourier[lk]
        rhs = np.zeros(h * n, dtype=np.complex128)
        i0 = int(np.nonzero(ks == 0)[0][0])
        rhs[i0 * n : (i0 + 1) * n] = b
        q = np.linalg.solve(big, rhs).reshape(h, n)
        return f_hz + ks * speed_hz, q @ c_out.T

    return Plant(tones=tones, n_out=c_out.shape[0], name="harmonic_balance")


# ------------------------------------------------------------------------------------------
# shared helpers
# ------------------------------------------------------------------------------------------


def _rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(rng)


def _force(spec: ForceSpec, f_hz: float) -> complex:
    val = spec(f_hz) if callable(spec) else spec
    return complex(val)


def _n_periods(settings: StepSettings, nf: int) -> np.ndarray:
    n = np.broadcast_to(np.asarray(settings.n_periods, dtype=np.int64), (nf,)).copy()
    if np.any(n < 2):
        raise ValueError("n_periods must be >= 2 (the variance needs period-to-period scatter)")
    return n


def _freqs(frequency_hz: Sequence[float] | np.ndarray) -> np.ndarray:
    f = np.asarray(frequency_hz, dtype=np.float64).reshape(-1)
    if f.size == 0 or np.any(~np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("frequencies must be finite and > 0 Hz")
    return f


def settle_counts(frequency_hz: np.ndarray, settings: StepSettings) -> np.ndarray:
    """Settle periods per point: ``max(settle_periods, ceil(settle_s f))``."""
    f = _freqs(frequency_hz)
    by_time = np.ceil(settings.settle_s * f - 1e-9).astype(np.int64)
    return np.maximum(int(settings.settle_periods), by_time)


def point_start_times(frequency_hz: np.ndarray, settings: StepSettings) -> np.ndarray:
    """Absolute start time (s) of every point on the shared timeline."""
    f = _freqs(frequency_hz)
    n = _n_periods(settings, f.size)
    dur = (settle_counts(f, settings) + n) / f + settings.dwell_s
    return settings.t_start_s + np.concatenate([[0.0], np.cumsum(dur)[:-1]])


def _phasor_noise_var(
    sample_std: float | Sequence[float],
    phasor_std: float | Sequence[float] | None,
    m: int | None,
    width: int,
    what: str,
) -> np.ndarray:
    if phasor_std is not None:
        v = np.broadcast_to(np.asarray(phasor_std, dtype=np.float64) ** 2, (width,))
        return np.array(v)
    s = np.broadcast_to(np.asarray(sample_std, dtype=np.float64), (width,))
    if np.any(s > 0) and m is None:
        raise ValueError(
            f"{what}: per-sample noise needs samples_per_period; give the phasor noise std instead"
        )
    if m is None:
        return np.zeros(width)
    return np.array(white_noise_phasor_var(s, m))


def _complex_gauss(rng: np.random.Generator, shape: tuple[int, ...], var: np.ndarray) -> np.ndarray:
    """Circular complex Gaussian with ``E|n|^2 = var`` (broadcast on the last axis)."""
    z = rng.standard_normal((*shape, 2))
    return np.sqrt(var / 2.0) * (z[..., 0] + 1j * z[..., 1])


def _assemble(
    f: np.ndarray,
    t0: np.ndarray,
    n: np.ndarray,
    per_in: list[np.ndarray],
    per_out: list[np.ndarray],
    keep: bool,
    records: list[TimeRecord] | None = None,
) -> SteppedSineResult:
    nf = f.size
    n_out = per_out[0].shape[1]
    mi = np.empty((nf, 1), complex)
    vi = np.empty((nf, 1))
    mo = np.empty((nf, n_out), complex)
    vo = np.empty((nf, n_out))
    for j in range(nf):
        mi[j], vi[j], _ = average_periods(per_in[j])
        mo[j], vo[j], _ = average_periods(per_out[j])
    pin = pout = None
    if keep:
        p = int(n.max())
        pin = np.full((nf, p, 1), np.nan + 1j * np.nan)
        pout = np.full((nf, p, n_out), np.nan + 1j * np.nan)
        for j in range(nf):
            pin[j, : n[j]] = per_in[j]
            pout[j, : n[j]] = per_out[j]
    return SteppedSineResult(
        frequency_hz=f,
        input_phasor=mi,
        output_phasor=mo,
        output_var=vo,
        input_var=vi,
        n_periods=n.astype(np.int32),
        t0_s=t0,
        period_input=pin,
        period_output=pout,
        records=records,
    )


# ------------------------------------------------------------------------------------------
# fast path
# ------------------------------------------------------------------------------------------


def simulate_fast(
    plant: Plant,
    frequency_hz: Sequence[float] | np.ndarray,
    settings: StepSettings | None = None,
    disturbances: Sequence[Tone] = (),
    rng: np.random.Generator | int | None = 0,
) -> SteppedSineResult:
    """Stepped-sine sweep by the closed-form tone lock-in plus per-period phasor noise.

    ``disturbances``: fixed output tones (m) in absolute time, e.g. the 1X/2X synchronous
    responses at ``k * speed_rpm / 60`` Hz. ``rng``: a Generator or a seed (deterministic).
    """
    st = settings or StepSettings()
    f = _freqs(frequency_hz)
    n = _n_periods(st, f.size)
    t0 = point_start_times(f, st)
    settle = settle_counts(f, st)
    gen = _rng(rng)
    m = st.samples_per_period
    var_out = _phasor_noise_var(
        st.output_noise_std, st.output_phasor_noise_std, m, plant.n_out, "output noise"
    )
    var_in = _phasor_noise_var(st.input_noise_std, st.input_phasor_noise_std, m, 1, "input noise")
    d_freq = np.array([d.freq_hz for d in disturbances], dtype=np.float64)
    d_amp = (
        np.array([np.asarray(d.amplitude, complex).reshape(plant.n_out) for d in disturbances])
        if disturbances
        else np.zeros((0, plant.n_out), complex)
    )
    per_in: list[np.ndarray] = []
    per_out: list[np.ndarray] = []
    for j, fj in enumerate(f):
        w = 2.0 * np.pi * fj
        force = _force(st.force_amplitude, fj)
        tf, ta = plant.tones(fj)
        tf = np.asarray(tf, dtype=np.float64).reshape(-1)
        ta = np.asarray(ta, dtype=np.complex128).reshape(tf.size, plant.n_out)
        # absolute-time amplitudes -> local frame tau = t - t0 (see module docstring)
        amp_plant = force * ta * np.exp(1j * (2.0 * np.pi * tf - w) * t0[j])[:, None]
        amp_dist = d_amp * np.exp(1j * 2.0 * np.pi * d_freq * t0[j])[:, None]
        freqs = np.concatenate([tf, d_freq])
        amps = np.concatenate([amp_plant, amp_dist], axis=0)
        tau0 = settle[j] / fj
        out = tone_lockin(freqs, amps, fj, tau0, int(n[j]), m)
        inp = np.full((int(n[j]), 1), force, dtype=np.complex128)
        inp = inp + _complex_gauss(gen, (int(n[j]), 1), var_in)
        out = out + _complex_gauss(gen, (int(n[j]), plant.n_out), var_out)
        per_in.append(inp)
        per_out.append(out)
    return _assemble(f, t0, n, per_in, per_out, st.keep_periods)


# ------------------------------------------------------------------------------------------
# time-domain path
# ------------------------------------------------------------------------------------------


def _state_matrix(m: np.ndarray, c: np.ndarray, k: np.ndarray) -> np.ndarray:
    n = m.shape[0]
    minv_k = np.linalg.solve(m, k)
    minv_c = np.linalg.solve(m, c)
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -minv_k
    a[n:, n:] = -minv_c
    return a


def simulate_time_domain(
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    b_in: np.ndarray,
    c_out: np.ndarray,
    frequency_hz: Sequence[float] | np.ndarray,
    settings: StepSettings | None = None,
    disturbances: Sequence[Tone] = (),
    rng: np.random.Generator | int | None = 0,
    stiffness_perturbation: Callable[[float], np.ndarray] | None = None,
    method: str = "auto",
    rtol: float = 1e-10,
    keep_records: bool = False,
) -> SteppedSineResult:
    """Stepped-sine sweep by time integration of ``M q'' + C q' + (K + dK(t)) q = b u + f_dist``.

    ``m, c, k`` (n, n) dense (SI; ``c`` may include ``Omega G``); ``b_in`` (n,) force pattern of
    the unit input (N per N); ``c_out`` (n_out, n) selects the outputs (m); ``disturbances``:
    force tones (n,) in N, absolute time; ``stiffness_perturbation``: the time-varying stiffness
    hook ``t -> dK(t)`` (absolute time, N/m). Starts from rest, carries the state across steps.
    ``method``: ``"exact"`` (LTI only: particular solution + ``expm`` propagation),
    ``"ode"`` (DOP853, relative tolerance ``rtol``) or ``"auto"``. Noise is white per sample
    (``settings.output_noise_std``, ``input_noise_std``); the phasor-noise overrides do not
    apply here. ``keep_records`` returns the samples of every point.
    """
    st = settings or StepSettings()
    if st.samples_per_period is None:
        raise ValueError("the time-domain path needs an integer samples_per_period")
    mm = int(st.samples_per_period)
    if mm < 3:
        raise ValueError("samples_per_period must be >= 3")
    if st.output_phasor_noise_std is not None or st.input_phasor_noise_std is not None:
        raise ValueError(
            "the time-domain path takes white noise per sample (output_noise_std, "
            "input_noise_std), not phasor noise std"
        )
    m = np.asarray(m, dtype=np.float64)
    c = np.asarray(c, dtype=np.float64)
    k = np.asarray(k, dtype=np.float64)
    ndof = m.shape[0]
    b = np.asarray(b_in, dtype=np.float64).reshape(ndof)
    cout = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    n_out = cout.shape[0]
    if method == "auto":
        method = "ode" if stiffness_perturbation is not None else "exact"
    if method == "exact" and stiffness_perturbation is not None:
        raise ValueError("method='exact' is for time-invariant systems; use 'ode' with dK(t)")
    if method not in ("exact", "ode"):
        raise ValueError(f"unknown method {method!r}")
    f = _freqs(frequency_hz)
    n = _n_periods(st, f.size)
    t0 = point_start_times(f, st)
    settle = settle_counts(f, st)
    gen = _rng(rng)
    s_out = np.broadcast_to(np.asarray(st.output_noise_std, dtype=np.float64), (n_out,))
    s_in = float(st.input_noise_std)
    a_mat = _state_matrix(m, c, k)
    d_freq = np.array([d.freq_hz for d in disturbances], dtype=np.float64)
    d_force = (
        np.array([np.asarray(d.amplitude, complex).reshape(ndof) for d in disturbances])
        if disturbances
        else np.zeros((0, ndof), complex)
    )
    # steady-state displacement amplitudes of the disturbances (exact path only)
    d_q = (
        np.array(
            [
                np.linalg.solve(dynamic_stiffness(m, c, k, fd), fv)
                for fd, fv in zip(d_freq, d_force, strict=True)
            ]
        )
        if (method == "exact" and disturbances)
        else np.zeros((0, ndof), complex)
    )
    x = np.zeros(2 * ndof)  # state [q, q'] at the start of the current point
    per_in: list[np.ndarray] = []
    per_out: list[np.ndarray] = []
    records: list[TimeRecord] | None = [] if keep_records else None
    for j, fj in enumerate(f):
        w = 2.0 * np.pi * fj
        period = 1.0 / fj
        n_tot = int(settle[j]) + int(n[j])
        ns = n_tot * mm
        dt = period / mm
        tau = np.arange(ns) * dt
        force = _force(st.force_amplitude, fj)
        u = np.real(force * np.exp(1j * 2.0 * np.pi * (np.arange(ns) % mm) / mm))
        if method == "exact":
            y, x = _exact_point(a_mat, m, c, k, b, cout, force, w, t0[j], d_freq, d_q, x, mm, n_tot)
        else:
            y, x = _ode_point(
                m,
                c,
                k,
                b,
                cout,
                force,
                w,
                t0[j],
                d_freq,
                d_force,
                x,
                tau,
                n_tot * period,
                stiffness_perturbation,
                rtol,
            )
        u_meas = u + s_in * gen.standard_normal(ns) if s_in > 0 else u
        y_meas = y + s_out * gen.standard_normal((ns, n_out)) if np.any(s_out > 0) else y
        fs = mm * fj
        per_in.append(lockin_periods(u_meas[:, None], fs, fj, 0.0, int(n[j]), int(settle[j])))
        per_out.append(lockin_periods(y_meas, fs, fj, 0.0, int(n[j]), int(settle[j])))
        if st.dwell_s > 0 and j + 1 < f.size:
            x = _dwell(
                a_mat,
                m,
                c,
                k,
                x,
                t0[j] + n_tot * period,
                st.dwell_s,
                d_freq,
                d_force,
                method,
                stiffness_perturbation,
                rtol,
            )
        if records is not None:
            records.append(TimeRecord(float(fj), float(t0[j]), tau, u_meas, y_meas))
    return _assemble(f, t0, n, per_in, per_out, st.keep_periods, records)


def _dwell(
    a_mat: np.ndarray,
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    x: np.ndarray,
    t_abs: float,
    dwell: float,
    d_freq: np.ndarray,
    d_force: np.ndarray,
    method: str,
    dk: Callable[[float], np.ndarray] | None,
    rtol: float,
) -> np.ndarray:
    """Propagate the state over an idle gap (drive off) starting at absolute time ``t_abs``."""
    ndof = m.shape[0]
    if method == "exact":
        nu = 2.0 * np.pi * d_freq

        def part(t: float) -> np.ndarray:
            if d_freq.size == 0:
                return np.zeros(2 * ndof)
            q = np.zeros(ndof, complex)
            v = np.zeros(ndof, complex)
            for fd, nd, fv in zip(d_freq, nu, d_force, strict=True):
                qd = np.linalg.solve(dynamic_stiffness(m, c, k, fd), fv) * np.exp(1j * nd * t)
                q += qd
                v += 1j * nd * qd
            return np.concatenate([q.real, v.real])

        xh = x - part(t_abs)
        return scipy.linalg.expm(a_mat * dwell) @ xh + part(t_abs + dwell)
    _, x_end = _ode_point(
        m,
        c,
        k,
        np.zeros(ndof),
        np.zeros((1, ndof)),
        0.0,
        2.0 * np.pi / dwell,
        t_abs,
        d_freq,
        d_force,
        x,
        np.zeros(0),
        dwell,
        dk,
        rtol,
    )
    return x_end


def _exact_point(
    a_mat: np.ndarray,
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    b: np.ndarray,
    cout: np.ndarray,
    force: complex,
    w: float,
    t0: float,
    d_freq: np.ndarray,
    d_q: np.ndarray,
    x_start: np.ndarray,
    mm: int,
    n_tot: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact LTI response over one point; returns outputs (n_tot*mm, n_out) and the end state."""
    ndof = m.shape[0]
    period = 2.0 * np.pi / w
    dt = period / mm
    qp = np.linalg.solve(dynamic_stiffness(m, c, k, w / (2.0 * np.pi)), b * force)  # local frame
    dq_loc = d_q * np.exp(1j * 2.0 * np.pi * d_freq * t0)[:, None]  # (nd, ndof) local frame
    nu = 2.0 * np.pi * d_freq

    def particular(tau_arr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        e = np.exp(1j * w * tau_arr)[:, None]
        q = np.real(qp[None, :] * e)
        v = np.real(1j * w * qp[None, :] * e)
        if d_freq.size:
            ed = np.exp(1j * np.outer(tau_arr, nu))  # (nt, nd)
            q = q + np.real(ed @ dq_loc)
            v = v + np.real((ed * (1j * nu)[None, :]) @ dq_loc)
        return q, v

    q0, v0 = particular(np.array([0.0]))
    xh = x_start - np.concatenate([q0[0], v0[0]])
    phi = scipy.linalg.expm(a_mat * dt)
    powers = np.empty((mm, 2 * ndof, 2 * ndof))
    powers[0] = np.eye(2 * ndof)
    for i in range(1, mm):
        powers[i] = phi @ powers[i - 1]
    phi_period = phi @ powers[mm - 1]
    c_pow = np.einsum("oq,iqs->ios", cout, powers[:, :ndof, :])  # (mm, n_out, 2n)
    ns = n_tot * mm
    y = np.empty((ns, cout.shape[0]))
    for p in range(n_tot):
        y[p * mm : (p + 1) * mm] = c_pow @ xh
        xh = phi_period @ xh
    # particular part projected on the outputs first (n_out << n)
    ph = np.exp(1j * 2.0 * np.pi * (np.arange(ns) % mm) / mm)  # exp(j w tau), exact periodicity
    y += np.real(np.outer(ph, cout @ qp))
    if d_freq.size:
        tau = np.arange(ns) * dt
        y += np.real(np.exp(1j * np.outer(tau, nu)) @ (dq_loc @ cout.T))
    qe, ve = particular(np.array([n_tot * period]))
    x_end = np.concatenate([qe[0], ve[0]]) + xh
    return y, x_end


def _ode_point(
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    b: np.ndarray,
    cout: np.ndarray,
    force: complex,
    w: float,
    t0: float,
    d_freq: np.ndarray,
    d_force: np.ndarray,
    x_start: np.ndarray,
    tau: np.ndarray,
    t_end: float,
    dk: Callable[[float], np.ndarray] | None,
    rtol: float,
) -> tuple[np.ndarray, np.ndarray]:
    """DOP853 over one point (local time); returns outputs at ``tau`` and the end state."""
    ndof = m.shape[0]
    minv = np.linalg.inv(m)
    nu = 2.0 * np.pi * d_freq

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v = x[:ndof], x[ndof:]
        load = b * np.real(force * np.exp(1j * w * t))
        if nu.size:
            load = load + np.real(np.exp(1j * nu * (t0 + t)) @ d_force)
        kk = k if dk is None else k + dk(t0 + t)
        acc = minv @ (load - kk @ q - c @ v)
        return np.concatenate([v, acc])

    # absolute tolerance from the size of the quasi-static and dynamic responses
    z = dynamic_stiffness(m, c, k, w / (2.0 * np.pi))
    qs = np.abs(np.linalg.solve(z, b * force))
    scale = max(float(np.max(qs)), float(np.max(np.abs(x_start))), 1e-300)
    if nu.size:
        for fd, fv in zip(d_freq, d_force, strict=True):
            qd = np.abs(np.linalg.solve(dynamic_stiffness(m, c, k, fd), fv))
            scale = max(scale, float(np.max(qd)))
    atol = np.concatenate([np.full(ndof, scale), np.full(ndof, scale * max(w, 1.0))]) * rtol * 1e-2
    t_eval = np.append(tau, t_end)
    sol = solve_ivp(
        rhs,
        (0.0, t_end),
        x_start,
        method="DOP853",
        t_eval=t_eval,
        rtol=rtol,
        atol=atol,
        max_step=(2.0 * np.pi / w) / 16.0,
    )
    if not sol.success:
        raise RuntimeError(f"time integration failed at f = {w / 2 / np.pi:g} Hz: {sol.message}")
    q = sol.y[:ndof, :-1].T
    return q @ cout.T, sol.y[:, -1].copy()
