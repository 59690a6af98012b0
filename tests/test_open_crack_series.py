"""The open-crack series at 0 rpm, 1x noise (issue 9): the anchored damage dynamics below the first
resonance against eq. 3.11 applied to the noiseless nominal model with the same crack (a second,
model-only route), and its bound against that reference."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.config import RigConfig, load_config
from rotorcheck.nominal import nominal_model
from rotorcheck.resources import configs_dir
from rotorcheck.robust.identify import damage_dynamics
from rotorcheck.sim.rig_sim import simulate_rig, step_settings

GRID = np.linspace(30.0, 600.0, 262)
FACTORS = (0.995, 0.98, 0.95, 0.9, 0.8, 0.6, 0.46)
LOW = GRID <= 50.0  # below the first resonance (54.5 Hz)


def _with_element_factor(cfg: RigConfig, element: int, factor: float) -> RigConfig:
    shaft = [s.model_copy(update={"modulus_factor": s.modulus_factor * factor}) if i == element - 1 else s
             for i, s in enumerate(cfg.shaft)]
    return cfg.model_copy(update={"shaft": shaft})


@pytest.fixture(scope="module")
def series() -> list[dict[str, np.ndarray | float]]:
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    st = step_settings(truth, keep_periods=False)
    healthy = workflow.measured_run(simulate_rig(truth, GRID, 0.0, seed=11, settings=st), nominal)
    val = workflow.validate(nominal, [healthy], workflow.fit_noise(healthy))
    E = nominal_model(nominal, GRID, 0.0).E
    out = []
    for k, mf in enumerate(FACTORS):
        cracked = _with_element_factor(truth, 4, mf)
        run = workflow.measured_run(simulate_rig(cracked, GRID, 0.0, seed=20 + k, settings=st), nominal)
        # the per-point certified rule: this series is about identification below the first resonance;
        # the joint test with the rig's benign ranges hides the 0.5 % loss (bench.detection_limit, part B)
        det = workflow.detect(nominal, val.baseline, run, rule="certified")
        T_ref = nominal_model(_with_element_factor(nominal, 4, mf), GRID, 0.0).frf
        ref = damage_dynamics(E[:, 0, 0], E[:, 0, 1], E[:, 1, 0], E[:, 1, 1], T_ref)
        out.append({"factor": mf, "anchored": det.anchored, "ref": ref, "bound": det.anchored_set,
                    "noise": det.anchored_noise_only, "verdict": det.verdict.verdict})
    return out


def test_every_crack_of_the_series_is_detected(series: list[dict]) -> None:
    assert [c["verdict"] for c in series] == ["damage"] * len(FACTORS)


def test_anchored_estimate_increases_monotonically_with_severity(series: list[dict]) -> None:
    med = [float(np.median(c["anchored"][LOW].real)) for c in series]
    assert all(b > a for a, b in itertools.pairwise(med)), med
    assert med[0] > 0


def test_anchored_estimate_within_10_percent_of_the_model_only_reference(series: list[dict]) -> None:
    """Where the noise leaves the estimate determined to better than 10 % (all but E x 0.995, where the
    noise bound is 5x the value and the bound is what counts), the estimate is within 10 %."""
    for c in series:
        a, ref = np.median(c["anchored"][LOW].real), np.median(c["ref"][LOW].real)
        width = np.median(c["noise"].max_abs[LOW] - c["noise"].min_abs[LOW])
        if width < 0.1 * abs(ref):
            assert abs(a / ref - 1) < 0.10, (c["factor"], a, ref)
        else:
            assert np.all(c["bound"].contains(c["ref"])[LOW]), c["factor"]


def test_bound_contains_the_reference_where_the_channels_error_assumption_holds(series: list[dict]) -> None:
    """The bound (noise of both sweeps + the model's damage-port channels erring as its io channel does)
    contains the reference at every point below the first resonance for losses up to 20 %; for the deep
    cracks the truth rig's damage-port channels err 2-4x more than its io channel (E11 1.1 %, E12 E21
    2.0 %, E22 0.5 % median over 30-50 Hz) and the 2.5-2.8 % bias of the estimate leaves the bound at
    some points: measured and stated, not hidden."""
    for c in series:
        inside = c["bound"].contains(c["ref"])[LOW]
        if c["factor"] >= 0.8:
            assert np.all(inside), c["factor"]
        else:  # outside at some points, but by less than 5 % of |D|
            mag = np.abs(c["ref"][LOW])
            assert np.all(mag >= 0.95 * c["bound"].min_abs[LOW]), c["factor"]
            assert np.all(mag <= 1.05 * c["bound"].max_abs[LOW]), c["factor"]
