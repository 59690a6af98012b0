"""A small simulated fleet shared by the fleet tests (made once per run by tools.fleet_sim, whichever xdist
worker needs it first; read only)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from tests.shared_runs import once, shared_root
from tools.fleet_sim import make_fleet


def _make(folder: Path) -> None:
    root = folder / "fleet"
    root.mkdir()
    make_fleet(root, machines=4, sweeps=4, seed=0)
    (folder / "done.json").write_text("{}")


@pytest.fixture(scope="session")
def small_fleet(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """4 machines x 4 sweeps (healthy, crack A, benign drift, crack B), seed 0, the samples' grid."""
    root = once(shared_root(tmp_path_factory), "small_fleet-4x4-seed0", _make) / "fleet"
    return root, json.loads((root / "truth.json").read_text())
