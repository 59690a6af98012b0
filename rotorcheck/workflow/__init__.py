"""The pipeline as functions a notebook can call; the CLI, the fleet and the bench are thin layers over these.

One module per pipeline step (frequencies in Hz, receptances in m/N, D_u in N/m):

- :mod:`~rotorcheck.workflow.rigs`: a rig file for a sweep, rig variants (updated parameters, crack depth).
- :mod:`~rotorcheck.workflow.outputs`: plot file formats and paths.
- :mod:`~rotorcheck.workflow.model`: ``rotorcheck model`` and ``rotorcheck crack`` (modal summary, figures).
- :mod:`~rotorcheck.workflow.measured`: a sweep's runs read against the rig (:class:`MeasuredRun`), grids,
  channel pairs, FRF estimates.
- :mod:`~rotorcheck.workflow.noise`: step 2, the noise bound.
- :mod:`~rotorcheck.workflow.validation`: step 3, gamma_h and the baseline.
- :mod:`~rotorcheck.workflow.benign`: the benign-change model and the joint test.
- :mod:`~rotorcheck.workflow.drift`: learning where the machine drifts from several healthy sweeps.
- :mod:`~rotorcheck.workflow.directional`: damage dynamics in x and y from several channel pairs.
- :mod:`~rotorcheck.workflow.detection`: steps 4-5, fault points, verdict, damage dynamics.
- :mod:`~rotorcheck.workflow.locating`: where and how big (candidate elements).
- :mod:`~rotorcheck.workflow.figures`: validation and detection figures.
- :mod:`~rotorcheck.workflow.prediction`: detectability and sensor ranking from stated noise.
"""

from rotorcheck.errors import InputError
from rotorcheck.workflow.benign import (
    KAPPA_MODAL,
    KAPPA_NOMINAL,
    benign_model,
    benign_table,
    certify_beyond_benign,
    joint_detection,
)
from rotorcheck.workflow.checking import FILE_RULE, SweepCheck, check_sweep, detect_pairs, paired_runs
from rotorcheck.workflow.detection import (
    DetectionOutcome,
    anchored_summary,
    baseline_for_speed,
    check_baseline,
    detect,
    diagnose,
    joint_summary,
    sweep_detectability,
)
from rotorcheck.workflow.detectors import DETECTORS, RULES, Detection, Detector, DetectorSettings, make_detector
from rotorcheck.workflow.detectors.enclosure import VERDICT_RULE
from rotorcheck.workflow.detectors.joint import joint_verdict
from rotorcheck.workflow.directional import DirectionalDamage, damage_per_direction
from rotorcheck.workflow.drift import DRIFT_RULE, DriftLearning, learn_drift_ranges
from rotorcheck.workflow.figures import (
    PLOT_STEMS_DETECT,
    PLOT_STEMS_VALIDATE,
    check_frf_unit,
    detection_figures,
    detection_plots,
    figure_context,
    uncertainty_disk,
    validation_figures,
    validation_plots,
)
from rotorcheck.workflow.locating import locate_damage, locate_run
from rotorcheck.workflow.measured import (
    GRID_TOLERANCE_HZ,
    MeasuredRun,
    aligned_pairs,
    baseline_pairs,
    frf_estimate,
    grid_mismatch,
    healthy_estimate,
    load_rig_and_run,
    load_rig_and_runs,
    load_run,
    measured_run,
    pair_experiments,
    pair_keys,
    read_runs,
    resample_run,
)
from rotorcheck.workflow.model import crack_report, model_report
from rotorcheck.workflow.noise import NOISE_METHODS, fit_noise, noise_baseline, noise_report, noise_values, prior_noise
from rotorcheck.workflow.outputs import PLOT_FORMATS, plot_formats, plot_paths
from rotorcheck.workflow.prediction import DETECTABILITY_POINTS, detectability_for_rig, sensor_ranking_for_rig
from rotorcheck.workflow.rigs import (
    baseline_rig,
    check_elements,
    load_rig,
    port_static_stiffness,
    rig_for,
    rig_with_crack_depth,
    speed_tolerance,
    updated_rig,
)
from rotorcheck.workflow.validation import (
    ENCLOSE_MODES,
    ValidationOutcome,
    learning_summary,
    parameter_structure,
    sideband_warning,
    update_summary,
    validate,
)

__all__ = [
    "DETECTABILITY_POINTS",
    "DETECTORS",
    "DRIFT_RULE",
    "ENCLOSE_MODES",
    "FILE_RULE",
    "GRID_TOLERANCE_HZ",
    "KAPPA_MODAL",
    "KAPPA_NOMINAL",
    "NOISE_METHODS",
    "PLOT_FORMATS",
    "PLOT_STEMS_DETECT",
    "PLOT_STEMS_VALIDATE",
    "RULES",
    "VERDICT_RULE",
    "Detection",
    "DetectionOutcome",
    "Detector",
    "DetectorSettings",
    "DirectionalDamage",
    "DriftLearning",
    "InputError",
    "MeasuredRun",
    "SweepCheck",
    "ValidationOutcome",
    "aligned_pairs",
    "anchored_summary",
    "baseline_for_speed",
    "baseline_pairs",
    "baseline_rig",
    "benign_model",
    "benign_table",
    "certify_beyond_benign",
    "check_baseline",
    "check_elements",
    "check_frf_unit",
    "check_sweep",
    "crack_report",
    "damage_per_direction",
    "detect",
    "detect_pairs",
    "detectability_for_rig",
    "detection_figures",
    "detection_plots",
    "diagnose",
    "figure_context",
    "fit_noise",
    "frf_estimate",
    "grid_mismatch",
    "healthy_estimate",
    "joint_detection",
    "joint_summary",
    "joint_verdict",
    "learn_drift_ranges",
    "learning_summary",
    "load_rig",
    "load_rig_and_run",
    "load_rig_and_runs",
    "load_run",
    "locate_damage",
    "locate_run",
    "make_detector",
    "measured_run",
    "model_report",
    "noise_baseline",
    "noise_report",
    "noise_values",
    "pair_experiments",
    "pair_keys",
    "paired_runs",
    "parameter_structure",
    "plot_formats",
    "plot_paths",
    "port_static_stiffness",
    "prior_noise",
    "read_runs",
    "resample_run",
    "rig_for",
    "rig_with_crack_depth",
    "sensor_ranking_for_rig",
    "sideband_warning",
    "speed_tolerance",
    "sweep_detectability",
    "uncertainty_disk",
    "update_summary",
    "updated_rig",
    "validate",
    "validation_figures",
    "validation_plots",
]
