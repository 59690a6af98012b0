"""Rig files that were accepted though wrong, or refused only as internal errors (issue 16): each is now
exit 2 with a message naming the file and the field or line, and nothing is written."""

from __future__ import annotations

from pathlib import Path

import pytest

from rotorcheck.cli import EXIT_INPUT, EXIT_OK, main
from rotorcheck.config import MAX_RIG_BYTES, ConfigError, load_config
from rotorcheck.resources import configs_dir

RIG = configs_dir() / "crack_rig.yaml"


def _variant(tmp_path: Path, old: str, new: str, name: str = "rig.yaml") -> Path:
    text = RIG.read_text()
    assert old in text, old
    p = tmp_path / name
    p.write_text(text.replace(old, new, 1))
    return p


def test_duplicate_key_is_refused_with_its_line(tmp_path: Path) -> None:
    text = RIG.read_text()
    p = tmp_path / "dup.yaml"
    p.write_text(text + "\nrig_id: another\n")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    msg = str(exc.value)
    assert str(p) in msg and "'rig_id' given twice" in msg and "line" in msg


def test_leading_zero_integer_is_refused(tmp_path: Path) -> None:
    p = _variant(tmp_path, "{station: 8, direction: x}", "{station: 010, direction: x}")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    assert "'010'" in str(exc.value) and "octal 8" in str(exc.value) and "write 10" in str(exc.value)


@pytest.mark.parametrize("bad", ["1e400", ".nan", ".inf", "-.inf"])
def test_non_finite_numbers_are_refused_by_field(tmp_path: Path, bad: str) -> None:
    p = _variant(tmp_path, "density: 7809", f"density: {bad}")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    assert exc.value.field == "materials.ss416.density" and "finite" in exc.value.message


@pytest.mark.parametrize("payload", [b"\xff\xfe" + "rig_id: x\n".encode("utf-16-le"),
                                     "rig_id: caf\xe9\n".encode("latin-1"), b"\x00\x01\x02binary"])
def test_binary_latin1_utf16_files_are_refused(tmp_path: Path, payload: bytes) -> None:
    p = tmp_path / "enc.yaml"
    p.write_bytes(payload)
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    assert "UTF-8" in str(exc.value) or "NUL" in str(exc.value)


def test_deep_nesting_and_huge_files_are_refused(tmp_path: Path) -> None:
    deep = tmp_path / "deep.yaml"
    deep.write_text("rig_id: " + "[" * 100_000 + "]" * 100_000 + "\n")
    with pytest.raises(ConfigError) as exc:
        load_config(deep)
    assert "nested too deeply" in str(exc.value) or "malformed YAML" in str(exc.value)
    big = tmp_path / "big.yaml"
    big.write_text(RIG.read_text() + "\n# " + "x" * MAX_RIG_BYTES + "\n")
    with pytest.raises(ConfigError) as exc:
        load_config(big)
    assert "at most" in str(exc.value)


def test_cli_exits_2_naming_the_file_and_writes_nothing(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    p = _variant(tmp_path, "density: 7809", "density: 1e400")
    out = tmp_path / "out"
    assert main(["model", str(p), "--out", str(out)]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert str(p) in err and "materials.ss416.density" in err and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())
    # the bundled rigs still load (quoted strings, comments and normal integers are untouched)
    for rig in sorted(configs_dir().glob("*.yaml")):
        load_config(rig)
    assert main(["model", str(RIG), "--out", str(tmp_path / "ok"), "--no-plots"]) == EXIT_OK


def test_two_bearings_at_one_station_and_lumped_masses_in_a_rotor(tmp_path: Path) -> None:
    import yaml

    data = yaml.safe_load(RIG.read_text())
    first = data["bearings"][0]
    cases = {
        "bearings[2].station": {**data, "bearings": [*data["bearings"], {**first, "name": "extra"}]},
        "masses": {**data, "masses": [{"name": "m", "mass": 10.0}]},
    }
    for field, doc in cases.items():
        p = tmp_path / "rig.yaml"
        p.write_text(yaml.safe_dump(doc))
        with pytest.raises(ConfigError) as exc:
            load_config(p)
        assert exc.value.field == field, (field, str(exc.value))
