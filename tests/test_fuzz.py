"""Issue 16: hypothesis-based fuzzing of the rig loader and the sweep reader (bounded, derandomized so CI is
repeatable): whatever the input, the only failures are the documented error classes (UserInputError:
ConfigError, InputError, SweepFormatError), each naming the file."""

from __future__ import annotations

import copy
import shutil
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rotorcheck.config import ConfigError, load_config, parse_config
from rotorcheck.errors import UserInputError
from rotorcheck.resources import configs_dir, samples_dir
from rotorcheck.sweep import read_sweep

RIG = yaml.safe_load((configs_dir() / "crack_rig.yaml").read_text())
SWEEP = samples_dir() / "crack_rig" / "healthy_0rpm.h5"
FUZZ = settings(max_examples=120, derandomize=True, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

LEAVES = st.one_of(
    st.none(), st.booleans(), st.integers(-10**30, 10**30),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
    st.sampled_from(["16 mm", "1e400", "3 kg", "-0", "010", "nan", "224 GPa", "1 rpm"]),
    st.lists(st.floats(allow_nan=True), max_size=3), st.dictionaries(st.text(max_size=5), st.integers(), max_size=2),
)


def _paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix] if prefix else []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


PATHS = _paths(RIG)


def _mutate(doc: dict[str, Any], edits: list[tuple[int, str, Any]]) -> dict[str, Any]:
    d = copy.deepcopy(doc)
    for idx, how, value in edits:
        path = PATHS[idx % len(PATHS)]
        parent: Any = d
        try:
            for p in path[:-1]:
                parent = parent[p]
            key = path[-1]
            if how == "set":
                parent[key] = value
            elif how == "delete" and isinstance(parent, dict):
                parent.pop(key, None)
            elif how == "add" and isinstance(parent, dict):
                parent[f"x_{key}"] = value
        except (KeyError, IndexError, TypeError):
            continue  # an earlier edit removed the path
    return d


@FUZZ
@given(st.lists(st.tuples(st.integers(0, 10**6), st.sampled_from(["set", "delete", "add"]), LEAVES),
                min_size=1, max_size=4))
def test_rig_loader_fails_only_with_config_errors(edits: list[tuple[int, str, Any]]) -> None:
    try:
        parse_config(_mutate(RIG, edits), "fuzz.yaml")
    except ConfigError as exc:
        assert str(exc).startswith("fuzz.yaml")


@FUZZ
@given(st.one_of(st.binary(max_size=400), st.text(max_size=400).map(str.encode)))
def test_rig_text_fails_only_with_config_errors(tmp_path: Path, raw: bytes) -> None:
    p = tmp_path / "rig.yaml"
    p.write_bytes(raw)
    try:
        load_config(p)
    except ConfigError as exc:
        assert str(p) in str(exc)


DATASETS = ["runs/0rpm/frequency", "runs/0rpm/frf", "runs/0rpm/input_phasor", "runs/0rpm/output_phasor",
            "runs/0rpm/output_var", "runs/0rpm/n_periods", "channels/node", "channels/role", "channels/unit"]
ATTRS = ["schema", "schema_version", "rig_id", "excitation", "phasor_convention", "source"]
ARRAYS = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=6).map(np.array),
    st.lists(st.integers(-5, 5), max_size=6).map(lambda x: np.array(x, dtype=np.int32)),
    st.lists(st.text(max_size=4), max_size=4).map(lambda x: np.array([s.encode() for s in x], dtype="S")),
    st.integers(1, 400).map(lambda n: np.full((n, 1), 1.0 + 1.0j)),
)


@pytest.mark.parametrize("shard", range(2))
def test_sweep_reader_fails_only_with_documented_errors(tmp_path: Path, shard: int) -> None:
    @FUZZ
    @given(st.lists(st.tuples(st.sampled_from(DATASETS + [f"@{a}" for a in ATTRS]), ARRAYS, st.booleans()),
                    min_size=1, max_size=3))
    def one(edits: list[tuple[str, np.ndarray, bool]]) -> None:
        p = tmp_path / f"s{shard}.h5"
        shutil.copy(SWEEP, p)
        with h5py.File(p, "r+") as h5:
            for name, value, delete in edits:
                if name.startswith("@"):
                    if delete:
                        h5.attrs.pop(name[1:], None)
                    else:
                        h5.attrs[name[1:]] = value if value.size else 0
                elif name in h5:
                    del h5[name]
                    if not delete:
                        h5.create_dataset(name, data=value)
        try:
            read_sweep(p)
        except UserInputError as exc:
            assert str(p) in str(exc)

    one()
