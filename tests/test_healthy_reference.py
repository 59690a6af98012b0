"""Several healthy sweeps (issue 29): averaged when they are repeats of one state, else the most central alone
(workflow.measured.healthy_reference), so that more healthy sweeps never make the joint test blinder.

Checked against the simulator, whose states are known: repeats of the bundled truth rig (only the noise differs)
pass the repeat test at its level (Monte Carlo) and are averaged; sweeps at Young's modulus -1.5 / 0 / +1.5 % (a
warm-up series) are not, and the sweep at the middle state is the one kept; validate then stores that sweep's
FRF and says why.
"""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.config import RigConfig, load_config
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig
from rotorcheck.variability import with_benign
from rotorcheck.workflow.measured import healthy_reference

F = np.linspace(30.0, 600.0, 120)


@pytest.fixture(scope="module")
def rigs() -> tuple[RigConfig, RigConfig]:
    nominal = load_config(configs_dir() / "crack_rig.yaml")
    truth = load_config(configs_dir() / "crack_rig_truth.yaml").model_copy(update={"variability": nominal.variability})
    return nominal, truth


def _run(truth: RigConfig, nominal: RigConfig, seed: int, e: float = 0.0) -> workflow.MeasuredRun:
    cfg = with_benign(truth, {"youngs_modulus": e})[0] if e else truth
    return workflow.measured_run(simulate_rig(cfg, F, 0.0, seed=seed), nominal)


def test_repeats_of_one_state_are_averaged_at_the_tests_level(rigs) -> None:
    """30 disjoint sets of 3 repeats (noise only): at most 2 of 30 called drifted (1 % per set, binomial: P(>= 3)
    = 0.3 %; measured 0 of 30 on another 30 sets); a set kept as a mean has the variance of a mean of three."""
    nominal, truth = rigs
    runs = [_run(truth, nominal, 1000 + s) for s in range(90)]
    called = 0
    for k in range(0, 90, 3):
        ref = healthy_reference(runs[k:k + 3])
        called += ref.reference is not None
        if ref.reference is None and k == 0:
            one = workflow.frf_estimate(runs[0])
            np.testing.assert_allclose(np.median(ref.estimate.var / one.var), 1.0 / 3.0, rtol=0.1)
    assert called <= 2, called


def test_a_warm_up_series_keeps_its_middle_sweep(rigs) -> None:
    """E -1.5 / 0 / +1.5 % (in shuffled order): the repeat test fails by far and the sweep at E = 0 is kept."""
    nominal, truth = rigs
    runs = [_run(truth, nominal, 7, 0.015), _run(truth, nominal, 8, 0.0), _run(truth, nominal, 9, -0.015)]
    ref = healthy_reference(runs)
    assert ref.reference == 1
    assert ref.chi2.max() > 10.0 * ref.threshold
    np.testing.assert_array_equal(ref.estimate.frf, workflow.frf_estimate(runs[1]).frf)
    out = workflow.validate(nominal, runs, workflow.fit_noise(runs[1]), enclose="measured")
    np.testing.assert_array_equal(out.baseline.healthy_frf, workflow.frf_estimate(runs[1]).frf)
    assert out.baseline.n_healthy == 1 and "most central sweep" in out.healthy_note
