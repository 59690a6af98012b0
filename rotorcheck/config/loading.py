"""Reading a rig file: bounded, strict YAML, validation into :class:`RigConfig` with errors naming the file and
the field, the benign ranges resolved, and the JSON Schema for editors."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from rotorcheck.config.base import ConfigError
from rotorcheck.config.errors import first_error
from rotorcheck.config.resolve import resolve_benign
from rotorcheck.config.rig import RigConfig
from rotorcheck.fileio import read_bounded_text
from rotorcheck.safeload import load_yaml, yaml_error_message


def parse_config(data: Any, source: str | Path = "<config>") -> RigConfig:
    """Validate a mapping (already parsed YAML) into a :class:`RigConfig`."""
    if not isinstance(data, dict):
        raise ConfigError(source, "", "the top level must be a mapping of keys")
    try:
        cfg = RigConfig.model_validate(data)
    except ValidationError as exc:
        field, msg = first_error(exc)
        raise ConfigError(source, field, msg) from None
    try:
        resolve_benign(cfg)  # every variability entry against the rig: refused here, naming the entry
    except ValueError as exc:
        field, _, msg = str(exc).partition(": ")
        raise ConfigError(source, field, msg) from None
    return cfg


#: a rig file larger than this is refused before it is parsed (bytes)
MAX_RIG_BYTES = 2_000_000


class StrictLoader(yaml.SafeLoader):
    """Safe YAML with two YAML 1.1 surprises refused: a key given twice in one mapping (the later one
    silently won) and an integer with a leading zero (``010`` was read as octal 8)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key {key!r} given twice (first on line {seen[key] + 1})", key_node.start_mark)
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node: yaml.ScalarNode) -> int:
        text = str(node.value).replace("_", "")
        if re.fullmatch(r"[-+]?0[0-7]+", text):
            raise yaml.constructor.ConstructorError(
                None, None, f"{node.value!r}: a leading zero (YAML 1.1 reads it as octal "
                f"{int(text, 8)}); write {int(text, 10)} or quote it", node.start_mark)
        return int(super().construct_yaml_int(node))


StrictLoader.add_constructor("tag:yaml.org,2002:int", StrictLoader.construct_yaml_int)


def _non_finite(data: Any, path: str = "") -> str | None:
    """The path of the first NaN or infinite number in parsed YAML (``1e400`` reads as inf), else None."""
    if isinstance(data, float) and not math.isfinite(data):
        return path or "(top level)"
    if isinstance(data, dict):
        for k, v in data.items():
            hit = _non_finite(v, f"{path}.{k}" if path else str(k))
            if hit:
                return hit
    elif isinstance(data, list):
        for i, v in enumerate(data):
            hit = _non_finite(v, f"{path}[{i}]")
            if hit:
                return hit
    return None


def load_config(path: str | Path) -> RigConfig:
    """Read and validate a rig YAML file; raises :class:`ConfigError` naming file and field. Refused
    before validation: files over :data:`MAX_RIG_BYTES`, text that is not UTF-8, duplicate keys,
    integers with a leading zero, nesting too deep to parse, YAML alias bombs (more aliases or expanded nodes
    than :mod:`rotorcheck.safeload` allows), NaN or infinite numbers (by field)."""
    p = Path(path)
    text = read_bounded_text(p, MAX_RIG_BYTES, "rig file", ConfigError)
    try:
        data = load_yaml(text, StrictLoader)  # bounded: aliases, nesting and expanded nodes (issue 32)
    except yaml.YAMLError as exc:
        where, problem = yaml_error_message(exc)
        raise ConfigError(p, "", f"malformed YAML: {where + ': ' if where else ''}{problem}") from None
    except RecursionError:
        raise ConfigError(p, "", "nested too deeply to be a rig file") from None
    bad = _non_finite(data)
    if bad is not None:
        raise ConfigError(p, bad, "not a finite number (NaN, inf, or beyond the float range such as 1e400)")
    return parse_config(data, p)


def json_schema() -> dict[str, Any]:
    """JSON Schema of the rig file, for editors."""
    schema = RigConfig.model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "rotorcheck rig"
    return schema

