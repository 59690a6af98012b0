"""Rig-file features of issue 20 (any rotor a user brings), each against an independent reference:
concentric layers, tapered elements, point masses, discs by geometry, support nodes (pedestals),
negative stiffness, optional ports, and `model` run twice in one folder."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from rotorcheck.cli import EXIT_INPUT, EXIT_OK, main
from rotorcheck.config import ConfigError, parse_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import model_summary
from rotorcheck.resources import configs_dir

DATA = Path(__file__).resolve().parent / "data" / "ross"
RHO = 7810.0


def _base() -> dict[str, Any]:
    return yaml.safe_load((DATA / "ross_rotor_example.yaml").read_text())


def _total_mass(doc: dict[str, Any]) -> float:
    """x-translation mass of the assembled model: r^T M r for a rigid x translation (kg)."""
    sys_ = build_system(parse_config(doc))
    M = sys_.matrices(0.0)[0]
    r = np.zeros(sys_.n_dof)
    r[0 : sys_.n_shaft_dof : 4] = 1.0
    r[sys_.n_shaft_dof :: 2] = 1.0
    return float(r @ M @ r)


def _bad(doc: dict[str, Any], field: str, words: str) -> None:
    with pytest.raises(ConfigError) as exc:
        parse_config(doc, "rig.yaml")
    assert exc.value.field == field, str(exc.value)
    assert words in exc.value.message, str(exc.value)


def test_masses_add_up_layers_taper_discs_and_point_masses() -> None:
    """Total mass = rho x volume of every shaft piece (cylinders, a frustum, a sleeve) + discs + point
    masses, computed here from the geometry alone."""
    d = _base()
    d["shaft"][2].update(outer_diameter_right=0.04, refine=3)  # frustum 0.05 -> 0.04 over 0.25 m
    d["shaft"].append({"start": 5, "end": 6, "material": "steel", "outer_diameter": 0.08, "inner_diameter": 0.05})
    d["point_masses"] = [{"name": "hub", "station": 1, "mass": 3.5}]
    d["discs"][0] = {"name": "disk0", "station": 3, "mass": 30.0, "polar_inertia": 0.3, "transverse_inertia": 0.16}
    vol = 5 * 0.25 * np.pi / 4 * 0.05**2 + np.pi * 0.25 / 12 * (0.05**2 + 0.05 * 0.04 + 0.04**2)
    vol += 0.25 * np.pi / 4 * (0.08**2 - 0.05**2)
    disc1 = RHO * np.pi * 0.07 * (0.28**2 - 0.05**2) / 4
    assert _total_mass(d) == pytest.approx(RHO * vol + 30.0 + disc1 + 3.5, rel=1e-12)


def test_disc_by_geometry_equals_the_same_disc_by_mass_and_inertias() -> None:
    g = _base()
    m = RHO * np.pi * 0.07 * (0.28**2 - 0.05**2) / 4
    ip = m * (0.28**2 + 0.05**2) / 8
    explicit = copy.deepcopy(g)
    explicit["discs"][0] = {"name": "disk0", "station": 3, "mass": m, "polar_inertia": ip,
                            "transverse_inertia": ip / 2 + m * 0.07**2 / 12}
    by_geometry, by_mass = build_system(parse_config(g)), build_system(parse_config(explicit))
    for a, b in zip(by_geometry.matrices(3000.0), by_mass.matrices(3000.0)):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=0.0)


def test_a_concentric_layer_adds_its_bending_stiffness() -> None:
    """Euler-Bernoulli, pinned-pinned beam with a sleeve over its whole length: the static mid-span
    deflection under a load P is P L^3 / (48 (E1 I1 + E2 I2)) (closed form, layers in parallel)."""
    d = _base()
    d.update(shear=False, rotary_inertia=False, gyroscopic=False, discs=[])
    d.pop("shear_method")  # unused without shear (refused)
    d["materials"]["alu"] = {"density": 2700, "youngs_modulus": 70e9, "poisson": 0.33}
    d["shaft"] += [{"start": k, "end": k + 1, "material": "alu", "outer_diameter": 0.07, "inner_diameter": 0.05}
                   for k in range(1, 7)]
    d["bearings"] = [{"name": "b0", "station": 1, "kxx": 1e16, "kyy": 1e16},
                     {"name": "b1", "station": 7, "kxx": 1e16, "kyy": 1e16}]
    sys_ = build_system(parse_config(d))
    K = sys_.matrices(0.0)[3]
    f = np.zeros(sys_.n_dof)
    f[sys_.dof(4, "x")] = 1000.0
    w = np.linalg.solve(K, f)[sys_.dof(4, "x")]
    EI = 211e9 * np.pi / 64 * 0.05**4 + 70e9 * np.pi / 64 * (0.07**4 - 0.05**4)
    assert w == pytest.approx(1000.0 * 1.5**3 / (48 * EI), rel=1e-8)


def test_layers_must_share_a_mesh_and_the_shaft_must_be_continuous() -> None:
    d = _base()
    d["shaft"].append({"start": 2, "end": 3, "material": "steel", "outer_diameter": 0.08, "inner_diameter": 0.05,
                       "refine": 2})
    _bad(d, "shaft[6].refine", "concentric layer")
    d = _base()
    d["shaft"][3] = {**d["shaft"][2]}  # two layers on 3-4, none on 4-5
    _bad(d, "shaft", "no element joins stations 4 and 5")
    d = _base()
    d["shaft"][0]["inner_diameter_right"] = 0.06
    _bad(d, "shaft[0]", "inner_diameter_right must be < outer_diameter_right")


def test_support_nodes_need_a_link_a_mass_and_no_gaps() -> None:
    d = _base()
    d["bearings"][0]["n_link"] = 8
    _bad(d, "point_masses", "support node 8 has no mass")
    d["point_masses"] = [{"station": 8, "mass": 1.0}]
    parse_config(d)  # linked, with mass: fine (the pedestal floats on the bearing alone)
    d["bearings"][0]["n_link"] = 9
    d["point_masses"] = [{"station": 9, "mass": 1.0}]
    _bad(d, "bearings", "without gaps")
    d = _base()
    d["point_masses"] = [{"station": 8, "mass": 1.0}]
    _bad(d, "point_masses[0].station", "neither a station")
    d = _base()
    d["point_masses"] = [{"station": 2, "mass": 1.0, "mx": 1.0}]
    _bad(d, "point_masses[0].mass", "not both")


def test_disc_forms_are_exclusive() -> None:
    d = _base()
    d["discs"][0]["mass"] = 10.0
    _bad(d, "discs[0].material", "not both")
    d = _base()
    del d["discs"][0]["width"]
    _bad(d, "discs[0].width", "required")


def test_negative_stiffness_is_accepted_and_warned_where_the_static_stiffness_is_indefinite() -> None:
    """A magnetic bearing's negative stiffness: accepted; the model warns when the net static stiffness
    is indefinite (smallest eigenvalue of the scaled K below zero: checked here against numpy's)."""
    d = _base()
    d["bearings"].append({"name": "amb", "station": 4, "kxx": -3e6, "kyy": -3e6})
    cfg = parse_config(d)
    sys_ = build_system(cfg)
    K = sys_.matrices(0.0)[3]
    assert np.linalg.eigvalsh(0.5 * (K + K.T))[0] < 0
    warns = model_summary(cfg, 0.0, sys_)["warnings"]
    assert warns and "indefinite" in warns[0]
    d["bearings"][-1].update(kxx=-1e5, kyy=-1e5)  # small: the bearings still hold it
    cfg = parse_config(d)
    assert np.linalg.eigvalsh(build_system(cfg).matrices(0.0)[3])[0] > 0
    assert model_summary(cfg, 0.0)["warnings"] == []


def test_a_free_free_rotor_is_warned() -> None:
    d = _base()
    d["bearings"] = []
    warns = model_summary(parse_config(d), 0.0)["warnings"]
    assert warns and "singular" in warns[0]


def test_a_rig_without_ports_models_and_refuses_sweeps(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    rig = DATA / "ross_rotor_example.yaml"
    assert main(["model", str(rig), "--no-plots", "--json"]) == EXIT_OK
    capsys.readouterr()
    assert main(["simulate", str(tmp_path / "s.h5"), "--rig", str(rig), "--points", "5"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "ports" in err and "needs ports.actuator and ports.sensor" in err
    assert not (tmp_path / "s.h5").exists()


def test_model_twice_replaces_its_own_plots_but_never_a_foreign_file(tmp_path: Path) -> None:
    # a user's rotor (the ROSS example) plotted once: Campbell, mode shapes and the rotor drawing
    assert main(["model", str(DATA / "ross_rotor_example.yaml"), "--out", str(tmp_path / "ross")]) == EXIT_OK
    assert {p.name for p in (tmp_path / "ross").glob("*.png")} == {"campbell.png", "mode_shapes.png", "rotor.png"}
    # the replacement rules do not depend on the rig: the three-mass rig's plots are 6x quicker (0.8 s, not 5)
    rig = configs_dir() / "three_mass_trial1.yaml"
    out = tmp_path / "out"
    args = ["model", str(rig), "--out", str(out), "--json"]
    assert main(args) == EXIT_OK
    first = (out / "campbell.png").stat().st_mtime_ns
    assert main(args) == EXIT_OK  # the tool's own outputs (manifest) are replaced
    assert (out / "campbell.png").stat().st_mtime_ns >= first
    (out / "mode_shapes.png").write_bytes(b"the user's own picture")  # changed since the tool wrote it
    assert main(args) == EXIT_INPUT
    assert (out / "mode_shapes.png").read_bytes() == b"the user's own picture"
    other = tmp_path / "other"
    other.mkdir()
    (other / "campbell.png").write_bytes(b"not ours")
    assert main(["model", str(rig), "--out", str(other)]) == EXIT_INPUT
    assert (other / "campbell.png").read_bytes() == b"not ours"
    assert main(["model", str(rig), "--out", str(other), "--force"]) == EXIT_OK


def test_import_ross_cli(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "rig.yaml"
    assert main(["import-ross", str(DATA / "pedestals.toml"), str(out), "--json"]) == EXIT_OK
    assert "lateral" in capsys.readouterr().err
    assert main(["model", str(out), "--no-plots"]) == EXIT_OK
    assert main(["import-ross", str(DATA / "pedestals.toml"), str(out)]) == EXIT_INPUT  # exists
    bad = tmp_path / "bad.toml"
    bad.write_text("this is = = not toml")
    assert main(["import-ross", str(bad), str(tmp_path / "x.yaml")]) == EXIT_INPUT
    assert not (tmp_path / "x.yaml").exists()


def test_every_accepted_key_is_used_or_refused() -> None:
    d = _base()
    d["shaft"][0].update(shear=False, shear_method="hutchinson")
    _bad(d, "shaft[0].shear_method", "unused with shear: false")
    d = _base()
    d["shear_coefficient"] = 0.9  # beside shear_method: cowper: one of them would be ignored
    _bad(d, "shear_coefficient", "not both")
    d = _base()
    d["shear"] = False  # and shear_method: cowper, now unused
    _bad(d, "shear_method", "no shaft element has shear")
    d["shaft"][0]["shear"] = True  # one element with shear uses the rig's method: fine
    parse_config(d)
    lumped = yaml.safe_load((Path(__file__).resolve().parents[1] / "configs" / "three_mass_trial1.yaml").read_text())
    lumped["point_masses"] = [{"station": 1, "mass": 1.0}]
    _bad(lumped, "point_masses", "applies to kind: rotor only")
    lumped.pop("point_masses")
    lumped["gyroscopic"] = False
    _bad(lumped, "gyroscopic", "applies to kind: rotor only")


def test_implausible_values_and_inconsistent_constants() -> None:
    """Issue 16: physical ranges by field; more modes than the model has (a note since issue 32); E, G
    and poisson that disagree are accepted with a note saying which one is used where (the bundled
    ss416: E/2G - 1 = 0.350)."""
    d = _base()
    d["materials"]["steel"]["density"] = 1e308
    _bad(d, "materials.steel.density", "<= 100000")
    d = _base()
    d["discs"][0] = {"name": "disk0", "station": 3, "mass": 1e300, "polar_inertia": 0.1, "transverse_inertia": 0.1}
    _bad(d, "discs[0].mass", "<= 10000000")
    d = _base()
    d["analysis"] = {"n_modes": 40}  # issue 32: clamped with a note, no longer refused
    assert any("40 modes asked, but the model has 28 degrees of freedom" in n for n in parse_config(d).notes())
    from rotorcheck.config import load_config

    notes = load_config(configs_dir() / "crack_rig.yaml").notes()
    assert len(notes) == 1 and "0.350" in notes[0] and "poisson 0.3" in notes[0]
    d = _base()
    d["materials"]["steel"]["poisson"] = 211 / (2 * 81.2) - 1  # consistent: no note
    assert parse_config(d).notes() == []


def test_a_parametric_uncertainty_names_an_existing_parameter_at_load() -> None:
    d = _base()
    d["uncertainty"] = {"structure": "parametric", "parameter": "bearings.nosuch.kxx"}
    _bad(d, "uncertainty.parameter", "no bearings entry named 'nosuch'")
    d["uncertainty"]["parameter"] = "bearings.bearing0.cxx"
    _bad(d, "uncertainty.parameter", "not a supported rank-one parameter")
    d["uncertainty"]["parameter"] = "bearings.bearing0.kxx"
    assert parse_config(d).uncertainty.parameter == "bearings.bearing0.kxx"


def test_an_endless_device_as_rig_file_is_refused_without_reading_it_whole(capsys: pytest.CaptureFixture) -> None:
    """Issue 16: /dev/zero as the rig: exit 2 naming the file (at most MAX_RIG_BYTES + 1 bytes are read)."""
    if not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero here")
    assert main(["model", "/dev/zero", "--no-plots"]) == EXIT_INPUT
    assert "/dev/zero" in capsys.readouterr().err
