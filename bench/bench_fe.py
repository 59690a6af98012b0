"""Benchmark of the FE layer: rig assembly from the config plus the io FRF at 262 frequencies.

``run()`` returns a dict of median times (s, over ``repeat`` >= 20 runs) and ratios; ``python -m
bench.bench_fe`` (or ``python bench/bench_fe.py``) prints it. The engine's methods
(:mod:`rotorcheck.fe.frf`) are timed in the same run: ``auto`` (what the product uses), ``direct``
(chunked per-frequency solves of the needed columns), ``modal`` (state-space eigendecomposition,
modal superposition), and a naive per-frequency loop inverting Z(w) (the baseline). Mesh scaling
and the commands on a refined mesh are in bench/bench_engine.py.

These are 40 x 40 (80 x 80 state) matrices: threaded BLAS gains nothing and, on a busy machine, its
threads can stall; ``OPENBLAS_NUM_THREADS=1`` gives the stable numbers.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bench.timing import median_time
from rotorcheck.config import load_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import receptance
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem

RIG = Path(__file__).resolve().parents[1] / "configs" / "crack_rig.yaml"
SPEED_RPM = 1000.0
FREQ_HZ = np.linspace(30.0, 600.0, 262)


def naive_receptance(
    system: MechanicalSystem, freq_hz: np.ndarray, speed_rpm: float, o: int, i: int
) -> np.ndarray:
    """Baseline: a Python loop over frequencies, full inverse of Z(w) at each."""
    M, C, G, K = system.matrices(speed_rpm)
    D = C + speed_rpm * RPM_TO_RAD_S * G
    out = np.empty(freq_hz.size, dtype=complex)
    for k, f in enumerate(freq_hz):
        w = 2 * np.pi * f
        out[k] = np.linalg.inv(K - w**2 * M + 1j * w * D)[o, i]
    return out


def run(repeat: int = 25) -> dict[str, Any]:
    """Median timings (s) and speed-up ratios; see the module docstring."""
    repeat = max(int(repeat), 20)
    config = load_config(RIG)
    probe = build_system(config)
    o, i = probe.port_dof(config.ports.sensor), probe.port_dof(config.ports.actuator)

    def end_to_end(method: str) -> Callable[[], Any]:
        def go() -> Any:
            s = build_system(config)
            if method == "naive":
                return naive_receptance(s, FREQ_HZ, SPEED_RPM, o, i)
            return receptance(s, FREQ_HZ, SPEED_RPM, o, i, method=method)  # type: ignore[arg-type]

        return go

    def frf_only(method: str) -> Callable[[], Any]:
        s = build_system(config)
        s.matrices(SPEED_RPM)  # warm the per-speed cache: time the FRF engine alone
        if method == "naive":
            return lambda: naive_receptance(s, FREQ_HZ, SPEED_RPM, o, i)
        return lambda: receptance(s, FREQ_HZ, SPEED_RPM, o, i, method=method)  # type: ignore[arg-type]

    res: dict[str, Any] = {
        "rig": str(RIG.name),
        "n_dof": probe.n_dof,
        "n_freq": int(FREQ_HZ.size),
        "speed_rpm": SPEED_RPM,
        "repeat": repeat,
        "openblas_num_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default"),
        "cpu_count": os.cpu_count(),
        "load_yaml_s": median_time(lambda: load_config(RIG), repeat),
        "assembly_s": median_time(lambda: build_system(config).matrices(SPEED_RPM), repeat),
    }
    for method in ("auto", "direct", "modal", "naive"):
        res[f"assembly_plus_frf_{method}_s"] = median_time(end_to_end(method), repeat)
        res[f"frf_only_{method}_s"] = median_time(frf_only(method), repeat)
    res["ratio_direct_over_modal"] = res["frf_only_direct_s"] / res["frf_only_modal_s"]
    res["ratio_naive_over_direct"] = res["frf_only_naive_s"] / res["frf_only_direct_s"]
    res["ratio_naive_over_modal"] = res["frf_only_naive_s"] / res["frf_only_modal_s"]
    ref = naive_receptance(probe, FREQ_HZ, SPEED_RPM, o, i)
    for method in ("direct", "modal"):
        h = receptance(probe, FREQ_HZ, SPEED_RPM, o, i, method=method)[:, 0, 0]  # type: ignore[arg-type]
        res[f"max_rel_diff_{method}_vs_naive"] = float(np.max(np.abs(h - ref)) / np.max(np.abs(ref)))
    return res


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
