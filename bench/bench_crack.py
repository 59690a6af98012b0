"""Benchmark of the breathing-crack plant: harmonic-balance sweep vs time integration.

The rig (``configs/crack_rig_truth.yaml``, Mayes-Davies breathing crack in element 4) at 1000 rpm,
force in at station 8, displacement out at station 6, 262 points 30-600 Hz (the chapter V sweep).

- ``hb_sweep_median_s``: one vectorized harmonic-balance sweep (H = 8, tones k = -8..8) of all 262
  points, median over ``repeat`` runs, including the per-speed setup (receptance factorization);
- ``hb_call_median_s``: one plant call per point (how the sweep simulator uses it), median;
- ``ti_point_median_s``: time integration of one point (Magnus-4, 512 steps per revolution, from
  rest to steady state, then the 64-period lock-in with 64 samples per period), median over
  ``ti_points`` frequencies of the same run;
- ``ratio_ti_over_hb_per_point``: ``ti_point_median_s / (hb_sweep_median_s / 262)``;
- ``max_rel_diff_hb_vs_ti``: the largest difference of the two lock-in phasors on those points.

``python bench/bench_crack.py`` prints the dict as JSON.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench.timing import median_time
from rotorcheck.config import load_config
from rotorcheck.faults.crack import crack_stiffness
from rotorcheck.faults.harmonic_balance import cracked_tones
from rotorcheck.fe.assembly import build_system
from rotorcheck.signal.lockin import tone_lockin
from rotorcheck.sim.time_sim import steady_state_lockin

RIG = Path(__file__).resolve().parents[1] / "configs" / "crack_rig_truth.yaml"
SPEED_RPM = 1000.0
FREQ_HZ = np.linspace(30.0, 600.0, 262)


def run(repeat: int = 20, ti_points: int = 3, n_harmonics: int = 8) -> dict[str, Any]:
    """Median times (s) and the HB/TI ratio on the rig (see the module docstring)."""
    cfg = load_config(RIG)
    system = build_system(cfg)
    crack = crack_stiffness(system, cfg.faults["breathing_crack"])
    ind = system.port_dof(cfg.ports.actuator)
    out = system.port_dof(cfg.ports.sensor)

    def sweep() -> Any:
        return cracked_tones(system, crack, SPEED_RPM, ind, out, n_harmonics).sweep(FREQ_HZ)

    t_sweep = median_time(sweep, repeat)
    plant = cracked_tones(system, crack, SPEED_RPM, ind, out, n_harmonics)
    t_call = median_time(lambda: [plant(f) for f in FREQ_HZ[::13]], 3) / FREQ_HZ[::13].size
    res = plant.sweep(FREQ_HZ)
    idx = np.linspace(0, FREQ_HZ.size - 1, ti_points).round().astype(int)
    ti_times, diffs = [], []
    for i in idx:
        f = float(FREQ_HZ[i])
        t0 = time.perf_counter()
        ti = steady_state_lockin(system, crack, SPEED_RPM, f, ind, [out])
        ti_times.append(time.perf_counter() - t0)
        ref = tone_lockin(res.tones_hz[i], res.out[i, :, :, 0], f, ti.t_start, 64, 64).mean(0)
        diffs.append(float(abs(ti.phasor[0] - ref[0]) / abs(ref[0])))
    t_ti = float(np.median(ti_times))
    per_point = t_sweep / FREQ_HZ.size
    return {
        "rig": RIG.name,
        "speed_rpm": SPEED_RPM,
        "n_points": int(FREQ_HZ.size),
        "n_harmonics": n_harmonics,
        "receptance_method": plant.solver.rec.method,
        "hb_sweep_median_s": t_sweep,
        "hb_per_point_s": per_point,
        "hb_call_median_s": t_call,
        "ti_points_hz": [float(FREQ_HZ[i]) for i in idx],
        "ti_point_times_s": ti_times,
        "ti_point_median_s": t_ti,
        "ratio_ti_over_hb_per_point": t_ti / per_point,
        "max_rel_diff_hb_vs_ti": max(diffs),
        "repeat": repeat,
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
