"""Benchmark of the validation step (FDMVOP) on a 262-point SISO sweep with rotor-like data.

Synthetic data: a 3-mode receptance (54, 173, 534 Hz, as the crack rig) as the "truth", a model
with about 5 % error in natural frequencies, damping and modal constants, forces of 1-10 N with
random phase, complex Gaussian output noise (sigma 5 nm) and V = 0.02 um (the dissertation's bound),
262 log-spaced points 30-600 Hz. Additive io uncertainty.

Timed in one run (median of repeats, OPENBLAS_NUM_THREADS=1 recommended): the LMI as built (one SDP
per frequency, SISO per-point numpy batched over the frequencies) and a per-frequency bisection on
the same LMI (``rtol`` 1e-9; same backend, same certified lower / verified upper bounds and status
checks on the final answer), for each backend ('clarabel', the default: conic data filled directly;
'cvxpy': the problem built once with cvxpy Parameters), plus the closed form. The accuracy of both
methods is checked against the closed form in the same run. Run
``OPENBLAS_NUM_THREADS=1 python -m bench.bench_validation``.
"""

from __future__ import annotations

import statistics
import time
import warnings
from typing import Any

import numpy as np

from rotorcheck.robust import mu as gmu
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


def run(repeats: int = 7, bisection_repeats: int = 3, seed: int = 0,
        backends: tuple[str, ...] = (gmu.DEFAULT_BACKEND, "cvxpy")) -> dict[str, Any]:
    """Time the methods on the same data; returns timings (s), ratios, time breakdowns and the
    accuracies against the closed form (max relative error over the points with gamma > 0)."""
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
    out: dict[str, Any] = {"default_backend": gmu.DEFAULT_BACKEND, "n_points": int(W.size),
                           "n_gamma_zero": int(np.count_nonzero(~nz)), "time_closed_form_s": t_cf}
    for bk in backends:
        # build the cached problems once (compilation is not part of the per-sweep cost)
        gmu.required_gamma(me[:3], W[:3], Zt[:3], V, backend=bk)
        gmu.required_gamma_bisection(me[:3], W[:3], Zt[:3], V, backend=bk)
        t_lmi, r_lmi = _median_time(lambda bk=bk: gmu.required_gamma(me, W, Zt, V, backend=bk),
                                    repeats)
        t_bis, r_bis = _median_time(
            lambda bk=bk: gmu.required_gamma_bisection(me, W, Zt, V, backend=bk),
            bisection_repeats)
        tl, tb = r_lmi.timings, r_bis.timings
        out.update({
            f"{bk}_time_lmi_s": t_lmi,
            f"{bk}_time_bisection_s": t_bis,
            f"{bk}_ratio_bisection_over_lmi": t_bis / t_lmi,
            f"{bk}_ratio_lmi_over_closed_form": t_lmi / t_cf,
            f"{bk}_lmi_solver_calls": r_lmi.n_solver_calls,
            f"{bk}_bisection_solver_calls": r_bis.n_solver_calls,
            # where the time goes (last repeat): inside Clarabel, in the solve calls (Clarabel plus
            # the data hand-over / cvxpy), SQP refinement of the explicit Delta, the rest (numpy)
            f"{bk}_lmi_time_in_clarabel_s": tl.get("clarabel", 0.0),
            f"{bk}_lmi_time_in_solve_calls_s": tl.get("solve_total", 0.0),
            f"{bk}_lmi_time_refine_s": tl.get("refine", 0.0),
            f"{bk}_lmi_time_rest_s": tl.get("wall", 0.0) - tl.get("solve_total", 0.0)
            - tl.get("refine", 0.0),
            f"{bk}_bisection_time_in_clarabel_s": tb.get("clarabel", 0.0),
            f"{bk}_bisection_time_in_solve_calls_s": tb.get("solve_total", 0.0),
            f"{bk}_bisection_time_refine_s": tb.get("refine", 0.0),
            f"{bk}_bisection_time_rest_s": tb.get("wall", 0.0) - tb.get("solve_total", 0.0)
            - tb.get("refine", 0.0),
            f"{bk}_ratio_clarabel_time_bisection_over_lmi":
                tb.get("clarabel", 0.0) / max(tl.get("clarabel", 0.0), 1e-300),
            f"{bk}_lmi_max_rel_err_lower": relerr(r_lmi.gamma_lower),
            f"{bk}_lmi_max_rel_err_upper": relerr(r_lmi.gamma_upper),
            f"{bk}_lmi_max_rel_gap": float(np.nanmax(r_lmi.rel_gap)),
            f"{bk}_bisection_max_rel_err_lower": relerr(r_bis.gamma_lower),
            f"{bk}_bisection_max_rel_err_upper": relerr(r_bis.gamma_upper),
            f"{bk}_bisection_max_rel_gap": float(np.nanmax(r_bis.rel_gap)),
            f"{bk}_lmi_status_ok": int(np.count_nonzero(r_lmi.status == "ok")),
            f"{bk}_bisection_status_ok": int(np.count_nonzero(r_bis.status == "ok")),
        })
    return out


def _summary(res: dict[str, Any]) -> str:
    bk = res["default_backend"]
    ratio, t_lmi = res[f"{bk}_ratio_bisection_over_lmi"], res[f"{bk}_time_lmi_s"]
    ok = ratio >= 50 and t_lmi < 1.0
    return (f"DEFAULT BACKEND {bk!r}: LMI {t_lmi:.3f} s for {res['n_points']} points, bisection "
            f"{res[f'{bk}_time_bisection_s']:.2f} s -> {ratio:.1f}x (target >= 50x and < 1 s: "
            f"{'met' if ok else 'NOT met'}); in-Clarabel time ratio "
            f"{res[f'{bk}_ratio_clarabel_time_bisection_over_lmi']:.1f}x; max rel err vs closed form: "
            f"LMI lower {res[f'{bk}_lmi_max_rel_err_lower']:.1e} upper "
            f"{res[f'{bk}_lmi_max_rel_err_upper']:.1e}, bisection lower "
            f"{res[f'{bk}_bisection_max_rel_err_lower']:.1e} upper "
            f"{res[f'{bk}_bisection_max_rel_err_upper']:.1e}")


def _print_table(res: dict[str, Any]) -> None:
    width = max(len(k) for k in res)
    for k, v in res.items():
        val = f"{v:.4g}" if isinstance(v, float) else str(v)
        print(f"{k:<{width}}  {val}")


if __name__ == "__main__":
    result = run()
    _print_table(result)
    print(_summary(result))
