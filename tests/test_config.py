"""Rig config validation: every bad input names the file and the field; the CLI exits 2."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml

from rotorcheck.cli import EXIT_INPUT, main
from rotorcheck.config import ConfigError, json_schema, load_config, parse_config
from rotorcheck.units import parse_quantity

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@pytest.fixture()
def rig() -> dict:
    return yaml.safe_load((CONFIGS / "crack_rig.yaml").read_text())


def _write(tmp_path: Path, data: dict | str, name: str = "rig.yaml") -> Path:
    p = tmp_path / name
    p.write_text(data if isinstance(data, str) else yaml.safe_dump(data))
    return p


def test_bundled_configs_load() -> None:
    for p in sorted(CONFIGS.glob("*.yaml")):
        cfg = load_config(p)
        assert cfg.rig_id
        assert len(cfg.sha256()) == 64


def test_units_convert_to_si() -> None:
    assert parse_quantity("16 mm", "length") == pytest.approx(0.016, rel=1e-15)
    assert parse_quantity("224.08 GPa", "pressure") == pytest.approx(224.08e9, rel=1e-15)
    assert parse_quantity("0.2 g m", "unbalance") == pytest.approx(2e-4, rel=1e-15)
    assert parse_quantity("1.65e7", "stiffness") == 1.65e7  # YAML 1.1 reads this as a string
    assert parse_quantity(3, "mass") == 3.0


def test_unit_spelling_does_not_change_hash(rig: dict) -> None:
    a = parse_config(rig, "a.yaml")
    b_data = copy.deepcopy(rig)
    b_data["shaft"][0]["outer_diameter"] = "16 mm"
    b = parse_config(b_data, "b.yaml")
    assert a.sha256() == b.sha256()
    b_data["shaft"][0]["outer_diameter"] = "17 mm"
    assert parse_config(b_data, "c.yaml").sha256() != a.sha256()


BAD_CASES = {
    "missing field": (lambda d: d["discs"][0].pop("mass"), "discs[0].mass", "missing"),
    # negative direct stiffness is allowed (seals, magnetic bearings; issue 20); negative damping is not
    "negative damping": (lambda d: d["bearings"][1].__setitem__("cxx", -1.0), "bearings[1].cxx", ">= 0"),
    "station out of range": (
        lambda d: d["discs"][0].__setitem__("station", 12), "discs[0].station", "out of range"),
    "unknown key": (lambda d: d["bearings"][0].__setitem__("kxz", 1.0), "bearings[0].kxz", "unknown key"),
    "bad unit string": (
        lambda d: d["shaft"][2].__setitem__("outer_diameter", "16 furlongs"),
        "shaft[2].outer_diameter", "furlongs"),
    "wrong dimension": (
        lambda d: d["materials"]["ss416"].__setitem__("density", "3 GPa"),
        "materials.ss416.density", "not a density unit"),
    "unknown material": (
        lambda d: d["shaft"][3].__setitem__("material", "brass"), "shaft[3].material", "brass"),
    "bad port": (lambda d: d["ports"]["sensor"].__setitem__("station", 11), "ports.sensor.station", "1..10"),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_config_names_field(rig: dict, tmp_path: Path, case: str) -> None:
    mutate, field, words = BAD_CASES[case]
    data = copy.deepcopy(rig)
    mutate(data)
    path = _write(tmp_path, data)
    with pytest.raises(ConfigError) as exc:
        load_config(path)
    assert exc.value.field == field
    assert str(path) in str(exc.value)
    assert words in str(exc.value)


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_config_cli_exit_2(rig: dict, tmp_path: Path, case: str, capsys: pytest.CaptureFixture) -> None:
    mutate, field, _ = BAD_CASES[case]
    data = copy.deepcopy(rig)
    mutate(data)
    path = _write(tmp_path, data)
    rc = main(["model", str(path), "--out", str(tmp_path / "out")])
    assert rc == EXIT_INPUT
    captured = capsys.readouterr()
    assert field in captured.err and str(path.name) in captured.err
    assert captured.out == ""
    assert not (tmp_path / "out").exists()  # nothing written on bad input


def test_malformed_yaml(tmp_path: Path) -> None:
    path = _write(tmp_path, "rig_id: x\nstations: [0, 1\nshaft: []\n")
    with pytest.raises(ConfigError) as exc:
        load_config(path)
    assert "malformed YAML" in str(exc.value) and "line" in str(exc.value)
    assert main(["model", str(path)]) == EXIT_INPUT


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="file not found"):
        load_config(tmp_path / "nope.yaml")


def test_json_schema_exports() -> None:
    schema = json_schema()
    assert schema["title"] == "rotorcheck rig"
    assert "bearings" in schema["properties"] and "rig_id" in schema["required"]
    assert "ports" in schema["properties"] and "ports" not in schema["required"]  # optional (issue 20)
    assert schema["additionalProperties"] is False


def test_damage_element_must_touch_the_damage_port(rig: dict) -> None:
    """damage.element is checked against the damage port (element e joins stations e and e + 1)."""
    ok = copy.deepcopy(rig)
    ok["damage"]["element"] = ok["damage"]["port"]["station"] - 1  # the element on the other side: fine
    parse_config(ok, "ok.yaml")
    bad = copy.deepcopy(rig)
    bad["damage"]["element"] = bad["damage"]["port"]["station"] + 2
    with pytest.raises(ConfigError, match=r"damage\.element: element .* the damage port is at station"):
        parse_config(bad, "bad.yaml")
