"""A rig of the user's own (issue 12): configs/overhung_rig.yaml, a two-disc overhung rotor with its own band,
grid, variability and no damage port, run end to end from the CLI with --rig given once (fit-noise)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rotorcheck.cli import EXIT_DAMAGE, EXIT_OK, main
from rotorcheck.config import load_config
from rotorcheck.resources import configs_dir
from rotorcheck.sweep import read_sweep

RIG = configs_dir() / "overhung_rig.yaml"


def test_own_rig_end_to_end_without_rig_after_fit_noise(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """simulate takes the rig's band and grid (10-400 Hz, 157 points); fit-noise stores the rig path;
    validate and detect find it (the rig_id is not a bundled one, so nothing else could); an open crack of
    30 % loss in element 4 is damage with element 4 the best candidate, a healthy repeat is healthy."""
    cfg = load_config(RIG)
    cases = (("h", ["--seed", "1"]), ("r", ["--seed", "2"]), ("c", ["--seed", "3", "--fault", "open_crack"]))
    for name, extra in cases:
        assert main(["simulate", str(tmp_path / f"{name}.h5"), "--rig", str(RIG), "--speed", "1500", *extra]) == EXIT_OK
    f = next(iter(read_sweep(tmp_path / "h.h5").runs.values())).frequency
    np.testing.assert_allclose(f, np.linspace(*cfg.analysis.band_hz, cfg.analysis.n_points or 0))
    out = tmp_path / "out"
    assert main(["fit-noise", str(tmp_path / "h.h5"), "--rig", str(RIG), "--out", str(out)]) == EXIT_OK
    assert main(["validate", str(tmp_path / "h.h5"), "--out", str(out), "--no-plots"]) == EXIT_OK
    capsys.readouterr()
    assert main(["detect", str(tmp_path / "c.h5"), "--out", str(out), "--no-plots", "--json"]) == EXIT_DAMAGE
    doc = json.loads(capsys.readouterr().out)
    # one probe does not separate elements 1-4 of this rig (issue 30: their best fits' misfits are within
    # 0.1 chi-square units): the diagnosis ranks them with their relative likelihoods instead of naming one
    lik = {c["element"]: c["relative_likelihood"] for c in doc["location"]["candidates"]}
    assert doc["rig_id"] == "overhung_rig" and doc["location"]["kind"] == "ranked" and lik[4] >= 0.15
    assert doc["best_element"] in (1, 2, 3, 4) and "relative likelihood" in doc["location"]["summary"]
    assert any("no damage port" in n for n in doc["notes"])
    assert main(["detect", str(tmp_path / "r.h5"), "--out", str(out), "--no-plots", "--force"]) == EXIT_OK


def test_a_rig_without_measurement_noise_warns(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    quiet = tmp_path / "quiet.yaml"
    quiet.write_text(RIG.read_text().replace("output_noise_std: 1.0e-7", "output_noise_std: 0.0"))
    assert main(["simulate", str(tmp_path / "q.h5"), "--rig", str(quiet), "--points", "5"]) == EXIT_OK
    assert "noise-free" in capsys.readouterr().err


def test_a_rig_without_band_says_which_it_uses(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    text = RIG.read_text()
    start = text.index("analysis:")
    end = text.index("variability:")
    bare = tmp_path / "bare.yaml"
    bare.write_text(text[:start] + text[end:])
    assert main(["simulate", str(tmp_path / "b.h5"), "--rig", str(bare), "--points", "5"]) == EXIT_OK
    err = capsys.readouterr().err
    assert "no analysis.band_hz; simulating 30-600 Hz (default)" in err
    f = next(iter(read_sweep(tmp_path / "b.h5").runs.values())).frequency
    assert (f[0], f[-1]) == (30.0, 600.0)
