"""Time integration as an independent check of the fast simulator and the harmonic balance (oracles).

- :func:`simulate_time_domain`: the stepped-sine sweep by time integration of
  ``M q'' + C q' + (K + dK(t)) q = b u(t) + f_dist(t)`` from rest through the whole sweep (state
  carried across steps) on the simulator's timeline, sampled (plus white noise) and locked in by
  :func:`rotorcheck.signal.lockin.lockin_periods`. Without ``dK`` it is exact: particular
  sinusoidal solutions plus the homogeneous part propagated by ``expm(A dt)``; with ``dK`` (the
  time-varying stiffness hook ``t -> dK`` in absolute time, N/m) it uses DOP853 at tight tolerance.
- :func:`simulate_ivp`: the cracked rotor from rest by ``scipy.integrate.solve_ivp`` (reference of
  the Magnus integrator on short spans).

The state matrix, dynamic stiffness and solves are built here, not taken from rotorcheck.fe.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from rotorcheck.config import Crack
from rotorcheck.faults.crack import CrackStiffness, crack_stiffness
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.signal.lockin import lockin_periods
from rotorcheck.sim.simulator import (
    SteppedSineResult,
    StepSettings,
    TimeRecord,
    Tone,
    _assemble,
    _force,
    _freqs,
    _n_periods,
    _rng,
    point_start_times,
    settle_counts,
)

TWO_PI = 2.0 * np.pi


def dynamic_stiffness(m: np.ndarray, c: np.ndarray, k: np.ndarray, f_hz: float) -> np.ndarray:
    """``Z = K - w^2 M + j w C`` at ``f_hz`` (N/m)."""
    w = 2.0 * np.pi * f_hz
    return k - w**2 * m + 1j * w * c




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
    # the right-hand side is called ~10^5 times per point: its constants once (M^-1 B Re/Im F, M^-1 K, M^-1 C, the
    # disturbances' M^-1 F_d), each call a few small products (the same equations; sums in another order)
    mb_re, mb_im = minv @ (b * force.real), minv @ (b * force.imag)
    mk, mc = minv @ k, minv @ c
    md = d_force @ minv.T if nu.size else None

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v = x[:ndof], x[ndof:]
        wt = w * t
        acc = mb_re * math.cos(wt) - mb_im * math.sin(wt) - mk @ q - mc @ v
        if md is not None:
            acc += np.real(np.exp(1j * nu * (t0 + t)) @ md)
        if dk is not None:
            acc -= minv @ (dk(t0 + t) @ q)
        res = np.empty(2 * ndof)
        res[:ndof] = v
        res[ndof:] = acc
        return res

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


def simulate_ivp(
    system: MechanicalSystem,
    crack: Crack | CrackStiffness | None,
    speed_rpm: float,
    force: np.ndarray,
    f_force_hz: float,
    t_eval: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-16,
    **crack_kw: Any,
) -> np.ndarray:
    """Reference integration with ``scipy.integrate.solve_ivp`` from rest; states (T, 2n) at
    ``t_eval`` (s). Force ``Re{force e^{j 2 pi f t}}`` (N). Slow: short spans / small models only.
    """
    if crack is not None and not isinstance(crack, CrackStiffness):
        crack = crack_stiffness(system, crack, **crack_kw)
    M, C, G, K = system.matrices(speed_rpm)
    n = system.n_dof
    om = float(speed_rpm) * RPM_TO_RAD_S
    minv = np.linalg.inv(M)
    mk, md = minv @ K, minv @ (C + om * G)
    b = np.asarray(force, dtype=complex)
    fr, fi = minv @ b.real, minv @ b.imag
    w = TWO_PI * f_force_hz
    dofs = crack.dofs if crack is not None else None
    minv_s = minv[:, dofs] if dofs is not None else None

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v = x[:n], x[n:]
        acc = -mk @ q - md @ v + fr * np.cos(w * t) - fi * np.sin(w * t)
        if crack is not None:
            assert minv_s is not None and dofs is not None
            acc += minv_s @ (crack.at_rotation(om * t)[0] @ q[dofs])
        return np.concatenate([v, acc])

    a_lin = np.zeros((2 * n, 2 * n))
    a_lin[:n, n:] = np.eye(n)
    a_lin[n:, :n] = -mk
    a_lin[n:, n:] = -md
    kw: dict[str, Any] = {}
    if method in ("Radau", "BDF", "LSODA"):
        kw["jac"] = a_lin
    sol = solve_ivp(
        rhs,
        (0.0, float(t_eval[-1])),
        np.zeros(2 * n),
        method=method,
        t_eval=t_eval,
        rtol=rtol,
        atol=atol,
        **kw,
    )
    if not sol.success:
        raise RuntimeError(sol.message)
    return sol.y.T
