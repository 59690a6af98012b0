"""Benchmark of real scalar uncertainty blocks (mixed mu, D-G scalings) against the complex
relaxation.

Three parts, one run (``python -m bench.bench_mixed_mu``):

* three-mass ECP 210a trials (dissertation section 3.4: m1e = 2.6 / 2.75 / 2.8113 kg, true
  2.8113 kg, damage k3 386 -> 350 N/m, 200 log-spaced points 0.5-8 Hz, force and displacement at
  mass 1), m1 uncertain as a REAL parameter vs a complex scalar: fault points of the damaged data
  (validation with enclose='data', detection), at a uniform noise bound V (the dissertation's trials
  are noise-free; V = 0 with a real parameter is ill-posed, see :mod:`rotorcheck.robust.mu`);
* brute-force gap: seeded random cases (SISO one real parameter; one real + one complex block),
  certified lower / verified upper bound against a brute-force search over the real parameter;
* time per point real vs complex in the same run (the SISO cases: one SDP per point each; the
  mixed cases: bisection each).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from rotorcheck.robust import detect, lft, mu, validate
from tests.oracles.mixed_mu import cplx as _cplx
from tests.oracles.mixed_mu import min_feasible_1d, real_plus_complex, real_plus_complex_cases

# ECP 210a three-mass system, dissertation Table 1
_M = (2.8113, 2.6396, 2.6074)
_K = (842.3, 806.5, 386.0)
_C = (5.992, 1.9467, 10.7375)
K_DAMAGED = 350.0
N_FREQ = 200
NOISE_LEVELS_M = (1e-5, 1e-4)


def three_mass_Z(freq_hz: np.ndarray, m1: float = _M[0], k3: float = _K[2]) -> np.ndarray:
    """Dynamic stiffness K - w^2 M + j w C (f, 3, 3) of the three-mass rig."""
    M = np.diag([m1, _M[1], _M[2]])
    k1, k2 = _K[0], _K[1]
    c1, c2, c3 = _C
    K = np.array([[k1, -k1, 0.0], [-k1, k1 + k2, -k2], [0.0, -k2, k2 + k3]])
    C = np.array([[c1, -c1, 0.0], [-c1, c1 + c2, -c2], [0.0, -c2, c2 + c3]])
    w = 2 * np.pi * np.asarray(freq_hz)[:, None, None]
    return K[None] - w**2 * M[None] + 1j * w * C[None]


def three_mass_counts(V: float) -> dict[str, tuple[int, int]]:
    """Fault points (real m1, complex m1) of the damaged data per trial at noise bound V (m)."""
    freq = np.geomspace(0.5, 8.0, N_FREQ)
    W = np.ones(N_FREQ, dtype=complex)
    H_h = np.linalg.inv(three_mass_Z(freq))[:, 0, 0]
    H_d = np.linalg.inv(three_mass_Z(freq, k3=K_DAMAGED))[:, 0, 0]
    L, R = lft.mass_factor(2 * np.pi * freq, 0, 3)
    e1 = np.eye(3)[:, [0]]
    out = {}
    for name, m1e in (("trial 1 (m1e 2.6 kg)", 2.6), ("trial 2 (m1e 2.75 kg)", 2.75),
                      ("trial 3 (m1e = m1)", _M[0])):
        me = lft.parametric_me(three_mass_Z(freq, m1=m1e), L, R, e1, e1.T)
        counts = []
        for st in (mu.Structure.real(), mu.Structure()):
            val = validate(me, W, H_h * W, V, enclose="data", structure=st)
            counts.append(detect(me, W, H_d * W, V, val.gamma, structure=st).n_fault)
        out[name] = (counts[0], counts[1])
    return out


def siso_gap(n: int = 300, seed: int = 11) -> dict[str, float]:
    """SISO, one real parameter: gap stats against brute force and time per point."""
    rng = np.random.default_rng(seed)
    me = np.zeros((n, 2, 2), complex)
    me[:, 0, 0] = 0.5 * _cplx(rng, n)
    me[:, 0, 1], me[:, 1, 0], me[:, 1, 1] = _cplx(rng, n), _cplx(rng, n), _cplx(rng, n)
    W = _cplx(rng, n)
    Z0 = lft.lft_upper(me, 0.5 * rng.normal(size=n)[:, None, None])[:, 0, 0] * W
    Zt = Z0 + 10 ** rng.uniform(-2, 0, n) * np.abs(Z0) * _cplx(rng, n)
    V = rng.uniform(0.1, 1.2, n) * np.abs(Zt - Z0)
    t0 = time.perf_counter()
    real = mu.required_gamma(me, W, Zt, V, mu.Structure.real())
    t_real = time.perf_counter() - t0
    t0 = time.perf_counter()
    comp = mu.required_gamma(me, W, Zt, V)
    t_comp = time.perf_counter() - t0

    def feas(i: int) -> Any:
        a, b, c = me[i, 0, 0], me[i, 0, 1] * me[i, 1, 0] * W[i], Zt[i] - me[i, 1, 1] * W[i]

        def f(d: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):
                return np.abs(c - b * d / (1 - a * d)) <= V[i]
        return f

    ref = np.array([min_feasible_1d(feas(i), n=40001) for i in range(n)])
    return _stats("siso", real, comp, ref, t_real, t_comp, n)


def _stats(tag: str, real: mu.GammaResult, comp: mu.GammaResult, ref: np.ndarray, t_real: float,
           t_comp: float, n: int) -> dict[str, float]:
    fin = np.isfinite(ref) & (ref > 0) & (real.status == "ok")
    gap = (real.gamma_upper[fin] - real.gamma_lower[fin]) / real.gamma_upper[fin]
    ok = (comp.status == "ok") & np.isfinite(real.gamma_lower)
    bracket = bool(np.all(real.gamma_lower[fin] <= ref[fin] * (1 + 1e-6))
                   and np.all(real.gamma_upper[fin] >= ref[fin] * (1 - 1e-6)))
    return {f"{tag}_cases": float(n), f"{tag}_explainable": float(np.count_nonzero(fin)),
            f"{tag}_bracket_holds": float(bracket),
            f"{tag}_gap_median": float(np.median(gap)), f"{tag}_gap_max": float(np.max(gap)),
            f"{tag}_real_above_complex_frac": float(np.mean(
                real.gamma_lower[ok] > comp.gamma_upper[ok] * (1 + 1e-3))),
            f"{tag}_ms_per_point_real": 1e3 * t_real / n,
            f"{tag}_ms_per_point_complex": 1e3 * t_comp / n,
            f"{tag}_time_ratio_real_over_complex": t_real / t_comp}


def mixed_gap(n: int = 40, seed: int = 12) -> dict[str, float]:
    """One real + one complex scalar block sharing gamma: gap stats and time per point."""

    me, W, Zt, V = real_plus_complex_cases(np.random.default_rng(seed), n)
    t0 = time.perf_counter()
    real = mu.required_gamma(me, W, Zt, V, mu.Structure((mu.Block("real"), mu.Block("scalar"))))
    t_real = time.perf_counter() - t0
    t0 = time.perf_counter()
    comp = mu.required_gamma(me, W, Zt, V, mu.Structure((mu.Block("scalar"), mu.Block("scalar"))))
    t_comp = time.perf_counter() - t0
    ref = real_plus_complex(me, W, Zt, V, 4001)
    ref = np.where(ref > 3.9, np.inf, ref)
    return _stats("mixed", real, comp, ref, t_real, t_comp, n)


def run() -> dict[str, Any]:
    """All three parts; prints the markdown table of the three-mass fault counts."""
    out: dict[str, Any] = {}
    lines = ["| trial | V (m) | fault points real m1 | fault points complex m1 |",
             "|---|---|---|---|"]
    t0 = time.perf_counter()
    for V in NOISE_LEVELS_M:
        for name, (nr, nc) in three_mass_counts(V).items():
            lines.append(f"| {name} | {V:g} | {nr} / {N_FREQ} | {nc} / {N_FREQ} |")
            out[f"three_mass_{name.split(' (')[0].replace(' ', '')}_V{V:g}_real_vs_complex"] = (
                f"{nr} vs {nc}")
    out["three_mass_seconds"] = time.perf_counter() - t0
    print("\n".join(lines))
    out["three_mass_table"] = {"markdown": "\n".join(lines)}
    out.update(siso_gap())
    out.update(mixed_gap())
    return out


if __name__ == "__main__":
    for k, v in run().items():
        if isinstance(v, dict):
            continue
        print(f"  {k:45s} {v:.4g}" if isinstance(v, float) else f"  {k:45s} {v}")
