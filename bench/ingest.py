"""Ingest throughput and memory (issue 33): ``python -m bench.ingest``.

1. Samples per second ingested on one core: a 4-channel record (force, two probes, keyphasor at
   1000 rpm) at 25.6 kHz, 20 steps 30-600 Hz of about 1 s each, analysed in memory and from an HDF5
   file, with the step table and with the steps found in the force (best of 7). Goal >= 20 million
   samples/s/core.
2. Memory: an HDF5 record larger than the memory budget (written step by step, never held whole)
   is ingested in a child process; its peak RSS (``resource.getrusage(RUSAGE_CHILDREN)``) against a
   child that ingests a small file shows that the reading is bounded (chunks of
   ``analysis.CHUNK_SAMPLES`` samples per step).

Not part of the test suite.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

FS = 25600.0
SPEED = 1000.0
BUDGET_MB = 128.0


def _step_signals(f: float, t: np.ndarray, t0: float, rng: np.random.Generator) -> np.ndarray:
    """(4, n) force (N), two probes (V) and the keyphasor (V) of one step."""
    w = 2 * np.pi * f
    tau = t - t0
    h = 1e-5 / (1 - (f / 80.0) ** 2 + 0.1j * f / 80.0)
    u = 10.0 * np.cos(w * tau)
    y1 = np.real(10.0 * h * np.exp(1j * w * tau)) + 1e-6 * np.cos(2 * np.pi * SPEED / 60 * t)
    y2 = 0.3 * y1
    frac = np.mod(SPEED / 60 * t, 1.0)
    kp = 5.0 * (frac < 0.1)
    noise = 2e-7 * rng.standard_normal((2, t.size))
    return np.stack([u, 7874.0 * (y1 + noise[0]) + 0.5, 7874.0 * (y2 + noise[1]) + 0.5, kp])


def write_h5(path: Path, freqs: np.ndarray, periods: np.ndarray, settle: int = 16) -> list[dict]:
    """Write the record step by step into resizable HDF5 datasets; returns the step table."""
    import h5py

    rng = np.random.default_rng(0)
    names = ("force", "p6x", "p2x", "keyphasor")
    steps, t_start = [], 0.0
    with h5py.File(path, "w") as h5:
        h5.attrs["sample_rate_hz"] = FS
        ds = [h5.create_dataset(n, shape=(0,), maxshape=(None,), chunks=(1 << 16,), dtype="f8") for n in names]
        n_done = 0
        for f, n in zip(freqs, periods):
            t_end = t_start + (settle + int(n)) / f
            m = int(np.ceil(t_end * FS)) - n_done
            for s in range(0, m, 1 << 20):
                k = min(1 << 20, m - s)
                t = (n_done + s + np.arange(k)) / FS
                sig = _step_signals(float(f), t, t_start, rng)
                for d, row in zip(ds, sig):
                    d.resize((n_done + s + k,))
                    d[n_done + s :] = row
            n_done += m
            steps.append({"frequency_hz": float(f), "start_s": float(t_start), "end_s": float(t_end)})
            t_start = t_end
    return steps


def channel_map(steps: list[dict] | None) -> dict:
    doc = {"rig_id": "crack_rig", "run_id": "bench", "force": {"channel": "force", "station": 8, "direction": "x"},
           "probes": [{"channel": "p6x", "station": 6, "direction": "x", "unit": "V", "sensitivity_v_per_m": 7874.0},
                      {"channel": "p2x", "station": 2, "direction": "x", "unit": "V", "sensitivity_v_per_m": 7874.0}],
           "keyphasor": {"channel": "keyphasor"}, "analysis": {"settle_periods": 16}}
    if steps is not None:
        doc["steps"] = steps
    return doc


def _child(path: str, map_path: str) -> None:
    from rotorcheck.ingest import ingest_files

    t = time.perf_counter()
    res = ingest_files([path], map_path)
    dt = time.perf_counter() - t
    print(f"{res.summary['n_steps']} {dt}")


def throughput(tmp: Path) -> list[tuple[str, float, float]]:
    from rotorcheck.ingest import analyse, parse_channel_map, read_records

    freqs = np.linspace(30.0, 600.0, 20)
    periods = np.maximum(64, np.round(freqs * 1.0)).astype(int)  # ~1 s per step
    path = tmp / "rec.h5"
    steps = write_h5(path, freqs, periods)
    rows = []
    for label, table in (("step table", steps), ("steps found", None)):
        cmap = parse_channel_map(channel_map(table))
        segs = read_records([path], cmap)
        n = 4 * segs[0].n_samples
        mem = segs[0].__class__(segs[0].path, segs[0].fs_hz, segs[0].t0_s,
                                {k: np.asarray(v[:]) for k, v in segs[0].channels.items()})
        # from the file (h5py reads per step), and in memory (the reading excluded): best of 7
        for where, recs in (("HDF5 file", segs), ("in memory", [mem])):
            best = np.inf
            for _ in range(7):
                t = time.perf_counter()
                analyse(recs, cmap)
                best = min(best, time.perf_counter() - t)
            rows.append((f"{where}, {label}", n, best))
        segs[0].close()
    return rows


def memory(tmp: Path, samples: int) -> tuple[float, float, float]:
    """(file MB, peak RSS MB of the big ingest, of a small ingest)."""
    res = {}
    for tag, n_samp in (("small", 200_000), ("big", samples)):
        freqs = np.linspace(30.0, 600.0, 40)
        dur = n_samp / FS / freqs.size
        periods = np.maximum(8, (dur * freqs).astype(int) - 16)
        path = tmp / f"{tag}.h5"
        steps = write_h5(path, freqs, periods)
        mp = tmp / f"{tag}.yaml"
        mp.write_text(yaml.safe_dump(channel_map(steps)))
        code = "import sys; from bench.ingest import _child; _child(sys.argv[1], sys.argv[2])"
        proc = subprocess.run([sys.executable, "-c", code, str(path), str(mp)], capture_output=True, text=True,
                              env={**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}, check=True)
        del proc
        peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0  # max over children so far
        res[tag] = (path.stat().st_size / 1e6, peak)
    return res["big"][0], res["big"][1], res["small"][1]


def run(samples: int = 10_000_000) -> dict[str, float]:
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        print(f"{'case':34s} {'samples':>12s} {'s':>8s} {'Msamples/s':>11s}")
        for label, n, dt in throughput(tmp):
            print(f"{label:34s} {n:12d} {dt:8.3f} {n / dt / 1e6:11.1f}")
            out[f"Msamples/s {label}"] = n / dt / 1e6
        size, big, small = memory(tmp, samples)
        print(f"\nmemory: {size:.0f} MB HDF5 record (budget {BUDGET_MB:.0f} MB): peak RSS {big:.0f} MB, "
              f"a 6 MB record {small:.0f} MB: the big file costs {big - small:.0f} MB more "
              f"({'within' if big - small < BUDGET_MB else 'OVER'} the budget)")
        out.update({"file MB": size, "peak RSS MB": big, "small-file peak RSS MB": small})
    return out


if __name__ == "__main__":
    run(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000_000)
