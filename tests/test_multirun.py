"""Several runs (speeds) in one file (issue 12): validate keeps one validated set per run, detect matches
the runs of a new file by speed, reports each and gives one verdict for the file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rotorcheck.baseline import read_baselines
from rotorcheck.cli import EXIT_DAMAGE, EXIT_INPUT, EXIT_OK, main
from rotorcheck.config import load_config
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.sweep import write_sweep
from rotorcheck.sweep.format import Sweep

GRID = np.linspace(30.0, 600.0, 262)[::3]


def _two_speeds(path: Path, fault: str | None, seed: int, speeds: tuple[float, float] = (0.0, 1000.0)) -> None:
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    sweeps = [simulate_rig(truth, GRID, sp, fault=fault, seed=seed + k,
                           settings=step_settings(truth, keep_periods=sp != 0.0)) for k, sp in enumerate(speeds)]
    runs = {r.run_id: r for sw in sweeps for r in sw.runs.values()}
    first = sweeps[0]
    write_sweep(Sweep(first.rig_id, first.source, first.generator, first.created_utc, first.channels, runs), path)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("runs")
    out = {}
    for name, fault, seed in (("healthy", None, 11), ("crack", "open_crack", 21), ("repeat", None, 31)):
        out[name] = d / f"{name}.h5"
        _two_speeds(out[name], fault, seed)
    out["other_speed"] = d / "other_speed.h5"
    _two_speeds(out["other_speed"], None, 41, (0.0, 1500.0))
    return out


def test_one_baseline_per_run_and_one_verdict_per_file(files, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    assert main(["validate", str(files["healthy"]), "--out", str(out), "--no-plots"]) == EXIT_OK
    bases = read_baselines(out / "baseline.h5")
    assert [(b.run_id, b.speed_rpm) for b in bases] == [("0rpm", 0.0), ("1000rpm", 1000.0)]
    assert all(b.validated and b.frequency_hz.size == GRID.size for b in bases)
    capsys.readouterr()
    assert main(["detect", str(files["crack"]), "--out", str(out), "--no-plots", "--json"]) == EXIT_DAMAGE
    doc = json.loads(capsys.readouterr().out)
    assert doc["verdict"] == "damage" and [r["run_id"] for r in doc["runs"]] == ["0rpm", "1000rpm"]
    assert [r["baseline_run_id"] for r in doc["runs"]] == ["0rpm", "1000rpm"]
    for r in doc["runs"]:
        assert json.loads(Path(r["report"]).read_text())["speed_rpm"] == r["speed_rpm"]
    assert main(["detect", str(files["repeat"]), "--out", str(out), "--no-plots", "--force"]) == EXIT_OK
    # a run at a speed the baseline does not hold: refused, naming the speeds it holds
    capsys.readouterr()
    assert main(["detect", str(files["other_speed"]), "--out", str(out), "--no-plots", "--force"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "1500 rpm" in err and "0rpm (0 rpm), 1000rpm (1000 rpm)" in err
