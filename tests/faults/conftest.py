"""Fixtures for the crack tests (helpers in faults_helpers.py)."""

from __future__ import annotations

import pytest
from faults_helpers import CONFIGS, HAVE_ASSEMBLY, small_rotor

from rotorcheck.config import load_config
from rotorcheck.fe.system import MechanicalSystem


@pytest.fixture(scope="session")
def rotor() -> MechanicalSystem:
    return small_rotor()


@pytest.fixture(scope="session")
def rig_system() -> MechanicalSystem:
    """The rig from the truth config when assembly exists, else the self-built one."""
    if HAVE_ASSEMBLY:
        from rotorcheck.fe.assembly import build_system

        path = CONFIGS / "crack_rig_truth.yaml"
        if not path.exists():
            path = CONFIGS / "crack_rig.yaml"
        return build_system(load_config(path))
    return small_rotor()
