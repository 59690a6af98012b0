"""modes() against the full first-order eigenproblem (issue 32, defect 3).

Reference: ``scipy.linalg.eig`` of the full first-order system of ``M q'' + D q' + K q = 0`` (every
DOF, no reduction), written in energy-scaled undamped modal coordinates ``q = Phi W^-1 r1``,
``q' = Phi r2`` (an exact change of variables): ``[[0, W], [-Phi^T K Phi W^-1, -Phi^T D Phi]]``. The
unscaled state matrix ``[[0, I], [-M^-1 K, -M^-1 D]]`` has norm ``w_max^2``; its own round-off puts its
low eigenvalues up to 2.3e-6 (relative) off on the 340-DOF mesh below, so it cannot referee 1e-9.

Before the fix (Ritz eigenvalues of large meshes, unrefined) modes() was 1.7e-7 off on ROSS's
compressor (cross-coupled, speed-dependent seals and bearings; 1 to 6 modes asked) and 4.4e-10 on the
damped anisotropic overhung rotor; now every eigenpair is refined on the full matrices.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import yaml

from rotorcheck.config import parse_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import modes
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.ross_import import import_ross

ROOT = Path(__file__).resolve().parents[2]
RPM = np.pi / 30.0


def _full_first_order_eigenvalues(M: np.ndarray, D: np.ndarray, K: np.ndarray) -> np.ndarray:
    w2, phi = sla.eigh(0.5 * (K + K.T), M)
    w = np.sqrt(w2)
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.diag(w)], [-(phi.T @ K @ phi) / w, -(phi.T @ D @ phi)]])
    lam = sla.eig(A, right=False)
    lam = lam[lam.imag > 0]
    return lam[np.argsort(lam.imag)]


def _overhung(refine: int) -> MechanicalSystem:
    """The overhung rig (kxx != kyy at both bearings), bearing damping cxx != cyy, ``refine`` elements per span."""
    d = yaml.safe_load((ROOT / "configs" / "overhung_rig.yaml").read_text())
    for e in d["shaft"]:
        e["refine"] = refine
    d["bearings"][0].update(cxx=2e3, cyy=5e3)
    d["bearings"][1].update(cxx=2e3, cyy=1e4)
    return build_system(parse_config(d))


def _compressor() -> MechanicalSystem:
    return build_system(parse_config(import_ross(ROOT / "tests" / "data" / "ross" / "compressor.toml").rig))


@pytest.mark.parametrize(("make", "rpms"), [
    (lambda: _overhung(1), (0.0, 9000.0)),  # 32 DOF: dense state matrix
    (lambda: _overhung(12), (0.0, 9000.0)),  # 340 DOF: Ritz basis
    (_compressor, (6000.0,)),  # 224 DOF, cross-coupled seals
], ids=["overhung_32dof", "overhung_340dof", "ross_compressor"])
def test_modes_match_the_full_first_order_eigenproblem(make, rpms) -> None:  # type: ignore[no-untyped-def]
    system = make()
    for rpm in rpms:
        M, C, G, K = system.matrices(rpm)
        ref = _full_first_order_eigenvalues(M, C + rpm * RPM * G, K)
        for n_modes in (1, 6, 12):
            lam = modes(system, rpm, n_modes=n_modes).eigenvalues
            assert lam.size == n_modes
            assert np.max(np.abs(lam / ref[:n_modes] - 1.0)) <= 1e-10, (rpm, n_modes)


def test_model_clamps_n_modes_to_the_degrees_of_freedom(tmp_path: Path) -> None:
    """A rig asking for 14 modes of a 12-DOF model was refused; now ``model`` reports all 12 (the count
    and the frequencies of the full first-order eigenproblem) and says so in its warnings."""
    from rotorcheck.workflow import model_report

    rig = {
        "rig_id": "three_nodes", "materials": {"steel": {"density": 7810, "youngs_modulus": 211e9, "poisson": 0.3}},
        "stations": [0.0, 0.25, 0.5],
        "shaft": [{"start": 1, "end": 2, "material": "steel", "outer_diameter": 0.05},
                  {"start": 2, "end": 3, "material": "steel", "outer_diameter": 0.05}],
        "bearings": [{"station": 1, "kxx": 1e6, "kyy": 0.8e6, "cxx": 50.0}, {"station": 3, "kxx": 1e6, "kyy": 0.8e6}],
        "analysis": {"n_modes": 14, "speeds_rpm": [0.0], "campbell_max_rpm": 1000.0},
    }
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(rig))
    summary = model_report(path)["summary"]
    assert any("14 modes asked, but the model has 12 degrees of freedom" in w for w in summary["warnings"])
    system = build_system(parse_config(rig))
    M, C, _, K = system.matrices(0.0)
    ref = _full_first_order_eigenvalues(M, C, K)
    assert system.n_dof == 12 and ref.size == 12 and len(summary["modes"]) == 12
    f = np.array([m["frequency_hz"] for m in summary["modes"]])
    assert np.max(np.abs(f / (ref.imag / (2 * np.pi)) - 1.0)) <= 1e-10
