"""A small simulated fleet shared by the fleet tests (made once per session by tools.fleet_sim)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from tools.fleet_sim import make_fleet


@pytest.fixture(scope="session")
def small_fleet(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """4 machines x 4 sweeps (healthy, crack A, benign drift, crack B), seed 0, the samples' grid."""
    root = tmp_path_factory.mktemp("fleet") / "fleet"
    root.mkdir()
    make_fleet(root, machines=4, sweeps=4, seed=0)
    return root, json.loads((root / "truth.json").read_text())
