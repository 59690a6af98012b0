"""Summary of a sweep for ``rotorcheck info`` (JSON-serialisable dict).

Noise estimate per run and output channel from ``output_var`` (variance of the mean output
phasor, m^2). The averaged noise ``v`` is circular complex Gaussian with ``E|v|^2 = var``, so
``P(|v| <= sqrt(var) sqrt(-ln(1-p))) = p``. Over a family of ``n`` points (Sidak, independent
points) the per-point level ``p = P^(1/n)`` gives a family-wise confidence ``P`` (0.99):

    V = max_k sqrt(var_k) sqrt(-ln(1 - p)),  p = P^(1/n)         (m, ``method.md`` step 2)

Version 2: a run of several excitation patterns pools the points of all patterns (``f * n_exc``
per output); an FRF-only run has no output noise (those numbers are NaN, ``n_periods_min``/``max``
None) and the summary repeats its ``noise_source`` and the spread of ``sqrt(frf_var)`` (m/N).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rotorcheck.robust.noise import noise_bound_from_variance, noise_bound_pooled
from rotorcheck.signal.harmonics import lockin_resolution_hz, shaft_harmonic_points
from rotorcheck.signal.lockin import SHAFT_ORDERS, remove_shaft_harmonics
from rotorcheck.signal.sidebands import sideband_scan, sideband_statistic
from rotorcheck.sweep.format import Run, Sweep, sweep_schema_version

__all__ = ["sidak_noise_bound", "summarize"]


def sidak_noise_bound(output_var: np.ndarray, confidence: float = 0.99) -> float:
    """``V = max sqrt(var) sqrt(-ln(1 - p))`` with ``p = confidence^(1/n)``, n = var.size (m)."""
    var = np.asarray(output_var, dtype=np.float64).reshape(-1)
    if var.size == 0:
        raise ValueError("no points")
    return noise_bound_from_variance(var, confidence, family="sidak").value_m


def _noise(var: np.ndarray, confidence: float) -> dict[str, Any]:
    s = np.sqrt(np.asarray(var, dtype=np.float64))
    return {
        "median_std_m": float(np.median(s)),
        "max_std_m": float(s.max()),
        "sidak_bound_m": sidak_noise_bound(var, confidence),
        "n_points": int(s.size),
    }


def _pooled(sweep: Sweep, run: Run, var: np.ndarray, confidence: float) -> dict[str, Any]:
    """The pooled bound (``fit-noise``'s default) of the stored variances and, for a rotating run
    with per-period phasors, after fitting the shaft harmonics 1X..4X out of each output channel
    (per pattern, the input column being the pattern's most driven input; rows of ``var`` are the
    points ``k n_exc + e``)."""
    assert run.n_periods_exc is not None
    n_min = int(np.min(run.n_periods_exc))
    pooled = noise_bound_pooled(var, confidence, n_periods=n_min)
    out: dict[str, Any] = {"pooled_bound_m": pooled.value_m,
                           "excess_scatter_points": len(pooled.details["excess_scatter_index"])}
    if run.period_phasor_exc is not None and run.speed_rpm != 0.0:
        assert run.input_phasor_exc is not None
        in_cols = [i for i, c in enumerate(sweep.channels) if c.role == "input"]
        out_cols = [i for i, c in enumerate(sweep.channels) if c.role == "output"]
        ne = run.n_exc
        cleaned = np.empty_like(var).reshape(-1, ne, var.shape[1])
        for e in range(ne):
            drive = 0 if ne == 1 else int(np.argmax(np.abs(run.input_phasor_exc[:, e, :]).sum(axis=0)))
            for o, col in enumerate(out_cols):
                _, _, cleaned[:, e, o], _ = remove_shaft_harmonics(
                    run.period_phasor_exc[:, e], run.n_periods_exc[:, e], run.frequency,
                    abs(run.speed_rpm) / 60.0, in_cols[drive], col)
        clean = noise_bound_pooled(cleaned.reshape(var.shape), confidence, n_periods=n_min)
        out["pooled_bound_harmonics_removed_m"] = clean.value_m
        out["excess_scatter_points_harmonics_removed"] = len(clean.details["excess_scatter_index"])
        out["shaft_orders_removed"] = SHAFT_ORDERS
    return out


def _frf_only_noise(sweep: Sweep, run: Run, confidence: float) -> dict[str, Any]:
    """The noise entry of an FRF-only run: no output variance (NaN), the frf_var spread if known."""
    nan = float("nan")
    empty = {"median_std_m": nan, "max_std_m": nan, "sidak_bound_m": nan, "n_points": 0}
    out: dict[str, Any] = {
        "confidence": confidence,
        "all_outputs": dict(empty),
        "per_output": {ch.name: dict(empty) for ch in sweep.outputs},
        "pooled_bound_m": nan,
        "excess_scatter_points": 0,
        "noise_source": run.noise_source,
    }
    if run.frf_var is not None:
        sd = np.sqrt(np.asarray(run.frf_var, dtype=np.float64))
        out["frf_std_m_per_n"] = {"median": float(np.median(sd)), "max": float(sd.max()),
                                  "n_points": int(sd.size)}
    return out


#: what ``info`` says the flagged points will be kept out of
HARMONICS_KEPT_OUT = "every certified claim of validate, detect and locate"


def _harmonics(run: Run) -> dict[str, Any]:
    """The run's points on a shaft harmonic (:mod:`rotorcheck.signal.harmonics`): records and the warning."""
    n = None if run.n_periods_exc is None else np.min(np.asarray(run.n_periods_exc), axis=1)
    res, assumed = lockin_resolution_hz(run.frequency, n)
    h = shaft_harmonic_points(run.frequency, float(run.speed_rpm), res, assumed_periods=assumed)
    return {"shaft_harmonic_points": h.points(), "shaft_harmonics_warning": h.warning(HARMONICS_KEPT_OUT)}


def _sidebands(run: Run) -> dict[str, Any] | None:
    """The run's sidebands (version 3): orders, separable tones, and the scan's p-value against a time-invariant
    rotor (:func:`rotorcheck.signal.sidebands.sideband_scan`); None without sidebands."""
    sb = run.sideband_frf()
    if sb is None:
        return None
    orders = [int(k) for k in np.asarray(run.sideband_order)]
    scan = sideband_scan(*sideband_statistic(sb[0], sb[1], np.asarray(run.frequency), abs(float(run.speed_rpm)) / 60.0,
                                             orders, np.min(np.asarray(run.n_periods_exc), axis=1)))
    total = int(np.size(sb[0]))
    return {"orders": orders, "n_tones": scan.n_tones,
            "n_not_separable": total - scan.n_tones, "scan_p_value": scan.p_value}


def summarize(sweep: Sweep, confidence: float = 0.99) -> dict[str, Any]:
    """Runs, speeds, grids, channels and noise estimates of a (validated) sweep.

    Per run: grid (min/max Hz, n), ``n_periods`` range, and ``noise``: per output channel and over
    all outputs together (family of ``f * n_out`` points) the median and max ``sqrt(output_var)``
    and the Sidak family-wise bound at ``confidence``; ``n_exc`` (patterns per frequency, None for
    an FRF-only run), ``frf_only`` and ``noise_source``; ``shaft_harmonic_points`` (the points within the
    lock-in's resolution of 1X..4X, :mod:`rotorcheck.signal.harmonics`) and ``shaft_harmonics_warning`` ('' when
    none); ``sidebands`` (version 3: orders, ``n_tones``, ``n_not_separable``, ``scan_p_value``; None without).
    ``shared_grid`` tells whether all runs share the frequency grid bit for bit; ``schema_version`` is the version
    the sweep is (or would be) written in.
    """
    runs = []
    grids = []
    for run in sweep.runs.values():
        f = np.asarray(run.frequency, dtype=np.float64)
        grids.append(f)
        entry: dict[str, Any] = {
            "run_id": run.run_id,
            "speed_rpm": float(run.speed_rpm),
            "grid": {"min_hz": float(f.min()), "max_hz": float(f.max()), "n": int(f.size)},
        }
        if run.is_frf_only:
            entry.update({
                "n_periods_min": None,
                "n_periods_max": None,
                "has_period_phasor": False,
                "notes": run.notes,
                "noise": _frf_only_noise(sweep, run, confidence),
            })
        else:
            assert run.output_var_exc is not None and run.n_periods_exc is not None
            v3 = np.asarray(run.output_var_exc, dtype=np.float64)
            var = v3.reshape(-1, v3.shape[2])  # (f n_exc, n_out), row k n_exc + e
            per_chan = {ch.name: _noise(var[:, o], confidence) for o, ch in enumerate(sweep.outputs)}
            entry.update({
                "n_periods_min": int(np.min(run.n_periods_exc)),
                "n_periods_max": int(np.max(run.n_periods_exc)),
                "has_period_phasor": run.period_phasor_exc is not None,
                "notes": run.notes,
                "noise": {
                    "confidence": confidence,
                    "all_outputs": _noise(var, confidence),
                    "per_output": per_chan,
                    **_pooled(sweep, run, var, confidence),
                },
            })
        entry.update({"n_exc": run.n_exc if not run.is_frf_only else None,
                      "frf_only": run.is_frf_only,
                      "noise_source": run.noise_source, **_harmonics(run), "sidebands": _sidebands(run)})
        runs.append(entry)
    shared = all(g.shape == grids[0].shape and np.array_equal(g, grids[0]) for g in grids)
    all_f = np.concatenate(grids)
    return {
        "schema_version": sweep_schema_version(sweep),
        "rig_id": sweep.rig_id,
        "source": sweep.source,
        "generator": sweep.generator,
        "created_utc": sweep.created_utc,
        "n_runs": len(runs),
        "speeds_rpm": sorted({float(r.speed_rpm) for r in sweep.runs.values()}),
        "grid": {
            "min_hz": float(all_f.min()),
            "max_hz": float(all_f.max()),
            "n": int(grids[0].size) if shared else None,
        },
        "shared_grid": bool(shared),
        "channels": [
            {
                "name": c.name,
                "role": c.role,
                "node": int(c.node),
                "direction": c.direction,
                "quantity": c.quantity,
                "unit": c.unit,
            }
            for c in sweep.channels
        ],
        "runs": runs,
    }
