"""Step 3: gamma_h(w) enclosing the healthy runs, the measured healthy FRF, and the baseline to store."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorcheck.baseline import Baseline, DriftModel, HealthyData, ModelBound, Provenance
from rotorcheck.config import RigConfig
from rotorcheck.errors import InputError, check_choice
from rotorcheck.nominal import NominalModel, nominal_model
from rotorcheck.report.schema import ValidationReport
from rotorcheck.robust import validation
from rotorcheck.robust.mu import Structure
from rotorcheck.robust.noise import NoiseBound
from rotorcheck.robust.validation import STATUS_EXCLUDED, ValidationResult
from rotorcheck.signal.harmonics import ShaftHarmonics
from rotorcheck.signal.sidebands import HEALTHY_SIDEBAND_ALPHA, sideband_scan
from rotorcheck.updating import Update, update_parameters
from rotorcheck.variability import benign_parameters
from rotorcheck.workflow.drift import DriftLearning, learn_drift_ranges
from rotorcheck.workflow.measured import (
    MeasuredRun,
    aligned_pairs,
    grid_mismatch,
    healthy_reference,
    pair_experiments,
    pair_keys,
    run_harmonics,
)
from rotorcheck.workflow.noise import noise_fit, noise_values
from rotorcheck.workflow.rigs import speed_tolerance, updated_rig


@dataclass
class ValidationOutcome:
    """What :func:`validate` returns: the baseline to store and the numbers behind it."""

    baseline: Baseline
    result: ValidationResult
    model: NominalModel
    runs: list[MeasuredRun]
    rig: RigConfig
    update: Update | None = None  # validate --update
    learning: DriftLearning | None = None  # validate --learn-drift
    harmonics: ShaftHarmonics | None = None  # points on a shaft harmonic: status 'excluded', in no claim
    healthy_note: str = ""  # how several healthy sweeps made the healthy FRF (workflow.measured.healthy_reference)
    healthy_run: int | None = None  # the run whose FRF is the healthy FRF alone (None: the mean of the runs)

    @property
    def not_enclosed(self) -> np.ndarray:
        """(f,) bool: points where gamma_h could not be verified (unexplainable, solver failure, bad data);
        points excluded (on a shaft harmonic) are not among them."""
        return np.asarray(~np.isin(self.result.status, ["ok", STATUS_EXCLUDED]))

    @property
    def n_not_enclosed(self) -> int:
        """The number of :attr:`not_enclosed` points."""
        return int(np.count_nonzero(self.not_enclosed))

    @property
    def bounded(self) -> np.ndarray:
        """(f,) bool: the points whose gamma_h is part of the model-error bound (status 'ok')."""
        return np.asarray(self.result.status == "ok")

    @property
    def harmonics_warning(self) -> str:
        """The shaft-harmonic warning ('' when no point is flagged)."""
        return "" if self.harmonics is None else self.harmonics.warning(HARMONICS_KEPT_OUT)

    def typed_report(self, noise_bound: NoiseBound, baseline_path: str | Path) -> ValidationReport:
        """``validate --json`` as a :class:`rotorcheck.report.schema.ValidationReport`."""

        res = self.result
        h = self.harmonics
        return ValidationReport(self.runs[0].frequency_hz, res.gamma, res.gamma_lower, [str(x) for x in res.status],
                                float(noise_bound.value_m), noise_bound.method, self.baseline.enclose,
                                self.model.structure, int(res.gamma.size), self.n_not_enclosed, str(baseline_path),
                                h.points() if h is not None and h.n_flagged else None,
                                None if self.learning is None else self.learning.as_dict(self.rig))


#: what validation keeps the points on a shaft harmonic out of (the warning's words)
HARMONICS_KEPT_OUT = "the model-error bound gamma_h and the benign update and learning"


#: Detection modes (``--enclose``): ``measured`` (default: the healthy set centred on the measured
#: healthy FRF, uncertainty = the noise of both sweeps), ``system`` and ``data`` (centred on the
#: nominal model with the model-error bound gamma_h; ``data`` is the dissertation's FDMVOP).
ENCLOSE_MODES = ("measured", "system", "data")


def validate(
    rig: RigConfig,
    runs: list[MeasuredRun],
    noise_bound: NoiseBound,
    enclose: str = "measured",
    fail_at: tuple[int, ...] = (),
    update: bool = False,
    learn_drift: bool | None = None,
) -> ValidationOutcome:
    """Step 3: gamma_h(w) enclosing every healthy run, and the measured healthy FRF with its noise.

    ``enclose``: 'measured' (default; gamma_h as for 'system', detection centred on the healthy
    data), 'system' or 'data' (see :data:`ENCLOSE_MODES`). ``update``: fit the rig's variability
    parameters to the healthy FRF (:mod:`rotorcheck.updating`); the joint test then predicts benign
    change around the updated model (stored in the baseline as ``updated_parameters``).
    ``learn_drift``: learn from the healthy sweeps (>= 3, drifted across the ranges) where the most central one
    sits among the machine's states, and test new sweeps with the ranges moved to the sweeps' centre
    (:mod:`rotorcheck.workflow.drift`); None (default): learned when there are 3 or more sweeps and they differ
    beyond their noise; False: several drifted sweeps keep the ranges about the most central one (the ranges
    read as the change between two sweeps).
    """

    check_choice(enclose, ENCLOSE_MODES, "--enclose")
    if learn_drift and len(runs) < 3:
        raise InputError(None, "--learn-drift", f"needs at least 3 healthy sweeps (got {len(runs)})")
    if learn_drift and enclose != "measured":
        raise InputError(None, "--learn-drift", f"learns the drift the joint test allows: only with --enclose measured "
                         f"(got {enclose})")
    runs = [runs[0]] + [aligned_pairs(r, pair_keys(runs[0])) for r in runs[1:]]  # same pairs, rows reordered
    first = runs[0]
    tol = speed_tolerance(rig)
    for r in runs[1:]:
        why = grid_mismatch(r.frequency_hz, first.frequency_hz)
        if why is not None:
            raise InputError(r.path, f"/runs/{r.run_id}/frequency",
                             f"grid differs from {first.path}: {why} (healthy sweeps must share the frequency grid)")
        if pair_keys(r) != pair_keys(first):
            raise InputError(r.path, "/channels", f"channel pairs differ from {first.path}'s (healthy sweeps must "
                             "share their channels)")
    # measured speeds of one operating point differ by a few rpm: the rig's speed range (variability: speed +-tol)
    # is the drift about the operating point, so two of its sweeps may sit up to 2 tol apart; at rest is exact
    slow, fast = min(runs, key=lambda r: r.speed_rpm), max(runs, key=lambda r: r.speed_rpm)
    spread = fast.speed_rpm - slow.speed_rpm
    if spread > 1e-9 and (slow.speed_rpm == 0.0 or spread > 2.0 * tol):
        raise InputError(fast.path, f"/runs/{fast.run_id}/@speed_rpm",
                         f"{fast.speed_rpm:g} rpm differs from {slow.path} ({slow.speed_rpm:g} rpm)"
                         + (f" by more than the rig's speed range allows between two sweeps (variability: speed "
                            f"+-{tol:g} rpm)" if tol and slow.speed_rpm != 0.0 else ""))
    harmonics = run_harmonics(runs)
    # several healthy sweeps: their mean when they are repeats of one state, else the most central one alone
    ref = healthy_reference(runs, harmonics.flagged)
    one = runs[0] if ref.reference is None else runs[ref.reference]
    speed = one.speed_rpm  # the baseline's operating point: the sweep it keeps (the first when averaged)
    model = nominal_model(rig, first.frequency_hz, speed)
    # 'measured' detects against the measured healthy FRF; its gamma is still the model-error bound
    # of 'system' (what validation is for: how far the nominal model is from the healthy rig)
    V: float | np.ndarray = noise_values(noise_bound)
    if not isinstance(V, float):  # per-point: every healthy run's own V(w), the largest per point
        V = np.max(np.array([noise_values(noise_bound, r) for r in runs], dtype=float), axis=0)
    if enclose != "measured" and first.n_pairs > 1:
        # several channel pairs against the model: one experiment per input (unit force), the additive
        # full block over all outputs and inputs, the noise per point from the stored variances
        if model.structure != "additive":
            raise InputError(None, "--enclose", f"with several channel pairs the model-centred modes need "
                             f"additive uncertainty (this rig: {model.structure}); use 'measured'")
        exps = [pair_experiments(rig, r) for r in runs]
        res = validation.validate(exps[0][0], [w for e in exps for w in e[1]], [z for e in exps for z in e[2]],
                                  np.max([e[3] for e in exps], axis=0), enclose=enclose, fail_at=fail_at)
    else:
        res = validation.validate(model.me, [r.W for r in runs], [r.Zt for r in runs], V,
                                  enclose="system" if enclose == "measured" else enclose,
                                  structure=parameter_structure(model, enclose), fail_at=fail_at)
    res.exclude(harmonics.flagged)
    keep = ~harmonics.flagged
    healthy = ref.estimate
    upd = None
    if update:

        if not rig.variability:
            raise InputError(None, "--update", "the rig has no variability section: nothing to update")
        upd = update_parameters(rig, first.frequency_hz[keep], speed, healthy.frf[keep, 0])
    model_rig = updated_rig(rig, None if upd is None else upd.as_dict())
    learning = None
    # ref.reference None: one sweep, or repeats of one state (no drift to learn)
    if (learn_drift is not False and len(runs) >= 3 and ref.reference is not None and enclose == "measured"
            and benign_parameters(model_rig)):
        learning = learn_drift_ranges(model_rig, runs, ref.reference, exclude=harmonics.flagged)
    structure, parameter = model.structure, model.parameter or ""
    base = Baseline(
        Provenance(rig.rig_id, rig.sha256(), [r.sha256 for r in runs], first.run_id, speed),
        noise_fit(noise_bound, structure, parameter, None if isinstance(V, float) else np.asarray(V, dtype=float)),
        ModelBound(enclose, structure, parameter, first.frequency_hz, res.gamma, model.frf[:, None, None],
                   res.gamma_lower, np.asarray(res.status, dtype=str)),
        HealthyData(healthy.frf, healthy.var, healthy.dof, one.W[:, None], one.Zt[:, None],
                    first.harmonics_removed, len(runs) if ref.reference is None else 1,
                    pair_keys(first), healthy_sideband_p_value(runs)),
        DriftModel(None if learning is None else learning.kappa, updated_parameters=None if upd is None
                   else upd.as_dict(), range_shift=None if learning is None else learning.shift_by_name,
                   range_widen=None if learning is None else learning.widen_by_name))
    return ValidationOutcome(base, res, model, runs, rig, upd, learning, harmonics,
                             ref.note, ref.reference)


def healthy_sideband_p_value(runs: list[MeasuredRun]) -> float | None:
    """The sideband scan's smallest p-value over the healthy runs that hold sidebands (None: none does): small, the
    healthy rotor is not time-invariant (an asymmetric shaft, a crack already there) and the sideband test has no
    zero to test against."""
    ps = [sideband_scan(*r.sidebands.statistic()).p_value for r in runs
          if r.sidebands is not None and r.speed_rpm != 0.0]
    return min(ps) if ps else None


def sideband_warning(outcome: ValidationOutcome, alpha: float = HEALTHY_SIDEBAND_ALPHA) -> str:
    """A warning when the healthy sweeps' sidebands are beyond noise ('' otherwise)."""
    p = outcome.baseline.healthy.sideband_p_value
    if p is None or p >= alpha:
        return ""
    return (f"the healthy sweeps hold sidebands f + k x speed beyond noise (scan p = {p:.3g} < {alpha:g}): the rotor "
            "is not time-invariant when healthy (a shaft with unequal bending stiffness, a crack already there?); "
            "detect will not use the sideband test against this baseline")


def learning_summary(outcome: ValidationOutcome) -> str:
    """Lines: where the learned drift moved the ranges, and the model-error factor the sweeps allowed."""
    return "" if outcome.learning is None else outcome.learning.summary()


def update_summary(outcome: ValidationOutcome) -> str:
    """One line: the updated parameters with standard errors and the FRF error before and after."""
    u = outcome.update
    if u is None:
        return ""
    parts = []
    for n, v, e, b in zip(u.names, u.values, u.se, u.at_bound):
        parts.append(f"{n} {100 * v:+.3g} % ({'range edge' if b or not np.isfinite(e) else f'se {100 * e:.2g} %'})")
    return ("model updated to the healthy FRF: " + ", ".join(parts)
            + f"; RMS relative FRF error {u.rms_before:.3g} -> {u.rms_after:.3g}")


def parameter_structure(model: NominalModel, enclose: str) -> Structure | None:
    """A named physical parameter (``uncertainty.structure: parametric``) is real: a real scalar block
    (mixed mu, D-G scalings) where the LMI path solves it ('data'); None (one complex block) otherwise
    ('system'/'measured' enclose through the complex closed form, a relaxation the report notes)."""

    return Structure.real() if model.structure == "parametric" and enclose == "data" else None

