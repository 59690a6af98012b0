"""Stepped-sine simulator: the plant's steady-state tones, a closed-form lock-in, per-period noise.

Timeline. Point ``j`` (excitation ``f_j``, period ``T_j = 1/f_j``) starts at absolute time
``t0_j = t_start_s + sum_{i<j} ((S_i + N_i) T_i + dwell_s)``; the drive is
``u(t) = Re{F_j exp(j w_j (t - t0_j))}`` (N), ``S_j = max(settle_periods, ceil(settle_s f_j))``
periods are skipped, then
``N_j`` periods are locked in with the local time reference ``tau = t - t0_j`` (so the mean input
phasor is ``F_j``). The sample clock is locked to the excitation: ``M = samples_per_period``
samples per period, ``fs_j = M f_j``.

:func:`simulate_fast`: the steady-state output is a sum of tones: the plant's response per unit input
force (``Plant.tones``), scaled by the force, plus fixed synchronous disturbance tones (1X unbalance,
2X misalignment responses, not scaled by the input). The per-period lock-in of that sum is exact in
closed form (:func:`rotorcheck.signal.lockin.tone_lockin`); noise is added per period as circular
complex Gaussian phasors with ``E|n|^2 = 4 sigma^2 / M`` (white noise of std ``sigma`` per sample;
derivation in :mod:`rotorcheck.signal.lockin`).

Plants. Time-invariant plants are receptances of the FE engine (:func:`receptance_plant`,
:func:`matrix_plant`, :class:`rotorcheck.fe.frf.Receptance`); the cracked rotor (a linear
time-periodic plant with tones at ``f + k * speed``) is :func:`rotorcheck.sim.plants.simulator_plant`.
The independent checks of this path (a time integration through the whole sweep on the same
timeline and lock-in: exact for time-invariant plants, DOP853 with a time-varying stiffness hook
``t -> dK(t)``; and an independent dense harmonic balance) are test oracles
(tests/oracles/time_domain.py, tests/oracles/hb.py).

Several inputs (:func:`simulate_fast_patterns`): a stepped-sine test with several actuators (two
shakers, the AMB's x and y axes) driven one at a time. At each frequency pattern ``e`` drives input
``e`` alone (one :class:`Plant` per input, e.g. :func:`receptance_plants`), the patterns measured in
turn on the shared timeline (point ``(j, e)``, frequency-major), each with its own settling; an
undriven input's force phasor is exactly 0. The result (:class:`PatternSweepResult`) becomes a
version-2 run with ``n_exc = n_in`` (:meth:`PatternSweepResult.to_run`, frf by least squares).

Conventions: SI units, frequencies in Hz at interfaces, phasors ``x = Re{X exp(j 2 pi f t)}``
(peak). :func:`simulate_fast`: one input (the actuator force); ``n_out`` outputs. Random numbers
come only from a seeded ``numpy.random.Generator``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from rotorcheck.fe.frf import Receptance
from rotorcheck.signal.lockin import average_periods, tone_lockin, white_noise_phasor_var
from rotorcheck.signal.sidebands import (
    point_times,
    requested_orders,
    shaft_referenced,
    tone_design,
    tone_phasors,
    tone_set,
    tone_variance,
)
from rotorcheck.sweep.format import Channel, Run

__all__ = [
    "PatternSweepResult",
    "Plant",
    "Sidebands",
    "StepSettings",
    "SteppedSineResult",
    "TimeRecord",
    "Tone",
    "disturbance_arrays",
    "local_tones",
    "lti_plant",
    "matrix_plant",
    "measure_sidebands",
    "point_start_times",
    "receptance_plant",
    "receptance_plants",
    "response_tones",
    "settle_counts",
    "simulate_fast",
    "simulate_fast_patterns",
]

ToneFn = Callable[[float], tuple[np.ndarray, np.ndarray]]
ForceSpec = complex | float | Callable[[float], complex]


@dataclass(frozen=True)
class Tone:
    """A fixed tone ``Re{amplitude exp(j 2 pi freq_hz t)}`` in absolute time ``t``.

    For :func:`simulate_fast` ``amplitude`` is the output response (n_out,) in m; as the input of
    :func:`response_tones` (or of a time integration) it is a force vector (n_dof,) in N.
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
    lock-in integral); ``force_amplitude``: input force phasor (N), constant or
    ``f -> F``; ``output_noise_std`` (m, scalar or (n_out,)) / ``input_noise_std`` (N): white
    noise std per sample; alternatively ``output_phasor_noise_std`` / ``input_phasor_noise_std``:
    ``sqrt(E|n|^2)`` of the per-period phasor noise (overrides the per-sample values);
    ``keep_periods``: keep per-period phasors; ``t_start_s``: absolute start time (s);
    ``dwell_s``: idle time between points (s; drive off, disturbances and state continue);
    ``sideband_orders``: the sidebands ``f + k speed`` measured at each point of a rotating run (the least-squares
    fit of :mod:`rotorcheck.signal.sidebands` on the point's samples; needs ``samples_per_period``).
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
    sideband_orders: tuple[int, ...] = ()


@dataclass
class TimeRecord:
    """Samples of one point of a time-domain simulation: local time ``tau`` (s), input (N), outputs (m)."""

    frequency_hz: float
    t0_s: float
    tau: np.ndarray
    u: np.ndarray
    y: np.ndarray


def _channel_columns(channels: Sequence[Channel] | None, n_in: int, n_out: int) -> tuple[list[int], list[int]]:
    """The columns of the inputs and of the outputs in the channel table (the last axis of
    ``period_phasor``), checked against a result's ``n_in`` inputs and ``n_out`` outputs."""
    if channels is None:
        raise ValueError("channels are needed to order period_phasor columns")
    ins = [j for j, c in enumerate(channels) if c.role == "input"]
    outs = [j for j, c in enumerate(channels) if c.role == "output"]
    if len(ins) != n_in or len(outs) != n_out:
        raise ValueError(f"channels have {len(ins)} inputs/{len(outs)} outputs, result has {n_in}/{n_out}")
    return ins, outs


@dataclass
class SteppedSineResult:
    """Averaged phasors per point (shapes: f points, n_out outputs, one input).

    ``input_phasor`` (f, 1) N; ``output_phasor`` (f, n_out) m; ``output_var`` (f, n_out) m^2 and
    ``input_var`` (f, 1) N^2 (variance of the mean from the period scatter); ``n_periods`` (f,);
    ``period_input`` (f, p, 1), ``period_output`` (f, p, n_out) per-period phasors (NaN padded)
    when kept; ``t0_s`` (f,) absolute start time of each point; ``records`` time samples
    (a time-domain simulation, when requested).
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
    sidebands: Sidebands | None = None

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
            ins, outs = _channel_columns(channels, self.period_input.shape[2], self.period_output.shape[2])
            assert channels is not None  # refused above
            nf, p = self.period_input.shape[:2]
            pp = np.full((nf, p, len(channels)), np.nan + 1j * np.nan, dtype=np.complex128)
            pp[:, :, ins] = self.period_input
            pp[:, :, outs] = self.period_output
        run = Run.from_phasors(
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
        sb = self.sidebands
        return run if sb is None else run.with_sidebands(sb.order, sb.phasor[:, None], sb.var[:, None])


# ------------------------------------------------------------------------------------------
# plants
# ------------------------------------------------------------------------------------------


def lti_plant(frf: Callable[[float], np.ndarray], n_out: int, name: str = "lti") -> Plant:
    """Time-invariant plant from an FRF callable ``f_hz -> (n_out,)`` (m/N)."""

    def tones(f_hz: float) -> tuple[np.ndarray, np.ndarray]:
        h = np.asarray(frf(f_hz), dtype=np.complex128).reshape(1, n_out)
        return np.array([f_hz]), h

    return Plant(tones=tones, n_out=n_out, name=name)


def receptance_plant(rec: Receptance, name: str = "lti") -> Plant:
    """Time-invariant plant from an engine receptance with one input (outputs (n_out,) m/N)."""
    if rec.cols.shape[1] != 1:
        raise ValueError(f"a plant has one input, the receptance has {rec.cols.shape[1]}")
    return lti_plant(lambda f: rec.at_hz(f)[:, 0], n_out=rec.C.shape[0], name=name)


def receptance_plants(rec: Receptance, name: str = "lti") -> list[Plant]:
    """One time-invariant plant per input column of an engine receptance (outputs (n_out,) m/N),
    for :func:`simulate_fast_patterns`; the receptance is evaluated once per frequency."""
    n_out, n_in = rec.C.shape[0], rec.cols.shape[1]
    cache: dict[float, np.ndarray] = {}

    def column(i: int) -> Callable[[float], np.ndarray]:
        def frf(f: float) -> np.ndarray:
            key = float(f)
            if key not in cache:
                cache.clear()
                cache[key] = np.asarray(rec.at_hz(f))
            return cache[key][:, i]

        return frf

    return [lti_plant(column(i), n_out=n_out, name=f"{name}[{i}]") for i in range(n_in)]


def matrix_plant(
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    b_in: np.ndarray,
    c_out: np.ndarray,
    band_hz: float | None = None,
) -> Plant:
    """Time-invariant plant ``c_out (K - w^2 M + j w C)^-1 b_in`` from (n, n) matrices (``c`` may
    include ``Omega G``), through the engine; ``band_hz``: the highest frequency that will be asked."""
    c_out = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    b = np.asarray(b_in, dtype=np.float64).reshape(-1, 1)
    return receptance_plant(Receptance(m, c, k, c_out, b, band_hz=band_hz), name="matrix")


def response_tones(
    m: np.ndarray,
    c: np.ndarray,
    k: np.ndarray,
    c_out: np.ndarray,
    force_tones: Sequence[Tone],
) -> list[Tone]:
    """Steady-state output tones (m) of an LTI system driven by force tones (N) in absolute time."""
    if not force_tones:
        return []
    c_out = np.atleast_2d(np.asarray(c_out, dtype=np.float64))
    forces = np.stack([np.asarray(t.amplitude, dtype=np.complex128) for t in force_tones], axis=1)
    freqs = np.array([t.freq_hz for t in force_tones], dtype=float)
    rec = Receptance(m, c, k, c_out, forces, band_hz=float(np.max(np.abs(freqs))))
    h = rec.at_hz(freqs)  # (tones, n_out, tones): column j is tone j's force
    return [Tone(t.freq_hz, h[j, :, j]) for j, t in enumerate(force_tones)]


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
    speed_rpm: float = 0.0,
    shaft_angle_rad: float = 0.0,
) -> SteppedSineResult:
    """Stepped-sine sweep by the closed-form tone lock-in plus per-period phasor noise.

    ``disturbances``: fixed output tones (m) in absolute time, e.g. the 1X/2X synchronous
    responses at ``k * speed_rpm / 60`` Hz. ``rng``: a Generator or a seed (deterministic).
    With ``settings.sideband_orders`` and ``speed_rpm`` > 0 the sidebands are measured too
    (:func:`measure_sidebands`; ``shaft_angle_rad`` the shaft angle at t = 0, as the plant was turned),
    their noise drawn after every other draw (the other results do not change).
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
    d_freq, d_amp = disturbance_arrays(disturbances, plant.n_out)
    per_in: list[np.ndarray] = []
    per_out: list[np.ndarray] = []
    for j, fj in enumerate(f):
        force = _force(st.force_amplitude, fj)
        inp, out = _point(plant, fj, force, t0[j], settle[j], int(n[j]), m, d_freq, d_amp, gen, var_in, var_out)
        per_in.append(inp)
        per_out.append(out)
    res = _assemble(f, t0, n, per_in, per_out, st.keep_periods)
    if st.sideband_orders and speed_rpm != 0.0:
        forces = np.array([_force(st.force_amplitude, fj) for fj in f])
        sb = measure_sidebands([plant], f, forces, t0[:, None], settle[:, None], n, st, var_out, d_freq, d_amp,
                               speed_rpm, shaft_angle_rad, gen)
        res.sidebands = Sidebands(sb.order, sb.phasor[:, 0], sb.var[:, 0])
    return res


@dataclass(frozen=True)
class Sidebands:
    """Measured sidebands: ``order`` (K,), ``phasor`` ((f, K, n_out) or (f, n_exc, K, n_out)) m, shaft-referenced,
    NaN where not separable; ``var`` the same shape, m^2 (the sweep contract's version 3)."""

    order: np.ndarray
    phasor: np.ndarray
    var: np.ndarray


def measure_sidebands(plants: Sequence[Plant], f: np.ndarray, forces: np.ndarray, t0: np.ndarray, settle: np.ndarray,
                      n: np.ndarray, st: StepSettings, var_out: np.ndarray, d_freq: np.ndarray, d_amp: np.ndarray,
                      speed_rpm: float, shaft_angle_rad: float, gen: np.random.Generator) -> Sidebands:
    """The sidebands ``settings.sideband_orders`` of every point (f,) and pattern (one plant each; ``t0`` (f, n_exc)
    s the points' start times, ``settle`` (f, n_exc) and ``n`` (f,) their periods), as the least-squares fit of
    :mod:`rotorcheck.signal.sidebands` reads them from the point's samples: the fit of the noise-free tones
    (the plant's, scaled by ``forces`` (f,), and the disturbances) plus Gaussian noise with the fit's exact
    covariance (white noise, ``var_out`` the per-period phasor variance ``4 sigma^2 / M``), drawn from ``gen``;
    the noise is drawn apart from the lock-in's (the two are uncorrelated for tones apart by more than the
    resolution)."""
    m = st.samples_per_period
    if m is None:
        raise ValueError("sidebands are read from the samples: give samples_per_period")
    orders = [int(k) for k in st.sideband_orders]
    shaft_hz = abs(speed_rpm) / 60.0
    nf, ne, kk, n_out = f.size, len(plants), len(orders), plants[0].n_out
    sigma2 = np.asarray(var_out, dtype=float) * m / 4.0  # per-sample noise variance (n_out,)
    phasor = np.full((nf, ne, kk, n_out), np.nan + 1j * np.nan)
    var = np.full((nf, ne, kk, n_out), np.nan)
    for j, fj in enumerate(f):
        tones = tone_set(float(fj), shaft_hz, orders, float(fj) / float(n[j]))
        design: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}  # by settle periods
        for e, plant in enumerate(plants):
            s_je = int(settle[j, e])
            if s_je not in design:  # the patterns of one frequency share their window: one design
                tau = point_times(float(fj), s_je, int(n[j]), m)
                x = tone_design(tau, tones.freq_hz)
                cov = np.linalg.inv(x.T @ x)
                design[s_je] = (tau, x, cov, np.linalg.cholesky(cov))
            tau, x, cov, chol = design[s_je]
            freqs, amps = local_tones(plant, float(fj), complex(forces[j]), float(t0[j, e]), d_freq, d_amp)
            clean = np.real(np.exp(2j * np.pi * np.outer(tau, freqs)) @ amps)  # (samples, n_out)
            z = gen.standard_normal((x.shape[1], n_out)) * np.sqrt(sigma2)[None, :]
            amp = tone_phasors(cov @ (x.T @ clean) + chol @ z, tones)
            theta = shaft_angle_rad + 2.0 * np.pi * shaft_hz * float(t0[j, e])
            phasor[j, e] = shaft_referenced(requested_orders(amp, tones, orders), orders, theta)
            var[j, e] = requested_orders(tone_variance(cov, tones)[:, None] * sigma2[None, :], tones, orders)
    return Sidebands(np.asarray(orders, dtype=np.int32), phasor, var)


def disturbance_arrays(disturbances: Sequence[Tone], n_out: int) -> tuple[np.ndarray, np.ndarray]:
    """Disturbance tone frequencies (Hz) and amplitudes (tones, n_out) m as arrays."""
    d_freq = np.array([d.freq_hz for d in disturbances], dtype=np.float64)
    d_amp = (
        np.array([np.asarray(d.amplitude, complex).reshape(n_out) for d in disturbances])
        if disturbances
        else np.zeros((0, n_out), complex)
    )
    return d_freq, d_amp


def local_tones(plant: Plant, fj: float, force: complex, t0j: float, d_freq: np.ndarray,
                d_amp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The output tones of point ``j`` in its local time ``tau = t - t0j``: frequencies (Hz) and
    amplitudes (tones, n_out) m, the plant's tones scaled by ``force`` then the disturbance tones
    (``d_freq``, ``d_amp`` as :func:`disturbance_arrays` gives them)."""
    w = 2.0 * np.pi * fj
    tf, ta = plant.tones(fj)
    tf = np.asarray(tf, dtype=np.float64).reshape(-1)
    ta = np.asarray(ta, dtype=np.complex128).reshape(tf.size, plant.n_out)
    # absolute-time amplitudes -> local frame tau = t - t0 (see module docstring)
    amp_plant = force * ta * np.exp(1j * (2.0 * np.pi * tf - w) * t0j)[:, None]
    amp_dist = d_amp * np.exp(1j * 2.0 * np.pi * d_freq * t0j)[:, None]
    return np.concatenate([tf, d_freq]), np.concatenate([amp_plant, amp_dist], axis=0)


def _point(
    plant: Plant,
    fj: float,
    force: complex,
    t0j: float,
    settle_j: int,
    n_j: int,
    m: int | None,
    d_freq: np.ndarray,
    d_amp: np.ndarray,
    gen: np.random.Generator,
    var_in: np.ndarray,
    var_out: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Per-period input (n_j, 1) and output (n_j, n_out) phasors of one point: the plant's tones
    scaled by ``force``, the disturbance tones, then input noise and output noise drawn in that order."""
    freqs, amps = local_tones(plant, fj, force, t0j, d_freq, d_amp)
    tau0 = settle_j / fj
    out = tone_lockin(freqs, amps, fj, tau0, n_j, m)
    inp = np.full((n_j, 1), force, dtype=np.complex128)
    inp = inp + _complex_gauss(gen, (n_j, 1), var_in)
    out = out + _complex_gauss(gen, (n_j, plant.n_out), var_out)
    return inp, out


# ------------------------------------------------------------------------------------------
# several inputs, driven one at a time
# ------------------------------------------------------------------------------------------


@dataclass
class PatternSweepResult:
    """Averaged phasors of a sweep with ``n_exc = n_in`` excitation patterns, pattern ``e`` driving
    input ``e`` alone (shapes: f points, n_exc patterns, n_in inputs, n_out outputs).

    ``input_phasor`` (f, n_exc, n_in) N (0 for the undriven inputs); ``output_phasor``
    (f, n_exc, n_out) m; ``output_var`` (f, n_exc, n_out) m^2 and ``input_var`` (f, n_exc, n_in)
    N^2 (variance of the mean from the period scatter); ``n_periods`` (f, n_exc); ``t0_s``
    (f, n_exc) absolute start time of each point; ``period_input`` (f, n_exc, p, n_in),
    ``period_output`` (f, n_exc, p, n_out) per-period phasors (NaN padded) when kept.
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
    sidebands: Sidebands | None = None

    def to_run(
        self,
        run_id: str,
        speed_rpm: float,
        channels: Sequence[Channel] | None = None,
        notes: str = "",
    ) -> Run:
        """A version-2 :class:`~rotorcheck.sweep.format.Run` (:meth:`Run.from_patterns`: frf by
        least squares, frf_var propagated); ``period_phasor`` columns follow ``channels``
        (required when per-period phasors were kept)."""
        pp = None
        if self.period_input is not None and self.period_output is not None:
            ins, outs = _channel_columns(channels, self.period_input.shape[3], self.period_output.shape[3])
            assert channels is not None  # refused above
            nf, ne, p = self.period_input.shape[:3]
            pp = np.full((nf, ne, p, len(channels)), np.nan + 1j * np.nan, dtype=np.complex128)
            pp[..., ins] = self.period_input
            pp[..., outs] = self.period_output
        run = Run.from_patterns(
            run_id,
            speed_rpm,
            self.frequency_hz,
            self.input_phasor,
            self.output_phasor,
            self.output_var,
            self.n_periods,
            input_var=self.input_var,
            period_phasor=pp,
            notes=notes,
        )
        sb = self.sidebands
        return run if sb is None else run.with_sidebands(sb.order, sb.phasor, sb.var)


def simulate_fast_patterns(
    plants: Sequence[Plant],
    frequency_hz: Sequence[float] | np.ndarray,
    settings: StepSettings | None = None,
    disturbances: Sequence[Tone] = (),
    rng: np.random.Generator | int | None = 0,
    speed_rpm: float = 0.0,
    shaft_angle_rad: float = 0.0,
) -> PatternSweepResult:
    """Stepped-sine sweep with several inputs driven one at a time (:func:`simulate_fast` per point).

    ``plants[i]``: the response to input ``i`` (all with the same ``n_out``). At each frequency the
    patterns ``e = 0 .. n_in - 1`` are measured in turn, pattern ``e`` driving input ``e`` with the
    force ``settings.force_amplitude`` (the other inputs exactly 0), each point with its own settling
    and ``n_periods`` periods on the shared timeline (frequency-major; ``settings.n_periods`` per
    frequency applies to every pattern). Disturbances, noise and lock-in as in
    :func:`simulate_fast`; input noise on the driven input only. ``rng``: a Generator or a seed;
    draws in the order point by point (input noise, then output noise); sidebands as :func:`simulate_fast`.
    """
    if len(plants) == 0:
        raise ValueError("no plants (one per input)")
    n_out = plants[0].n_out
    if any(p.n_out != n_out for p in plants):
        raise ValueError(f"plants have different output counts {[p.n_out for p in plants]}")
    st = settings or StepSettings()
    f = _freqs(frequency_hz)
    n_in = ne = len(plants)
    n = _n_periods(st, f.size)
    f_pts = np.repeat(f, ne)
    n_pts = np.repeat(n, ne)
    t0 = point_start_times(f_pts, dataclasses.replace(st, n_periods=[int(v) for v in n_pts]))
    settle = settle_counts(f_pts, st)
    gen = _rng(rng)
    m = st.samples_per_period
    var_out = _phasor_noise_var(st.output_noise_std, st.output_phasor_noise_std, m, n_out, "output noise")
    var_in = _phasor_noise_var(st.input_noise_std, st.input_phasor_noise_std, m, 1, "input noise")
    d_freq, d_amp = disturbance_arrays(disturbances, n_out)
    nf = f.size
    p_max = int(n.max())
    mi = np.zeros((nf, ne, n_in), complex)
    vi = np.zeros((nf, ne, n_in))
    mo = np.empty((nf, ne, n_out), complex)
    vo = np.empty((nf, ne, n_out))
    pin = np.full((nf, ne, p_max, n_in), np.nan + 1j * np.nan) if st.keep_periods else None
    pout = np.full((nf, ne, p_max, n_out), np.nan + 1j * np.nan) if st.keep_periods else None
    for j, fj in enumerate(f):
        force = _force(st.force_amplitude, fj)
        nj = int(n[j])
        for e, plant in enumerate(plants):
            q = j * ne + e
            inp, out = _point(plant, fj, force, t0[q], settle[q], nj, m, d_freq, d_amp, gen, var_in, var_out)
            full_in = np.zeros((nj, n_in), complex)
            full_in[:, e] = inp[:, 0]
            mi[j, e], vi[j, e], _ = average_periods(full_in)
            mo[j, e], vo[j, e], _ = average_periods(out)
            if pin is not None and pout is not None:
                pin[j, e, :nj] = full_in
                pout[j, e, :nj] = out
    sidebands = None
    if st.sideband_orders and speed_rpm != 0.0:
        forces = np.array([_force(st.force_amplitude, fj) for fj in f])
        sidebands = measure_sidebands(plants, f, forces, t0.reshape(nf, ne), settle.reshape(nf, ne), n, st, var_out,
                                      d_freq, d_amp, speed_rpm, shaft_angle_rad, gen)
    return PatternSweepResult(
        frequency_hz=f,
        input_phasor=mi,
        output_phasor=mo,
        output_var=vo,
        input_var=vi,
        n_periods=np.repeat(n[:, None], ne, axis=1).astype(np.int32),
        t0_s=t0.reshape(nf, ne),
        period_input=pin,
        period_output=pout,
        sidebands=sidebands,
    )
