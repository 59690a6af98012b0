"""The fault-model registry (issue 28): every fault of every bundled rig has one model, and the simulator's
system built through the registry equals the system assembled with the fault's change given by hand (values
read from the YAML text, not through the schema)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from rotorcheck.config import load_config
from rotorcheck.faults.kinds import FAULT_MODELS, fault_elements, fault_model
from rotorcheck.fe.assembly import build_system
from rotorcheck.resources import configs_dir
from rotorcheck.sim.rig_sim import _rig_system


@pytest.mark.parametrize("name", sorted(p.name for p in configs_dir().glob("*.yaml")))
def test_every_bundled_fault_has_exactly_one_model(name: str) -> None:
    cfg = load_config(configs_dir() / name)
    for spec in cfg.faults.values():
        assert sum(m.applies(spec) for m in FAULT_MODELS) == 1
        assert fault_model(spec).schema is type(spec)


def test_open_crack_through_the_registry_equals_the_hand_built_system() -> None:
    path = configs_dir() / "crack_rig_truth.yaml"
    raw = yaml.safe_load(path.read_text())["faults"]["open_crack"]
    cfg = load_config(path)
    system, breathing = _rig_system(cfg, "open_crack")
    hand = build_system(cfg, modulus_factors={int(raw["element"]): float(raw["modulus_factor"])})
    assert breathing is None
    np.testing.assert_array_equal(system.matrices()[3], hand.matrices()[3])
    assert not np.array_equal(system.matrices()[3], build_system(cfg).matrices()[3])  # the crack changed something
    assert fault_elements(cfg) == [int(raw["element"])]  # open and breathing crack: both in element 4


def test_breathing_crack_is_time_varying_only() -> None:
    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    system, breathing = _rig_system(cfg, "breathing_crack")
    assert breathing is cfg.faults["breathing_crack"]
    np.testing.assert_array_equal(system.matrices()[3], build_system(cfg).matrices()[3])


def test_spring_change_through_the_registry_equals_the_hand_built_system() -> None:
    path = configs_dir() / "three_mass_truth.yaml"
    raw = yaml.safe_load(path.read_text())["faults"]["stiffness_loss"]
    cfg = load_config(path)
    system, breathing = _rig_system(cfg, "stiffness_loss")
    hand = build_system(cfg, stiffness_overrides={raw["spring"]: float(raw["stiffness"])})
    assert breathing is None and fault_elements(cfg) == []
    np.testing.assert_array_equal(system.matrices()[3], hand.matrices()[3])
    assert not np.array_equal(system.matrices()[3], build_system(cfg).matrices()[3])
