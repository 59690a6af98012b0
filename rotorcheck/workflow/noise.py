"""Step 2: the noise bound V (m) from a healthy run, and the per-point noise values the later steps use."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.baseline import Baseline, NoiseFit, Provenance, read_baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError
from rotorcheck.report.schema import NoiseReport
from rotorcheck.robust import noise
from rotorcheck.robust.noise import NoiseBound, noise_bound_per_point
from rotorcheck.workflow.measured import MeasuredRun, variance_dof

NOISE_METHODS = ("pooled", "per-point", "max", "floor", "manual")


def fit_noise(
    run: MeasuredRun, method: str = "pooled", confidence: float = 0.99, manual_m: float | None = None
) -> NoiseBound:
    """Step 2: the noise bound V (m, uniform in frequency) from a healthy run.

    ``pooled`` (default): the noise level pooled over the points (median of the per-point variance
    of the mean, which synchronous-disturbance leaks near kX cannot inflate), then V at
    ``confidence`` family-wise over the points (Sidak), complex circular Gaussian; points whose
    scatter is far above the pool (F test at the same family-wise level) are listed in
    ``details["excess_scatter_hz"]``. ``max``: the largest per-point bound (conservative).
    ``floor``: the dissertation's noise floor (scatter of the data around a smooth local fit).
    ``manual``: ``manual_m`` as given. ``per-point``: V(w) per point from each point's own variance
    and degrees of freedom (F quantile; ``details["per_point_m"]``), used per frequency by
    validate/detect with ``--enclose system|data`` (detect then takes the new sweep's own V(w)).
    """

    if method == "manual":
        if manual_m is None or not np.isfinite(manual_m) or manual_m < 0:
            raise InputError(None, "--value", "a manual noise bound needs a finite value >= 0 (m)")
        return noise.noise_bound_manual(float(manual_m))
    if method == "per-point":
        return noise.noise_bound_per_point(run.output_var, variance_dof(run), confidence)
    if method == "max":
        nb = noise.noise_bound_from_variance(run.output_var, confidence, n_periods=int(np.min(run.n_periods)))
    elif method == "pooled":
        nb = noise.noise_bound_pooled(run.output_var, confidence, n_periods=int(np.min(run.n_periods)))
        excess = np.asarray(nb.details.get("excess_scatter_index", []), dtype=int)
        nb.details["excess_scatter_hz"] = [float(x) for x in run.frequency_hz[excess]]
    elif method == "floor":
        nb = noise.noise_bound_from_floor(run.Zt, run.frequency_hz, confidence=confidence)
    else:
        raise InputError(None, "--method", f"unknown noise method {method!r} (one of {', '.join(NOISE_METHODS)})")
    return nb


def noise_baseline(rig: RigConfig, run: MeasuredRun, noise_bound: NoiseBound) -> Baseline:
    """The baseline after step 2 (stage 'noise'): the noise bound and where it came from."""

    return Baseline(Provenance(rig.rig_id, rig.sha256(), [run.sha256], run.run_id, run.speed_rpm),
                    noise_fit(noise_bound, rig.uncertainty.structure, rig.uncertainty.parameter or ""))


def noise_fit(noise_bound: NoiseBound, uncertainty: str, parameter: str, per_point_m: np.ndarray | None = None
              ) -> NoiseFit:
    """The baseline's noise part from a fitted bound (``per_point_m``: V per point when the caller has it;
    else the bound's own per-point values, if any)."""
    per = per_point_m if per_point_m is not None else noise_bound.details.get("per_point_m")
    return NoiseFit(float(noise_bound.value_m), noise_bound.method, float(noise_bound.confidence or 0.0),
                    None if per is None else np.asarray(per, dtype=float), uncertainty, parameter)


def prior_noise(baseline_path: str | Path, rig: RigConfig, force: bool, sweep_sha256: str | None = None,
                reuse: bool = False) -> NoiseBound | None:
    """The noise bound of an existing baseline at ``baseline_path`` to validate with (None: fit anew).

    A stage-'noise' baseline (``fit-noise``) gives its bound. A validated one is refused unless ``force``
    (it would be overwritten); with ``force`` a manual bound (``fit-noise --method manual``) survives, a
    fitted one is fitted anew. A bound fitted on another sweep than ``sweep_sha256`` is refused unless
    ``reuse`` (then ``details["fitted_on_sweep"]`` names that sweep, for the caller to record); a noise fit
    made for another rig description is refused (InputError naming the field). ``details["run_id"]``: the
    run the bound was fitted on.
    """

    path = Path(baseline_path)
    if not path.exists():
        return None
    prior = read_baseline(path)
    if prior.validated:
        if not force:
            raise InputError(path, "", "a validated baseline exists; refusing to overwrite (use --force)")
        if prior.noise_method != "manual":
            return None
    if prior.rig_sha256 != rig.sha256():
        raise InputError(path, "/@rig_sha256", "the noise fit was made for another rig description")
    fitted_on = [s for s in prior.sweep_sha256 if s]
    if (prior.noise_method != "manual" and sweep_sha256 and fitted_on and sweep_sha256 not in fitted_on
            and not reuse):
        raise InputError(path, "/@sweep_sha256", f"the noise bound was fitted on another sweep (sha256 "
                         f"{fitted_on[0][:12]}, this one {sweep_sha256[:12]}): run fit-noise on this sweep, or "
                         "pass --reuse-noise to validate with it (recorded in the baseline)")
    per = prior.noise_bound_per_point_m
    details: dict[str, Any] = {"run_id": prior.run_id}
    if per is not None:
        details["per_point_m"] = per
    if prior.noise_method != "manual" and sweep_sha256 and fitted_on and sweep_sha256 not in fitted_on:
        details["fitted_on_sweep"] = fitted_on[0]  # reused as asked (reuse): the caller records it
    return NoiseBound(prior.noise_bound_m, prior.noise_method, prior.noise_confidence, details)


def noise_report(noise_bound: NoiseBound, sweep: str | Path, baseline_path: str | Path) -> NoiseReport:
    """``fit-noise --json`` as a :class:`rotorcheck.report.schema.NoiseReport`."""

    return NoiseReport(noise_bound.value_m, noise_bound.method, noise_bound.confidence, str(sweep),
                       str(baseline_path), noise_bound.details)


def noise_values(noise_bound: NoiseBound, run: MeasuredRun | None = None) -> float | np.ndarray:
    """V (m) as the validation/detection LMIs take it: uniform, or per point for a 'per-point' bound
    (recomputed from ``run``'s own variances at the same confidence when a run is given)."""
    per = noise_bound.details.get("per_point_m") if noise_bound.details else None
    if noise_bound.method != "per-point" or per is None:
        return float(noise_bound.value_m)
    if run is None:
        return np.asarray(per, dtype=float)
    return _own_v(run, float(noise_bound.confidence or 0.0))


def _own_v(run: MeasuredRun, confidence: float) -> np.ndarray:
    """The run's own per-point noise bound V(w) (m) at ``confidence`` family-wise."""

    return np.asarray(noise_bound_per_point(run.output_var, variance_dof(run), confidence).details["per_point_m"],
                      dtype=float)


def baseline_noise_values(baseline: Baseline, run: MeasuredRun) -> float | np.ndarray:
    """The noise bound for new data against ``baseline``: uniform, or the new run's own V(w)."""
    if baseline.noise_bound_per_point_m is None:
        return float(baseline.noise_bound_m)
    return _own_v(run, float(baseline.noise_confidence))


def frf_noise_radius(run: MeasuredRun, confidence: float = 0.99) -> np.ndarray:
    """The run's own noise bound as a receptance radius (f,), m/N: V(w) / |W(w)|."""
    return _own_v(run, confidence) / np.abs(run.W)

