"""A second user rig of a real machine type (issue 20): configs/compressor_rig.yaml, an overhung
centrifugal compressor rotor with an impeller on a tapered fit, a seal sleeve (concentric layer), a
thrust collar by geometry, a labyrinth seal with negative direct stiffness and tilting-pad bearings
from speed tables, run end to end: model, simulate, fit-noise, validate, detect."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rotorcheck.cli import EXIT_DAMAGE, EXIT_OK, main
from rotorcheck.config import load_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.resources import configs_dir

RIG = configs_dir() / "compressor_rig.yaml"


def test_compressor_rig_assembles_what_the_file_says() -> None:
    cfg = load_config(RIG)
    sys_ = build_system(cfg)
    assert len(sys_.layers) == 1 and sys_.layers[0].segment == 9  # the seal sleeve over element 9
    taper = [e for e in sys_.elements if e.segment == 10]
    assert taper[0].outer_diameter == 0.09 and taper[0].outer_right == 0.07
    # seal: negative direct stiffness at speed, the bearings keep the static stiffness positive definite
    seal = cfg.bearings[2].coefficients(6000.0)
    assert seal["kxx"] < 0 and seal["kxy"] == -seal["kyx"] > 0
    assert sys_.static_stiffness_margin(6000.0) > 0
    # bearing tables interpolate linearly between their speeds
    assert cfg.bearings[0].coefficients(4500.0)["kxx"] == pytest.approx(0.5 * (1.5e8 + 1.9e8))


def test_compressor_rig_end_to_end(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    assert main(["model", str(RIG), "--out", str(out), "--json"]) == EXIT_OK
    summary = json.loads(capsys.readouterr().out)
    # the bearing tables end at 12000 rpm, the Campbell diagram runs to 15000 rpm: held there, and said so
    assert len(summary["warnings"]) == 3 and len(summary["modes"]) == 6
    assert all("0-12000 rpm" in w and "(extrapolate: hold)" in w for w in summary["warnings"])
    cases = (("h", ["--seed", "1"]), ("r", ["--seed", "2"]), ("c", ["--seed", "3", "--fault", "open_crack"]))
    for name, extra in cases:
        assert main(["simulate", str(tmp_path / f"{name}.h5"), "--rig", str(RIG), "--speed", "6000", *extra]) == EXIT_OK
    assert main(["fit-noise", str(tmp_path / "h.h5"), "--rig", str(RIG), "--out", str(out)]) == EXIT_OK
    assert main(["validate", str(tmp_path / "h.h5"), "--out", str(out), "--no-plots"]) == EXIT_OK
    capsys.readouterr()
    assert main(["detect", str(tmp_path / "c.h5"), "--out", str(out), "--no-plots", "--json"]) == EXIT_DAMAGE
    doc = json.loads(capsys.readouterr().out)
    assert doc["rig_id"] == "compressor_rig" and doc["best_element"] == 10  # the crack's element
    assert main(["detect", str(tmp_path / "r.h5"), "--out", str(out), "--no-plots", "--force"]) == EXIT_OK
    # the repeated model run replaces its own plots (manifest), as any rerun must
    assert main(["model", str(RIG), "--out", str(out)]) == EXIT_OK
    assert np.isfinite(summary["critical_speeds_rpm"]).all()
