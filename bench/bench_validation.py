"""Benchmark of the validation step (FDMVOP) on a 262-point SISO sweep with rotor-like data.

Synthetic data: a 3-mode receptance (54, 173, 534 Hz, as the crack rig) as the "truth", a model
with about 5 % error in natural frequencies, damping and modal constants, forces of 1-10 N with
random phase, complex Gaussian output noise (sigma 5 nm) and V = 0.02 um (the dissertation's bound),
262 log-spaced points 30-600 Hz. Additive io uncertainty.

Timed in one run (median of repeats): the LMI as built (cvxpy Parameters, one SDP per frequency),
the same LMI with Clarabel called directly, a per-frequency bisection on the same LMI (both
backends), and the closed form. Run ``python bench/bench_validation.py``.
"""

from __future__ import annotations

import statistics
import time
import warnings
from typing import Any

import numpy as np

from rotorcheck.robust import gmu
from rotorcheck.robust.closed_form import gamma_required_additive
from rotorcheck.robust.lft import additive_me

N_POINTS = 262
NOISE_SIGMA_M = 5e-9
NOISE_BOUND_M = 2e-8


def receptance(freq_hz: np.ndarray, fn_hz: np.ndarray, zeta: np.ndarray, modal_const: np.ndarray
               ) -> np.ndarray:
    """Sum of modes ``A_r / (w_r^2 - w^2 + 2 j zeta_r w_r w)`` (m/N)."""
    w = 2 * np.pi * freq_hz[:, None]
    wr = 2 * np.pi * fn_hz[None, :]
    return np.sum(modal_const[None, :] / (wr**2 - w**2 + 2j * zeta[None, :] * wr * w), axis=1)


def make_data(seed: int = 0, n_points: int = N_POINTS) -> dict[str, np.ndarray]:
    """Frequencies (Hz), model receptance G (m/N), forces W (N), measured outputs Zt (m)."""
    rng = np.random.default_rng(seed)
    fr = np.geomspace(30.0, 600.0, n_points)
    fn = np.array([54.0, 173.0, 534.0])
    zeta = np.array([0.012, 0.015, 0.02])
    A = np.array([1.1e-1, 2.5e-1, 9.0e-1])  # m/N * (rad/s)^2: statics about 1e-6 m/N
    truth = receptance(fr, fn, zeta, A)
    err = 1 + 0.05 * rng.uniform(-1, 1, size=(3, 3))
    model = receptance(fr, fn * err[0], zeta * err[1], A * err[2])
    W = rng.uniform(1.0, 10.0, n_points) * np.exp(2j * np.pi * rng.uniform(size=n_points))
    noise = NOISE_SIGMA_M / np.sqrt(2) * (rng.normal(size=n_points) + 1j * rng.normal(size=n_points))
    return {"frequency_hz": fr, "G": model, "W": W, "Zt": truth * W + noise}


def _median_time(fn: Any, repeats: int) -> tuple[float, Any]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def run(repeats: int = 5, bisection_repeats: int = 3, seed: int = 0,
        backends: tuple[str, ...] = ("cvxpy", "clarabel")) -> dict[str, Any]:
    """Time the methods on the same data; returns timings (s), ratios and accuracies.

    For each backend ('cvxpy': the problem built once with cvxpy Parameters and re-solved per
    frequency; 'clarabel': the same conic data filled directly and handed to Clarabel) the one-SDP
    LMI and the per-frequency bisection on the same LMI (``rtol`` 1e-9, i.e. the accuracy the
    one-SDP answer reaches) are timed, plus the closed form once.
    """
    warnings.simplefilter("ignore")
    d = make_data(seed)
    me = additive_me(d["G"])
    W, Zt, V = d["W"], d["Zt"], NOISE_BOUND_M
    ref = gamma_required_additive(d["G"], W, Zt, V)
    nz = ref > 0

    def relerr(g: np.ndarray) -> float:
        e = np.abs(g[nz] - ref[nz]) / ref[nz]
        return float(np.max(e)) if e.size else 0.0

    t_cf, _ = _median_time(lambda: gamma_required_additive(d["G"], W, Zt, V), max(repeats, 50))
    out: dict[str, Any] = {"n_points": int(W.size), "n_gamma_zero": int(np.count_nonzero(~nz)),
                           "time_closed_form_s": t_cf}
    for bk in backends:
        # build the cached problems once (compilation is not part of the per-sweep cost)
        gmu.required_gamma(me[:3], W[:3], Zt[:3], V, backend=bk)
        gmu.required_gamma_bisection(me[:3], W[:3], Zt[:3], V, backend=bk)
        t_lmi, r_lmi = _median_time(lambda bk=bk: gmu.required_gamma(me, W, Zt, V, backend=bk),
                                    repeats)
        t_bis, r_bis = _median_time(
            lambda bk=bk: gmu.required_gamma_bisection(me, W, Zt, V, backend=bk),
            bisection_repeats)
        out.update({
            f"{bk}_time_lmi_s": t_lmi,
            f"{bk}_time_bisection_s": t_bis,
            f"{bk}_ratio_bisection_over_lmi": t_bis / t_lmi,
            f"{bk}_ratio_lmi_over_closed_form": t_lmi / t_cf,
            f"{bk}_lmi_solver_calls": r_lmi.n_solver_calls,
            f"{bk}_bisection_solver_calls": r_bis.n_solver_calls,
            f"{bk}_lmi_time_in_solve_calls_s": r_lmi.timings.get("solve_total", 0.0),
            f"{bk}_lmi_time_in_clarabel_s": r_lmi.timings.get("clarabel", 0.0),
            f"{bk}_lmi_wall_s": r_lmi.timings.get("wall", 0.0),
            f"{bk}_bisection_time_in_clarabel_s": r_bis.timings.get("clarabel", 0.0),
            f"{bk}_lmi_max_rel_err_lower": relerr(r_lmi.gamma_lower),
            f"{bk}_lmi_max_rel_err_upper": relerr(r_lmi.gamma_upper),
            f"{bk}_lmi_max_rel_gap": float(np.nanmax(r_lmi.rel_gap)),
            f"{bk}_bisection_max_rel_err_lower": relerr(r_bis.gamma_lower),
            f"{bk}_lmi_status_ok": int(np.count_nonzero(r_lmi.status == "ok")),
            f"{bk}_bisection_status_ok": int(np.count_nonzero(r_bis.status == "ok")),
        })
    return out


def _print_table(res: dict[str, Any]) -> None:
    width = max(len(k) for k in res)
    for k, v in res.items():
        val = f"{v:.4g}" if isinstance(v, float) else str(v)
        print(f"{k:<{width}}  {val}")


if __name__ == "__main__":
    _print_table(run())
