"""Fixtures for the sweep tests."""

from __future__ import annotations

from pathlib import Path

import pytest
from sweep_helpers import make_sweep

from rotorcheck.sweep import Sweep, write_sweep


@pytest.fixture
def sweep() -> Sweep:
    return make_sweep()


@pytest.fixture
def sweep_file(tmp_path: Path, sweep: Sweep) -> Path:
    p = tmp_path / "sweep.h5"
    write_sweep(sweep, p)
    return p
