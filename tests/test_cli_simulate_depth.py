"""``rotorcheck simulate --crack-depth`` drives the crack: deeper cracks change the sweep more, the depth
equals the rig-file route, and bad depths exit 2 naming the flag."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rotorcheck.cli import EXIT_INPUT, EXIT_OK, main
from rotorcheck.config import load_config
from rotorcheck.faults.compliance import with_crack_depth
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import simulate_rig, step_settings
from rotorcheck.sweep import read_sweep


def _frf(path: Path) -> np.ndarray:
    run = next(iter(read_sweep(path).runs.values()))
    return run.frf[:, 0, 0]


def test_crack_depth_flag_drives_the_breathing_crack(tmp_path: Path) -> None:
    common = ["--speed", "1000", "--points", "12", "--f-min", "40", "--f-max", "70", "--noise", "0",
              "--periods", "4", "--no-keep-periods"]
    files = {}
    for depth in ("0.05", "0.2", "0.4"):
        files[depth] = tmp_path / f"d{depth}.h5"
        assert main(["simulate", str(files[depth]), "--fault", "breathing_crack", "--crack-depth", depth,
                     *common]) == EXIT_OK
    healthy = tmp_path / "h.h5"
    assert main(["simulate", str(healthy), *common]) == EXIT_OK
    h = _frf(healthy)
    change = [np.max(np.abs(_frf(files[d]) - h) / np.abs(h)) for d in ("0.05", "0.2", "0.4")]
    assert 0 < change[0] < change[1] < change[2]
    # the CLI route equals the library route at the same depth (rig file with depth_ratio = 2 x 0.2)
    truth = load_config(configs_dir() / "crack_rig_truth.yaml")
    cfg = with_crack_depth(truth, "breathing_crack", 0.2)
    st = step_settings(cfg, keep_periods=False)
    import dataclasses

    st = dataclasses.replace(st, output_noise_std=0.0, n_periods=4)
    sw = simulate_rig(cfg, np.linspace(40, 70, 12), 1000.0, fault="breathing_crack", settings=st)
    np.testing.assert_allclose(next(iter(sw.runs.values())).frf[:, 0, 0], _frf(files["0.2"]), rtol=1e-12)


def test_bad_crack_depth_exits_2(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    for bad in ("0", "1.5", "0.7"):
        assert main(["simulate", str(tmp_path / "x.h5"), "--fault", "breathing_crack", "--crack-depth", bad,
                     "--points", "3"]) == EXIT_INPUT
        assert "--crack-depth" in capsys.readouterr().err
    assert main(["simulate", str(tmp_path / "x.h5"), "--crack-depth", "0.1", "--points", "3"]) == EXIT_INPUT
    assert not (tmp_path / "x.h5").exists()
