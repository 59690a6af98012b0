"""End to end: healthy and breathing-crack time records of the bundled crack rig (the truth rig played
by the simulator at 1000 rpm, free-running start angles, a sample clock not locked to the
excitation), ingested, then detection against an ingested healthy baseline (certified per-point rule:
24 points are too few for the joint test's benign-change budget). The verdicts must match those of the
phasor-path sweeps of the same rig, seeds and grid, the fault points nearly (independent noise)."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.config import load_config
from rotorcheck.ingest import analyse, parse_channel_map
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.sim.time_records import RecordSpec, channel_map_dict, simulate_rig_record

GRID = np.linspace(30.0, 110.0, 24)  # where the breathing crack shows at station 6 (bundled samples)
CASES = (("healthy", None, 11), ("repeat", None, 12), ("crack", "breathing_crack", 13))


@pytest.fixture(scope="module")
def sweeps():
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    out = {}
    for name, fault, seed in CASES:
        out[("phasor", name)] = simulate_rig(truth, GRID, 1000.0, fault=fault, seed=seed,
                                             settings=step_settings(truth, keep_periods=True))
        sim = simulate_rig_record(truth, GRID, 1000.0, fault, seed=seed, shaft_angle_rad=0.3 * seed,
                                  spec=RecordSpec(fs_hz=5120.0, probe_names=("disp_s6_x",)))
        out[("ingest", name)] = analyse([sim.record], parse_channel_map(channel_map_dict(sim, "crack_rig"))).sweep
    return out


def _verdicts(sweeps, path: str):
    rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
    runs = {n: workflow.measured_run(sweeps[(path, n)], rig) for n, _, _ in CASES}
    base = workflow.validate(rig, [runs["healthy"]], workflow.fit_noise(runs["healthy"])).baseline
    return {n: workflow.detect(rig, base, runs[n], rule="certified") for n in ("repeat", "crack")}


def test_detect_verdicts_match_the_phasor_path(sweeps) -> None:
    ph, ing = _verdicts(sweeps, "phasor"), _verdicts(sweeps, "ingest")
    assert ph["repeat"].verdict.verdict == ing["repeat"].verdict.verdict == "healthy"
    assert ph["crack"].verdict.verdict == ing["crack"].verdict.verdict == "damage"
    # the two paths draw different noise: points near the threshold may differ, the picture may not
    a, b = (np.asarray(v["crack"].detection.fault, bool) for v in (ph, ing))
    assert ph["crack"].verdict.n_fault >= 5 and abs(int(a.sum()) - int(b.sum())) <= 4, (a, b)
    assert np.mean(a == b) >= 0.75, (a, b)
