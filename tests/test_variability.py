"""The ``variability:`` section (benign parameter ranges): parsing, errors by path, the normalized view
(rotorcheck.variability.benign_parameters) and applying values (with_benign) down to the FE matrices."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from rotorcheck.config import ConfigError, RigConfig, SpeedTable, json_schema, load_config, parse_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.variability import BenignParameter, benign_parameters, with_benign

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
E_SS416 = 224.08e9
K_BEARING = 1.5e7


@pytest.fixture()
def rig() -> dict[str, Any]:
    data = yaml.safe_load((CONFIGS / "crack_rig.yaml").read_text())
    data.pop("variability", None)
    return data


@pytest.fixture()
def lumped() -> dict[str, Any]:
    return yaml.safe_load((CONFIGS / "three_mass_trial1.yaml").read_text())


def _with(data: dict[str, Any], *entries: dict[str, Any]) -> RigConfig:
    d = copy.deepcopy(data)
    d["variability"] = list(entries)
    return parse_config(d, "rig.yaml")


def _error(data: dict[str, Any], *entries: dict[str, Any]) -> tuple[str, str]:
    with pytest.raises(ConfigError) as exc:
        _with(data, *entries)
    assert str(exc.value).startswith("rig.yaml: ")
    return exc.value.field, exc.value.message


def _one(data: dict[str, Any], entry: dict[str, Any]) -> BenignParameter:
    (p,) = benign_parameters(_with(data, entry))
    return p


# --------------------------------------------------------------------------------------------
# the bundled rig


def test_bundled_crack_rig_has_the_five_ranges() -> None:
    cfg = load_config(CONFIGS / "crack_rig.yaml")
    assert benign_parameters(cfg) == (
        BenignParameter("youngs_modulus", "factor", -0.02, 0.02, "%", ("materials", "*", "youngs_modulus")),
        BenignParameter("bearing_stiffness.nme", "factor", -0.03, 0.03, "%", ("bearings", "nme", "stiffness")),
        BenignParameter("bearing_stiffness.me", "factor", -0.03, 0.03, "%", ("bearings", "me", "stiffness")),
        BenignParameter("sensor_gain", "factor", -0.01, 0.01, "%", ("gain", "sensor")),
        BenignParameter("speed", "offset", -20.0, 20.0, "rpm", ("speed",)),
    )


def test_truth_config_has_no_section_and_empty_section_keeps_the_hash(rig: dict[str, Any]) -> None:
    truth = load_config(CONFIGS / "crack_rig_truth.yaml")
    assert truth.variability == [] and benign_parameters(truth) == ()
    plain = parse_config(rig, "a.yaml")
    empty = _with(rig)
    assert plain.sha256() == empty.sha256()  # configs without the section hash as before it existed
    assert _with(rig, {"parameter": "sensor_gain", "percent": 1}).sha256() != plain.sha256()


def test_json_schema_has_the_section() -> None:
    schema = json_schema()
    assert schema["properties"]["variability"]["items"] == {"$ref": "#/$defs/BenignRange"}
    props = schema["$defs"]["BenignRange"]["properties"]
    assert {"parameter", "percent", "range_percent", "absolute", "rpm", "temperature_c", "de_dt"} <= set(props)


# --------------------------------------------------------------------------------------------
# every form, normalized


def test_forms_normalize_to_hand_computed_ranges(rig: dict[str, Any]) -> None:
    assert _one(rig, {"parameter": "bearing_stiffness", "bearing": "me", "range_percent": [-3, 5]}) == (
        BenignParameter("bearing_stiffness.me", "factor", -0.03, 0.05, "%", ("bearings", "me", "stiffness")))
    # absolute stiffness: a factor range relative to the nominal 1.5e7 N/m, unit strings accepted
    p = _one(rig, {"parameter": "bearing_stiffness", "bearing": "nme", "absolute": ["14.7 MN/m", 1.56e7]})
    assert p.kind == "factor" and p.lo == pytest.approx(-0.02, rel=1e-12) and p.hi == pytest.approx(0.04, rel=1e-12)
    # absolute damping around a nominal 0: an offset in N s/m
    assert _one(rig, {"parameter": "bearing_damping", "bearing": "me", "absolute": [0, "50 N s/m"]}) == (
        BenignParameter("bearing_damping.me", "offset", 0.0, 50.0, "N s/m", ("bearings", "me", "damping")))
    assert _one(rig, {"parameter": "actuator_gain", "percent": 1}) == (
        BenignParameter("actuator_gain", "factor", -0.01, 0.01, "%", ("gain", "actuator")))
    assert _one(rig, {"parameter": "speed", "rpm": "0.5 Hz"}) == (
        BenignParameter("speed", "offset", -30.0, 30.0, "rpm", ("speed",)))
    assert _one(rig, {"parameter": "disc_mass", "disc": "amb_rotor", "percent": 1}) == (
        BenignParameter("disc_mass.amb_rotor", "factor", -0.01, 0.01, "%", ("discs", "amb_rotor", "mass")))
    p = _one(rig, {"parameter": "youngs_modulus", "material": "ss416", "absolute": ["220 GPa", "230 GPa"]})
    assert p.name == "youngs_modulus.ss416" and p.target == ("materials", "ss416", "youngs_modulus")
    assert (p.lo, p.hi) == pytest.approx((220e9 / E_SS416 - 1, 230e9 / E_SS416 - 1), rel=1e-12)
    # the generic path form, with or without "parameter: path"
    assert _one(rig, {"path": "materials.ss416.density", "percent": 1}) == (
        BenignParameter("path:materials.ss416.density", "factor", -0.01, 0.01, "%", ("materials", "ss416", "density")))
    p = _one(rig, {"parameter": "path", "path": "damping.ratios[0]", "absolute": [0.008, 0.012]})
    assert p.name == "path:damping.ratios[0]" and p.target == ("damping", "ratios", "0")
    assert (p.lo, p.hi) == pytest.approx((-0.2, 0.2), rel=1e-12)
    p = _one(rig, {"path": "bearings.me.cxx", "absolute": [0, 20]})  # nominal 0: an offset
    assert (p.kind, p.lo, p.hi, p.unit) == ("offset", 0.0, 20.0, "N s/m")


@pytest.mark.parametrize("de_dt", [-6.0e7, "-60 MPa/K", "-6e7"])
def test_temperature_form(rig: dict[str, Any], de_dt: Any) -> None:
    """E(T) = E_ref + de_dt (T - T_ref): T in [10, 50], T_ref 20, de_dt -6e7 Pa/K."""
    p = _one(rig, {"parameter": "youngs_modulus", "material": "ss416", "temperature_c": [10, 50],
                   "reference_c": 20, "de_dt": de_dt})
    assert (p.name, p.kind, p.unit) == ("youngs_modulus.ss416", "factor", "%")
    assert p.lo == pytest.approx(-30 * 6e7 / E_SS416, rel=1e-12)  # 50 degC: softer
    assert p.hi == pytest.approx(+10 * 6e7 / E_SS416, rel=1e-12)  # 10 degC: stiffer
    assert p.lo < 0 < p.hi


def test_lumped_forms(lumped: dict[str, Any]) -> None:
    cfg = _with(lumped, {"parameter": "mass", "mass": "m1", "percent": 2},
                {"parameter": "spring_stiffness", "spring": "k1", "absolute": ["800 N/m", 900]},
                {"parameter": "sensor_gain", "range_percent": [-1, 2]})
    m, k, g = benign_parameters(cfg)
    assert m == BenignParameter("mass.m1", "factor", -0.02, 0.02, "%", ("masses", "m1", "mass"))
    assert (k.name, k.target) == ("spring_stiffness.k1", ("lumped_springs", "k1", "stiffness"))
    assert (k.lo, k.hi) == pytest.approx((800 / 842.3 - 1, 900 / 842.3 - 1), rel=1e-12)
    assert (g.lo, g.hi) == (-0.01, 0.02)
    new, speed, sensor, actuator = with_benign(cfg, {"mass.m1": 0.02, "spring_stiffness.k1": -0.05})
    assert new.masses[0].mass == pytest.approx(2.6 * 1.02, rel=1e-15) and new.masses[1] == cfg.masses[1]
    assert new.lumped_springs[0].stiffness == pytest.approx(842.3 * 0.95, rel=1e-15)
    assert new.lumped_springs[0].damping == cfg.lumped_springs[0].damping
    assert (speed, sensor, actuator) == (0.0, 1.0, 1.0)


# --------------------------------------------------------------------------------------------
# errors by path


BAD = {
    "no form": ([{"parameter": "sensor_gain"}], "variability[0]",
                "give exactly one of percent, range_percent, absolute, rpm, temperature_c"),
    "two forms": ([{"parameter": "sensor_gain", "percent": 1, "range_percent": [-1, 1]}], "variability[0]",
                  "give exactly one of percent, range_percent, absolute, rpm, temperature_c"),
    "unknown bearing": (
        [{"parameter": "sensor_gain", "percent": 1}, {"parameter": "speed", "rpm": 20},
         {"parameter": "bearing_stiffness", "bearing": "xx", "percent": 3}],
        "variability[2].bearing", "unknown bearing 'xx' (known: nme, me)"),
    "bearing missing": ([{"parameter": "bearing_damping", "percent": 3}], "variability[0].bearing",
                        "required for parameter bearing_damping"),
    "selector not used": ([{"parameter": "sensor_gain", "bearing": "nme", "percent": 1}],
                          "variability[0].bearing", "not used by parameter sensor_gain"),
    "unknown material": ([{"parameter": "youngs_modulus", "material": "brass", "percent": 1}],
                         "variability[0].material", "unknown material 'brass' (known: ss416)"),
    "unknown disc": ([{"parameter": "disc_mass", "disc": "rim", "percent": 1}], "variability[0].disc",
                     "unknown disc 'rim' (known: disc, amb_rotor)"),
    "unknown parameter": ([{"parameter": "humidity", "percent": 1}], "variability[0].parameter",
                          "unknown parameter 'humidity' (known: youngs_modulus, bearing_stiffness, bearing_damping, "
                          "sensor_gain, actuator_gain, speed, disc_mass, mass, spring_stiffness, path)"),
    "unknown key": ([{"parameter": "speed", "rpm": 1, "tolerance": 2}], "variability[0].tolerance", "unknown key"),
    "duplicate": ([{"parameter": "sensor_gain", "percent": 1}, {"parameter": "sensor_gain", "percent": 2}],
                  "variability[1]", "duplicate of variability[0] (sensor_gain)"),
    "overlap": ([{"parameter": "youngs_modulus", "percent": 2},
                 {"parameter": "youngs_modulus", "material": "ss416", "percent": 1}],
                "variability[1]", "youngs_modulus.ss416 changes materials.ss416.youngs_modulus, which variability[0] "
                "(youngs_modulus) already varies; give each quantity one range"),
    "overlap by path": ([{"parameter": "bearing_stiffness", "bearing": "nme", "percent": 3},
                         {"path": "bearings.nme.kyy", "percent": 1}],
                        "variability[1]", "path:bearings.nme.kyy changes bearings[0].kyy, which variability[0] "
                        "(bearing_stiffness.nme) already varies; give each quantity one range"),
    "percent zero": ([{"parameter": "sensor_gain", "percent": 0}], "variability[0].percent", "must be > 0.0"),
    "E to zero": ([{"parameter": "youngs_modulus", "percent": 100}], "variability[0].percent",
                  "100 % would make youngs_modulus <= 0 (must be < 100)"),
    "stiffness to zero": ([{"parameter": "bearing_stiffness", "bearing": "me", "range_percent": [-120, 5]}],
                          "variability[0].range_percent",
                          "-120 % would make bearing 'me' stiffness <= 0 (lower bound must be > -100)"),
    "mass to zero": ([{"parameter": "disc_mass", "disc": "disc", "absolute": [0, 1]}], "variability[0].absolute",
                     "lower bound 0 would make disc 'disc' mass <= 0"),
    "E negative by temperature": (
        [{"parameter": "youngs_modulus", "temperature_c": [0, 5000], "reference_c": 20, "de_dt": "-60 MPa/K"}],
        "variability[0].temperature_c", "youngs_modulus would be <= 0 in [0, 5000] degC"),
    "range order": ([{"parameter": "sensor_gain", "range_percent": [2, -1]}], "variability[0].range_percent",
                    "must be [lo, hi] with lo < hi"),
    "absolute misses nominal": ([{"parameter": "bearing_stiffness", "bearing": "nme", "absolute": [1.6e7, 2e7]}],
                                "variability[0].absolute",
                                "[1.6e+07, 2e+07] does not contain the nominal bearing 'nme' stiffness 1.5e+07"),
    "absolute wrong unit": ([{"parameter": "bearing_damping", "bearing": "me", "absolute": [0, "50 N"]}],
                            "variability[0].absolute",
                            "unit 'N' is not a damping unit (use one of 'N s/m', 'Ns/m', 'N*s/m', 'kg/s' or a bare "
                            "SI number)"),
    "negative damping": ([{"parameter": "bearing_damping", "bearing": "me", "absolute": [-5, 50]}],
                         "variability[0].absolute", "lower bound -5 would make bearing 'me' damping < 0"),
    "relative on zero damping": ([{"parameter": "bearing_damping", "bearing": "me", "percent": 10}],
                                 "variability[0].percent",
                                 "bearing 'me' has no damping (cxx = cyy = 0), a relative range changes nothing; "
                                 "give absolute"),
    "speed in percent": ([{"parameter": "speed", "percent": 1}], "variability[0].percent",
                         "speed takes rpm (a +- tolerance in rpm)"),
    "rpm on a gain": ([{"parameter": "sensor_gain", "rpm": 5}], "variability[0].rpm",
                      "only for parameter speed, not sensor_gain"),
    "temperature on stiffness": (
        [{"parameter": "bearing_stiffness", "bearing": "me", "temperature_c": [0, 40], "reference_c": 20,
          "de_dt": 1.0}], "variability[0].temperature_c", "only for parameter youngs_modulus, not bearing_stiffness"),
    "temperature without de_dt": ([{"parameter": "youngs_modulus", "temperature_c": [0, 40], "reference_c": 20}],
                                  "variability[0].de_dt", "required with temperature_c"),
    "de_dt without temperature": ([{"parameter": "youngs_modulus", "percent": 2, "de_dt": -6e7}],
                                  "variability[0].de_dt", "only with temperature_c"),
    "de_dt not per kelvin": (
        [{"parameter": "youngs_modulus", "temperature_c": [0, 40], "reference_c": 20, "de_dt": "-60 MPa"}],
        "variability[0].de_dt", "expected Pa/K: a number or a string such as '-60 MPa/K', got '-60 MPa'"),
    "lumped parameter on a rotor": ([{"parameter": "mass", "mass": "m1", "percent": 1}],
                                    "variability[0].parameter", "mass applies to lumped rigs only (this rig is rotor)"),
    "path outside the model": ([{"path": "analysis.n_modes", "percent": 1}], "variability[0].path",
                               "'analysis' is not a model section (use one of materials, stations, shaft, discs, "
                               "bearings, springs, masses, lumped_springs, damping)"),
    "path not a real": ([{"path": "discs.disc.station", "percent": 1}], "variability[0].path",
                        "discs.disc.station is not a real-valued quantity"),
    "path unknown field": ([{"path": "materials.ss416.colour", "percent": 1}], "variability[0].path",
                           "materials.ss416 has no field 'colour'"),
    "path makes the rig invalid": ([{"path": "materials.ss416.poisson", "percent": 80}], "variability[0].percent",
                                   "materials.ss416.poisson = 0.54 is not a valid rig "
                                   "(materials.ss416.poisson: must be < 0.5)"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_errors_name_the_entry(rig: dict[str, Any], case: str) -> None:
    entries, field, message = BAD[case]
    got_field, got_message = _error(rig, *entries)
    assert (got_field, got_message) == (field, message)


def test_rotor_parameter_on_a_lumped_rig(lumped: dict[str, Any]) -> None:
    assert _error(lumped, {"parameter": "bearing_stiffness", "bearing": "nme", "percent": 3}) == (
        "variability[0].parameter", "bearing_stiffness applies to rotor rigs only (this rig is lumped)")
    assert _error(lumped, {"parameter": "spring_stiffness", "spring": "k9", "percent": 3}) == (
        "variability[0].spring", "unknown spring 'k9' (known: k1, k2, k3)")


def test_bad_section_through_load_config(rig: dict[str, Any], tmp_path: Path) -> None:
    rig["variability"] = [{"parameter": "speed", "rpm": 20}, {"parameter": "speed", "rpm": 10}]
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(rig))
    with pytest.raises(ConfigError) as exc:
        load_config(path)
    assert str(exc.value) == f"{path}: variability[1]: duplicate of variability[0] (speed)"


# --------------------------------------------------------------------------------------------
# with_benign


def _crack_rig() -> RigConfig:
    return load_config(CONFIGS / "crack_rig.yaml")


def test_bearing_stiffness_changes_k_at_the_bearing_only() -> None:
    cfg = _crack_rig()
    new, speed, sensor, actuator = with_benign(cfg, {"bearing_stiffness.nme": 0.02})
    assert (speed, sensor, actuator) == (0.0, 1.0, 1.0)
    s0, s1 = build_system(cfg), build_system(new)
    M0, _, G0, K0 = s0.matrices(0.0)
    M1, _, G1, K1 = s1.matrices(0.0)
    dK = K1 - K0
    x, y = s0.dof(station=2, direction="x"), s0.dof(station=2, direction="y")
    expected = np.zeros_like(dK)
    expected[x, x] = expected[y, y] = 0.02 * K_BEARING
    assert dK[x, x] == pytest.approx(0.02 * K_BEARING, rel=1e-9)
    np.testing.assert_allclose(dK, expected, rtol=0, atol=1e-12 * K_BEARING)
    np.testing.assert_array_equal(M1, M0)
    np.testing.assert_array_equal(G1, G0)
    assert new.bearings[1] == cfg.bearings[1] and new.materials == cfg.materials


def test_youngs_modulus_scales_the_shaft_stiffness() -> None:
    cfg = _crack_rig()
    x = -0.015
    new, *_ = with_benign(cfg, {"youngs_modulus": x})
    mat = new.materials["ss416"]
    assert mat.youngs_modulus == pytest.approx(E_SS416 * (1 + x), rel=1e-15)
    assert mat.shear_modulus == pytest.approx(83e9 * (1 + x), rel=1e-15)  # G with E: phi unchanged
    assert mat.poisson == cfg.materials["ss416"].poisson and mat.density == cfg.materials["ss416"].density
    s0, s1 = build_system(cfg), build_system(new)
    K0, K1 = s0.matrices(0.0)[3], s1.matrices(0.0)[3]
    bearing_dofs = [s0.dof(station=st, direction=d) for st in (2, 9) for d in ("x", "y")]
    for K in (K0, K1):  # the shaft alone: bearings out
        for d in bearing_dofs:
            K[d, d] -= K_BEARING
    scale = np.abs(K0).max()
    np.testing.assert_allclose(K1, (1 + x) * K0, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(s1.matrices(0.0)[0], s0.matrices(0.0)[0])  # mass unchanged


def test_speed_gains_and_damping(rig: dict[str, Any]) -> None:
    cfg = _with(rig, {"parameter": "speed", "rpm": 20}, {"parameter": "sensor_gain", "percent": 1},
                {"parameter": "actuator_gain", "percent": 1},
                {"parameter": "bearing_damping", "bearing": "me", "absolute": [0, 50]})
    new, speed, sensor, actuator = with_benign(
        cfg, {"speed": -12.5, "sensor_gain": 0.01, "actuator_gain": -0.005, "bearing_damping.me": 30.0})
    assert (speed, sensor, actuator) == (-12.5, 1.01, 0.995)
    me = new.bearings[1]
    assert (me.cxx, me.cyy, me.cxy, me.cyx) == (30.0, 30.0, 0.0, 0.0)
    assert new.bearings[0] == cfg.bearings[0]
    unchanged, *rest = with_benign(cfg, {})
    assert unchanged == cfg and rest == [0.0, 1.0, 1.0]
    with pytest.raises(ValueError, match=r"would make bearings\[1\]\.cxx < 0"):
        with_benign(cfg, {"bearing_damping.me": -1.0})


def test_speed_tables_and_damping_factor_scale(rig: dict[str, Any]) -> None:
    rig["bearings"][0]["kxx"] = {"speed_rpm": [0, 1000], "values": [1.5e7, 1.7e7]}
    rig["bearings"][0].update(cxx=100.0, cyy=100.0, cxy=10.0, kxy=-1e5)
    cfg = _with(rig, {"parameter": "bearing_stiffness", "bearing": "nme", "percent": 3},
                {"parameter": "bearing_damping", "bearing": "nme", "percent": 10})
    new, *_ = with_benign(cfg, {"bearing_stiffness.nme": 0.03, "bearing_damping.nme": -0.1})
    b = new.bearings[0]
    assert isinstance(b.kxx, SpeedTable) and b.kxx.speed_rpm == [0.0, 1000.0]
    assert b.kxx.values == pytest.approx([1.5e7 * 1.03, 1.7e7 * 1.03], rel=1e-15)
    assert (b.kyy, b.kxy) == pytest.approx((1.5e7 * 1.03, -1e5 * 1.03), rel=1e-15)
    assert (b.cxx, b.cyy, b.cxy, b.cyx) == pytest.approx((90.0, 90.0, 9.0, 0.0), rel=1e-15)


def test_path_parameter_applies(rig: dict[str, Any]) -> None:
    cfg = _with(rig, {"path": "materials.ss416.density", "percent": 1},
                {"path": "bearings.me.cxx", "absolute": [0, 20]})
    new, *_ = with_benign(cfg, {"path:materials.ss416.density": 0.01, "path:bearings.me.cxx": 7.0})
    assert new.materials["ss416"].density == pytest.approx(7809 * 1.01, rel=1e-15)
    assert (new.bearings[1].cxx, new.bearings[1].cyy) == (7.0, 0.0)


def test_unknown_or_unphysical_values_raise() -> None:
    cfg = _crack_rig()
    with pytest.raises(ValueError, match=r"not benign parameters of rig 'crack_rig': actuator_gain, bogus "
                                         r"\(its variability section has: youngs_modulus, "):
        with_benign(cfg, {"actuator_gain": 0.01, "bogus": 1.0})
    with pytest.raises(ValueError, match="youngs_modulus: x = -1"):
        with_benign(cfg, {"youngs_modulus": -1.0})
    with pytest.raises(ValueError, match="finite"):
        with_benign(cfg, {"speed": float("nan")})
