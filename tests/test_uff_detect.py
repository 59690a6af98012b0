"""A third-party UFF58 file (written by pyuff directly, no rotorcheck tokens) imports and detects (issue 12):
the FRFs of the bundled 0 rpm samples as an analyser would export them, binary and ASCII."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import pyuff

from rotorcheck.cli import EXIT_DAMAGE, EXIT_OK, main
from rotorcheck.resources import samples_dir
from rotorcheck.sweep import read_sweep


def _analyser_file(path: Path, sample: str, binary: bool) -> None:
    """One FRF record (response 6 +X / reference 8 +X), m/N over Hz, as pyuff writes it for any tool."""
    run = next(iter(read_sweep(samples_dir() / "crack_rig" / sample).runs.values()))
    rec = {"type": 58, "binary": int(binary), "func_type": 4, "id1": "Analyser FRF 6X/8X", "id2": "rig A",
           "id3": "01-JAN-26 12:00:00", "rsp_node": 6, "rsp_dir": 1, "ref_node": 8, "ref_dir": 1,
           "abscissa_spacing": 1, "abscissa_spec_data_type": 18, "ordinate_spec_data_type": 8,
           "orddenom_spec_data_type": 13, "x": run.frequency.copy(), "data": run.frf[:, 0, 0].copy()}
    pyuff.UFF(str(path)).write_sets([rec], mode="add")


@pytest.mark.parametrize("binary", [True, False])
def test_third_party_uff_imports_and_detects(tmp_path: Path, capsys: pytest.CaptureFixture, binary: bool) -> None:
    """Without --speed and a noise statement the import is refused naming them; with them the FRF-only
    sweeps validate and the open crack is damage, and the report repeats the noise statement."""
    for name, sample in (("healthy", "healthy_0rpm.h5"), ("crack", "open_crack_0rpm.h5")):
        _analyser_file(tmp_path / f"{name}.uff", sample, binary)
    assert main(["convert", str(tmp_path / "healthy.uff"), str(tmp_path / "x.h5")]) == 2
    err = "".join(capsys.readouterr().err.split())
    assert "--speed" in err and "--noise" in err
    rule = "assumed: 1 % of |H|"
    for name in ("healthy", "crack"):
        assert main(["convert", str(tmp_path / f"{name}.uff"), str(tmp_path / f"{name}.h5"), "--speed", "0",
                     "--rig-id", "crack_rig", "--noise-source", rule]) == EXIT_OK
    out = tmp_path / "out"
    assert main(["fit-noise", str(tmp_path / "healthy.h5"), "--out", str(out)]) == EXIT_OK
    assert main(["validate", str(tmp_path / "healthy.h5"), "--out", str(out), "--no-plots"]) in (0, 3)
    capsys.readouterr()
    assert main(["detect", str(tmp_path / "crack.h5"), "--out", str(out), "--no-plots", "--json"]) == EXIT_DAMAGE
    doc = json.loads(capsys.readouterr().out)
    assert any(rule in n for n in doc["notes"])
    assert np.isfinite(doc["joint_statistic"])
