"""Fixtures of the FE tests (the bundled crack rig configs)."""

from __future__ import annotations

import pytest
from fe_helpers import CONFIGS

from rotorcheck.config import RigConfig, load_config


@pytest.fixture(scope="session")
def crack_rig() -> RigConfig:
    return load_config(CONFIGS / "crack_rig.yaml")


@pytest.fixture(scope="session")
def crack_rig_truth() -> RigConfig:
    return load_config(CONFIGS / "crack_rig_truth.yaml")
