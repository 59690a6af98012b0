"""The FE engine takes the rig's mechanics only (issue 28): any object with the fields of
:class:`rotorcheck.fe.description.MechanicalDescription` assembles, to the same matrices as the rig file it
came from; the assembly reads no other field; rigs that differ only in what the engine does not read
(ports, faults, benign ranges) share one assembled shaft."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rotorcheck.config import load_config
from rotorcheck.fe.assembly import _rotor_structure, build_system
from rotorcheck.fe.description import MECHANICAL_FIELDS
from rotorcheck.resources import configs_dir

FE = Path(__file__).resolve().parents[2] / "rotorcheck" / "fe"


@pytest.mark.parametrize("rig", ["crack_rig_truth.yaml", "overhung_rig.yaml", "three_mass_truth.yaml",
                                 "compressor_rig.yaml"])
def test_a_plain_object_with_the_mechanics_assembles_like_the_rig_file(rig: str) -> None:
    cfg = load_config(configs_dir() / rig)
    fields = {name: getattr(cfg, name) for name in MECHANICAL_FIELDS} | {"n_support_nodes": cfg.n_support_nodes}
    plain = dataclasses.make_dataclass("Plain", list(fields), frozen=True)(**fields)  # no RigConfig, no pydantic
    for speed in (0.0, 1500.0):
        for a, b in zip(build_system(cfg).matrices(speed), build_system(plain).matrices(speed)):  # type: ignore[arg-type]
            np.testing.assert_array_equal(a, b)


def _attributes_read(path: Path) -> set[str]:
    """The ``config.<name>`` attributes a module reads."""
    tree = ast.parse(path.read_text())
    return {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name)
            and n.value.id == "config"}


def test_the_assembly_reads_only_the_mechanical_fields() -> None:
    read = _attributes_read(FE / "assembly.py") | _attributes_read(FE / "lumped.py")
    assert read, "found no config.<attribute> reads: the scan is broken"
    assert read <= MECHANICAL_FIELDS | {"n_support_nodes"}, sorted(read - MECHANICAL_FIELDS)


def test_rigs_differing_outside_the_mechanics_share_one_assembled_shaft() -> None:
    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    other: Any = cfg.model_copy(update={"faults": {}, "variability": [], "description": "another"})
    a = _rotor_structure(cfg, None, cfg.n_support_nodes)
    b = _rotor_structure(other, None, other.n_support_nodes)
    assert a is b  # one cache entry: the same arrays
    stiffer = cfg.model_copy(update={"gyroscopic": False})
    assert _rotor_structure(stiffer, None, stiffer.n_support_nodes) is not a
