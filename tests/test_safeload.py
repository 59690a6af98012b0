"""Issue 32: bounded YAML and TOML parsing (rotorcheck.safeload): alias bombs and deep nesting are refused in
well under a second, naming the file and line; ordinary documents load as yaml.safe_load / tomllib load them."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml

from rotorcheck.cli import main
from rotorcheck.config import ConfigError, load_config
from rotorcheck.config import StrictLoader as _StrictLoader
from rotorcheck.errors import InputError
from rotorcheck.resources import configs_dir
from rotorcheck.safeload import MAX_DEPTH, YamlBoundError, load_toml, load_yaml, load_yaml_file, toml_depth


def _laughs(levels: int = 12, key: str = "lol") -> str:
    lines = [f'a0: &a0 ["{key}", "{key}", "{key}", "{key}", "{key}", "{key}", "{key}", "{key}", "{key}"]']
    for i in range(1, levels):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    return "\n".join(lines) + "\n"


BOMB_LIST = "- " + _laughs().replace("\n", "\n  ").rstrip() + "\n"  # the bomb inside a list
BOMB_UNKNOWN_KEY = (configs_dir() / "crack_rig.yaml").read_text() + "unknown_key:\n  " + \
    _laughs().replace("\n", "\n  ").rstrip() + "\n"  # the bomb under a key a rig does not have


@pytest.mark.parametrize("text", [BOMB_LIST, BOMB_UNKNOWN_KEY, _laughs()], ids=["list", "unknown-key", "top"])
@pytest.mark.parametrize("loader", [yaml.SafeLoader, _StrictLoader], ids=["safe", "rig"])
def test_alias_bombs_are_refused_fast(text: str, loader: type) -> None:
    t0 = time.monotonic()
    with pytest.raises(YamlBoundError, match=r"line \d+, column \d+: more than \d+ (aliases|nodes)"):
        load_yaml(text, loader)
    assert time.monotonic() - t0 < 2.0


def test_deep_nesting_is_refused() -> None:
    with pytest.raises(YamlBoundError, match=f"nested deeper than {MAX_DEPTH} levels"):
        load_yaml("[" * 100_000 + "]" * 100_000)
    with pytest.raises(YamlBoundError, match="nested deeper"):
        load_yaml("a:\n" + "".join("  " * i + f"k{i}:\n" for i in range(1, 80)))


def test_ordinary_documents_load_as_safe_load() -> None:
    text = (configs_dir() / "crack_rig.yaml").read_text()
    assert load_yaml(text, _StrictLoader) == yaml.load(text, Loader=_StrictLoader)
    shared = "base: &b {x: 1, y: [1, 2]}\nc1: *b\nc2: *b\n"
    assert load_yaml(shared) == yaml.safe_load(shared)
    nested = "[" * 30 + "]" * 30
    assert load_yaml("") is None and load_yaml(nested) == yaml.safe_load(nested)


def test_a_yaml_file_bomb_names_the_file(tmp_path: Path) -> None:
    p = tmp_path / "m.yaml"
    p.write_text(BOMB_LIST)
    with pytest.raises(InputError, match=rf"^{p}: line \d+, column \d+: malformed YAML: more than"):
        load_yaml_file(p, 10_000, "manifest")


def test_toml_depth_counts_brackets_outside_strings() -> None:
    assert toml_depth('a = [[1, 2], ["]]]", "[[["]]\n# [[[[[[\n[t]\nb = {c = [1]}\n') == 2
    assert toml_depth("a = '''[[[\n[[['''\nb = \"\\\"[\"\n") == 0
    assert toml_depth("a = " + "[" * 100_000 + "]" * 100_000) == 100_000


def test_deep_toml_is_refused_before_parsing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rotor = tmp_path / "deep.toml"
    rotor.write_text("a = " + "[" * 100_000 + "]" * 100_000 + "\n")
    with pytest.raises(InputError, match="nested 100000 deep"):
        load_toml(rotor.read_text(), rotor)
    out = tmp_path / "rig.yaml"
    t0 = time.monotonic()
    assert main(["import-ross", str(rotor), str(out)]) == 2
    assert time.monotonic() - t0 < 5
    assert f"error: {rotor}: arrays or tables nested 100000 deep: refused" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("text", [BOMB_LIST, "sweeps: " + "[" * 100_000 + "]" * 100_000 + "\n",
                                  "sweeps:\n- " + _laughs(key="x").replace("\n", "\n  ").rstrip() + "\n"],
                         ids=["bomb", "deep", "bomb-in-sweeps"])
def test_fleet_manifest_bombs_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str) -> None:
    manifest = tmp_path / "fleet.yaml"
    manifest.write_text(text)
    t0 = time.monotonic()
    assert main(["fleet", str(manifest), "--serial", "--out", str(tmp_path / "r")]) == 2
    assert time.monotonic() - t0 < 5
    assert f"error: {manifest}: line " in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_a_rig_file_alias_bomb_is_refused_naming_the_file(tmp_path: Path) -> None:
    """The rig loader goes through the bounded loader: a billion-laughs rig file is a ConfigError at once."""
    import time

    bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
        for p, c in zip("abcdefgh", "bcdefghi"))
    f = tmp_path / "bomb.yaml"
    f.write_text(bomb)
    t0 = time.perf_counter()
    with pytest.raises(ConfigError) as exc:
        load_config(f)
    assert str(f) in str(exc.value) and time.perf_counter() - t0 < 5.0
