"""Benchmark of the receptance engine (rotorcheck.fe.frf) and of the commands on a refined mesh.

(a) ``frf_*``: the crack rig's nominal plant at 262 points (30-600 Hz, 1000 rpm; receptances at
    [damage port, sensor] for [damage port, actuator]) as the product computes it
    (:func:`rotorcheck.nominal.nominal_model`), against a per-frequency dense solve of the same
    columns in the same run (timed in turn), on every mesh 9 ... 576 elements (``frf_rows``; the
    dense baseline on a 16-point subset above 72 elements, scaled to 262), the product time fitted
    as a power law in the element count; median times (s), the ratio, the largest relative
    difference. The published rig also at 0 rpm, with the assembly, and the floor of its path: one
    eigensolution of the (half-size complex / full real) state matrix.
(b) ``scaling``: the same engine call (factorisation + 262 points) on the rig with every element
    split into 1, 2, 4, ... 64 (9 ... 576 elements), with its peak traced memory, fitted as a power
    law ``t = a N^p`` in the element count N; and the nominal plant of the 576-element mesh on 262
    and on 3,081 points (time, peak traced memory).
(c) ``cli_*``: ``rotorcheck model --speed 1000`` and ``rotorcheck validate`` (after ``fit-noise``)
    of the bundled healthy 1000 rpm sweep on the 576-element mesh (and the 9-element rig in the
    same run), each a fresh process as a user runs it: wall time and peak RSS (``os.wait4``).
(d) ``hb_sweep_*``, ``modal_factor_*``: the harmonic-balance sweep of the cracked rig (262 points,
    H = 8) and the engine's modal factorisation of the 18-element rig with BLAS limited to one thread
    (as the product runs them) and with the BLAS default, in the same run, with the load average
    (the difference depends on what else runs on the machine).

``python -m bench.bench_engine`` prints the dict as JSON; ``python -m bench.bench_engine frf`` only (a).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from bench.timing import median_time
from rotorcheck.config import RigConfig, load_config
from rotorcheck.faults.crack import crack_stiffness
from rotorcheck.faults.harmonic_balance import HBSolver
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.blas import one_blas_thread
from rotorcheck.fe.frf import _isotropic_half, _modal_state, _scaled_modal_factors, system_receptance
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.nominal import nominal_model

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "configs" / "crack_rig.yaml"
TRUTH = ROOT / "configs" / "crack_rig_truth.yaml"
SWEEP = ROOT / "data_samples" / "crack_rig" / "healthy_1000rpm.h5"
SPEED_RPM = 1000.0
FREQ_HZ = np.linspace(30.0, 600.0, 262)
REFINE = (1, 2, 4, 8, 16, 32, 64)


def _paired(fns: Sequence[Callable[[], Any]], repeat: int) -> list[float]:
    """Median times of several functions run in turn (a, b, c, a, b, c, ...): a change of the
    machine's load during the run affects all of them alike."""
    for fn in fns:
        fn()  # warm-up
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for fn, ts in zip(fns, times):
            t0 = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t0)
    return [float(np.median(ts)) for ts in times]


def refined(config: RigConfig, refine: int) -> RigConfig:
    """The rig with every shaft element split into ``refine`` (the config's own ``refine`` option)."""
    shaft = [e.model_copy(update={"refine": refine}) for e in config.shaft]
    return config.model_copy(update={"shaft": shaft})


def _ports(config: RigConfig, system: MechanicalSystem) -> tuple[list[int], list[int]]:
    assert config.damage is not None
    d = system.port_dof(config.damage.port)
    return [d, system.port_dof(config.ports.sensor)], [d, system.port_dof(config.ports.actuator)]


def dense_per_frequency(system: MechanicalSystem, freq_hz: np.ndarray, speed_rpm: float,
                        outs: list[int], ins: list[int]) -> np.ndarray:
    """Baseline: at each frequency build Z(w) and solve it densely for the input columns."""
    M, C, G, K = system.matrices(speed_rpm)
    D = C + speed_rpm * RPM_TO_RAD_S * G
    B = np.zeros((system.n_dof, len(ins)))
    B[ins, np.arange(len(ins))] = 1.0
    out = np.empty((freq_hz.size, len(outs), len(ins)), dtype=complex)
    for k, f in enumerate(freq_hz):
        w = 2.0 * np.pi * f
        out[k] = np.linalg.solve(K - w**2 * M + 1j * w * D, B)[outs]
    return out


def _engine(system: MechanicalSystem, outs: list[int], ins: list[int]) -> np.ndarray:
    return system_receptance(system, SPEED_RPM, outs, ins, band_hz=float(FREQ_HZ.max())).at_hz(FREQ_HZ)


def _dense_one_thread(system: MechanicalSystem, freq_hz: np.ndarray, speed_rpm: float,
                      outs: list[int], ins: list[int]) -> np.ndarray:
    with one_blas_thread():
        return dense_per_frequency(system, freq_hz, speed_rpm, outs, ins)


def _max_rel(got: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(got - ref).max(axis=(1, 2)) / np.abs(ref).max(axis=(1, 2))))


#: meshes up to this many elements get the dense baseline on all 262 points; finer ones on an
#: evenly spread subset of DENSE_SUBSET points, its time scaled to 262 (labelled ``_extrapolated``)
DENSE_FULL_UP_TO = 72
DENSE_SUBSET = 16


def frf_ratio(repeat: int) -> dict[str, Any]:
    """(a) the product's nominal plant (:func:`rotorcheck.nominal.nominal_model` on a built system,
    as ``validate`` and ``detect`` compute it) vs per-frequency dense solves, every mesh of REFINE
    (9 ... 576 elements), at 1000 rpm (and 0 rpm for the rig as published). Timed in turn in the
    same loop (:func:`_paired`). The dense baseline is the faster of BLAS default threads and one
    thread (on 2 cores one thread wins below ~100 DOF); 9 elements also with the assembly
    (``nominal_model`` without a built system, as the CLI calls it) and timed back to back as this
    bench did before (warm caches: the interleaved product time is ~0.3 ms longer)."""
    out: dict[str, Any] = {}
    base = load_config(RIG)
    rows = []
    for r in REFINE:
        config = refined(base, r)
        system = build_system(config)
        system.matrices(SPEED_RPM)  # both timings without the assembly
        system.matrices(0.0)
        outs, ins = _ports(config, system)
        n_el = 9 * r
        full = n_el <= DENSE_FULL_UP_TO
        f_dense = FREQ_HZ if full else FREQ_HZ[:: FREQ_HZ.size // DENSE_SUBSET][:DENSE_SUBSET]
        reps = repeat if n_el <= 36 else (3 if n_el <= 72 else 1)

        def prod(c: RigConfig = config, s: MechanicalSystem = system) -> Any:
            return nominal_model(c, FREQ_HZ, SPEED_RPM, system=s)

        def dense(s: MechanicalSystem = system, f: np.ndarray = f_dense, o: list[int] = outs,
                  i: list[int] = ins) -> Any:
            return dense_per_frequency(s, f, SPEED_RPM, o, i)

        def dense1(s: MechanicalSystem = system, f: np.ndarray = f_dense, o: list[int] = outs,
                   i: list[int] = ins) -> Any:
            return _dense_one_thread(s, f, SPEED_RPM, o, i)

        if n_el <= 72:
            t_prod, t_d, t_d1 = _paired([prod, dense, dense1], reps)
        else:
            t_prod, t_d = _paired([prod, dense], reps)
            t_d1 = np.inf
        t_dense = min(t_d, t_d1) * FREQ_HZ.size / f_dense.size
        got = nominal_model(config, FREQ_HZ, SPEED_RPM, system=system).P[:, 1:, 1:]
        ref = dense_per_frequency(system, f_dense, SPEED_RPM, outs, ins)
        sel = np.searchsorted(FREQ_HZ, f_dense)
        row: dict[str, Any] = {
            "elements": n_el, "n_dof": system.n_dof, "product_s": t_prod,
            ("dense_per_frequency_s" if full else "dense_per_frequency_extrapolated_s"): t_dense,
            "dense_points_timed": int(f_dense.size),
            "dense_threads": "one" if t_d1 < t_d else "default",
            "ratio_dense_over_product": t_dense / t_prod,
            "max_rel_diff": _max_rel(got[sel], ref),
        }
        rows.append(row)
        out[f"frf_{n_el}el_ratio_dense_over_product"] = row["ratio_dense_over_product"]
    out["frf_rows"] = rows
    n = np.array([row["elements"] for row in rows], dtype=float)
    t = np.array([row["product_s"] for row in rows])
    out["frf_product_power_law_exponent"] = float(np.polyfit(np.log(n), np.log(t), 1)[0])
    # the rig as published: also at rest, and with the assembly in the timing
    config = base
    system = build_system(config)
    outs, ins = _ports(config, system)
    for rpm in (SPEED_RPM, 0.0):
        system.matrices(rpm)

        def prod0(s: MechanicalSystem = system, w: float = rpm) -> Any:
            return nominal_model(config, FREQ_HZ, w, system=s)

        def cold(w: float = rpm) -> Any:
            return nominal_model(config, FREQ_HZ, w)

        def dense0(s: MechanicalSystem = system, w: float = rpm) -> Any:
            return _dense_one_thread(s, FREQ_HZ, w, outs, ins)

        t_prod, t_cold, t_dense = _paired([prod0, cold, dense0], repeat)
        # as the bench measured before (each back to back, warm): the product after itself runs
        # ~0.3 ms faster than after a dense loop or an idle moment
        t_prod_b2b, t_dense_b2b = median_time(prod0, 3 * repeat), median_time(dense0, repeat)
        tag = f"frf_9el_{int(rpm)}rpm"
        got = nominal_model(config, FREQ_HZ, rpm, system=system).P[:, 1:, 1:]
        out.update({
            f"{tag}_product_s": t_prod,
            f"{tag}_product_with_assembly_s": t_cold,
            f"{tag}_dense_per_frequency_one_thread_s": t_dense,
            f"{tag}_ratio_dense_over_product": t_dense / t_prod,
            f"{tag}_ratio_dense_over_product_with_assembly": t_dense / t_cold,
            f"{tag}_product_back_to_back_s": t_prod_b2b,
            f"{tag}_dense_back_to_back_s": t_dense_b2b,
            f"{tag}_ratio_back_to_back": t_dense_b2b / t_prod_b2b,
            f"{tag}_max_rel_diff": _max_rel(got, dense_per_frequency(system, FREQ_HZ, rpm, outs, ins)),
        })
    # the floor of the product path on the rig: one eigensolution of its state matrix (the
    # isotropic half-size complex one, rotorcheck.fe.frf._isotropic_half, and the full real one)
    M, C, G, K = system.matrices(SPEED_RPM)
    D = C + SPEED_RPM * RPM_TO_RAD_S * G
    half = _isotropic_half((M, D, K), system.plane_pairs())
    assert half is not None

    def eig_half() -> Any:
        with one_blas_thread():
            return _modal_state(*half)

    def eig_full() -> Any:
        with one_blas_thread():
            return _modal_state(M, D, K)

    out["frf_9el_floor_modal_state_half_s"], out["frf_9el_floor_modal_state_full_s"] = _paired(
        [eig_half, eig_full], 5 * repeat)
    return out


def scaling(dense_up_to: int = 0) -> dict[str, Any]:
    """(b) engine time and peak traced memory against the element count; power-law fit (the dense
    baseline of each mesh is in :func:`frf_ratio`; ``dense_up_to`` elements repeat it here)."""
    base = load_config(RIG)
    rows = []
    for r in REFINE:
        config = refined(base, r)
        t0 = time.perf_counter()
        system = build_system(config)
        system.matrices(SPEED_RPM)
        t_asm = time.perf_counter() - t0
        outs, ins = _ports(config, system)
        t0 = time.perf_counter()
        tracemalloc.start()
        H = _engine(system, outs, ins)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        t_frf = time.perf_counter() - t0
        t_frf = min(t_frf, median_time(lambda s=system, o=outs, i=ins: _engine(s, o, i), 2))
        row: dict[str, Any] = {"elements": 9 * r, "n_dof": system.n_dof, "assembly_s": t_asm, "frf_s": t_frf,
                               "frf_peak_traced_mb": peak / 2**20,
                               "dense_stack_would_be_mb": FREQ_HZ.size * system.n_dof**2 * 16 / 2**20}
        if 9 * r <= dense_up_to:
            t0 = time.perf_counter()
            ref = dense_per_frequency(system, FREQ_HZ, SPEED_RPM, outs, ins)
            row["dense_per_frequency_s"] = time.perf_counter() - t0
            row["max_rel_diff_vs_dense"] = float(np.max(np.abs(H - ref).max(axis=(1, 2))
                                                        / np.abs(ref).max(axis=(1, 2))))
        rows.append(row)
    # the nominal plant of the finest mesh on 262 and on 3,081 points: same peak memory
    config = refined(base, REFINE[-1])
    system = build_system(config)
    system.matrices(SPEED_RPM)
    points: dict[str, Any] = {}
    for npts in (262, 3081):
        f = np.linspace(30.0, 600.0, npts)
        tracemalloc.start()
        t0 = time.perf_counter()
        nominal_model(config, f, SPEED_RPM, system=system)
        points[f"nominal_{9 * REFINE[-1]}el_{npts}pts_s"] = time.perf_counter() - t0
        points[f"nominal_{9 * REFINE[-1]}el_{npts}pts_peak_traced_mb"] = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    n = np.array([row["elements"] for row in rows], dtype=float)
    t = np.array([row["frf_s"] for row in rows])
    big = n >= 72  # the reduced path (above rotorcheck.fe.frf.N_FULL DOF)
    p_all, _ = np.polyfit(np.log(n), np.log(t), 1)
    p_big, _ = np.polyfit(np.log(n[big]), np.log(t[big]), 1)
    return {"scaling": rows, "frf_power_law_exponent_all": float(p_all),
            "frf_power_law_exponent_72_to_576": float(p_big), **points}


#: runs ``python -m rotorcheck`` and, at exit, writes the process's peak RSS (``VmHWM`` of
#: /proc/self/status: the peak of this program's own address space; ``getrusage`` of a child would
#: also count the benchmark's memory the child had before ``exec``)
_WRAPPER = """
import atexit, runpy, sys
def _peak(path=sys.argv[1]):
    with open('/proc/self/status') as fh, open(path, 'w') as out:
        out.write(next(l for l in fh if l.startswith('VmHWM')).split()[1])
atexit.register(_peak)
sys.argv = ['rotorcheck', *sys.argv[2:]]
runpy.run_module('rotorcheck', run_name='__main__')
"""


def _cli(args: list[str], cwd: Path) -> tuple[int, float, float]:
    """(exit code, wall s, peak RSS MB) of ``python -m rotorcheck args`` in a fresh process."""
    env = dict(os.environ, MPLBACKEND="Agg")
    peak = cwd / "peak_rss_kb"
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", _WRAPPER, str(peak), *args], cwd=cwd, env=env, check=False,
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    return proc.returncode, wall, float(peak.read_text()) / 1024.0


def commands() -> dict[str, Any]:
    """(c) ``model`` and ``validate`` on the 9- and 576-element meshes, fresh processes."""
    out: dict[str, Any] = {}
    raw = yaml.safe_load(RIG.read_text())
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for r in (1, 64):
            doc = dict(raw, shaft=[dict(e, refine=r) for e in raw["shaft"]])
            rig = work / f"crack_rig_{9 * r}.yaml"
            rig.write_text(yaml.safe_dump(doc))
            tag = f"{9 * r}el"
            rc, wall, rss = _cli(["model", str(rig), "--speed", "1000", "--out", str(work / tag), "--force"], work)
            out[f"cli_model_{tag}_s"], out[f"cli_model_{tag}_peak_rss_mb"], out[f"cli_model_{tag}_rc"] = wall, rss, rc
            rc, wall, rss = _cli(["fit-noise", str(SWEEP), "--rig", str(rig), "--out", str(work / tag), "--force"],
                                 work)
            out[f"cli_fit_noise_{tag}_rc"] = rc
            for plots in (True, False):
                args = ["validate", str(SWEEP), "--rig", str(rig), "--out", str(work / tag), "--force"]
                key = f"cli_validate_{tag}" + ("" if plots else "_no_plots")
                rc, wall, rss = _cli(args + ([] if plots else ["--no-plots"]), work)
                out[f"{key}_s"], out[f"{key}_peak_rss_mb"], out[f"{key}_rc"] = wall, rss, rc
    return out


def blas_threads(repeat: int) -> dict[str, Any]:
    """(d) with one BLAS thread (as the product runs them) and with the BLAS default, same run: the
    HB sweep of the cracked rig and the engine's modal factorisation of the 18-element rig."""
    cfg = load_config(TRUTH)
    system = build_system(cfg)
    crack = crack_stiffness(system, cfg.faults["breathing_crack"])
    ind, out = system.port_dof(cfg.ports.actuator), system.port_dof(cfg.ports.sensor)
    solver = HBSolver(system, crack, SPEED_RPM, ind, [out], 8)
    fine = build_system(refined(load_config(RIG), 2))
    M, C, G, K = fine.matrices(SPEED_RPM)
    D = C + SPEED_RPM * RPM_TO_RAD_S * G
    cols = np.eye(fine.n_dof)[:, :2]

    def factor() -> Any:
        return _scaled_modal_factors(M, D, K, cols)

    def factor_one() -> Any:
        with one_blas_thread():
            return factor()

    return {
        "hb_sweep_one_thread_s": median_time(lambda: solver.solve(FREQ_HZ), repeat),
        "hb_sweep_default_threads_s": median_time(lambda: solver._solve(FREQ_HZ, 64), repeat),
        "modal_factor_18el_one_thread_s": median_time(factor_one, 5 * repeat),
        "modal_factor_18el_default_threads_s": median_time(factor, 5 * repeat),
        "load_average_1min": os.getloadavg()[0],
        "cpu_count": os.cpu_count(),
    }


def run(repeat: int = 15) -> dict[str, Any]:
    """Everything above; see the module docstring."""
    res: dict[str, Any] = {"openblas_num_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default")}
    res.update(frf_ratio(repeat))
    res.update(scaling())
    res.update(commands())
    res.update(blas_threads(max(repeat // 3, 3)))
    return res


if __name__ == "__main__":
    if sys.argv[1:] == ["frf"]:
        print(json.dumps(frf_ratio(15), indent=2))
    else:
        print(json.dumps(run(), indent=2))
