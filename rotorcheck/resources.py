"""Where the bundled rigs and sample sweeps live (the repository's ``configs/`` and ``data_samples/``)."""

from __future__ import annotations

import os
from pathlib import Path

from rotorcheck.errors import InputError

_REPO = Path(__file__).resolve().parents[1]


def configs_dir() -> Path:
    """Folder of bundled rig YAML files (``$ROTORCHECK_CONFIGS`` overrides)."""
    return Path(os.environ.get("ROTORCHECK_CONFIGS", _REPO / "configs"))


def samples_dir() -> Path:
    """Folder of bundled sample sweeps (``$ROTORCHECK_SAMPLES`` overrides)."""
    return Path(os.environ.get("ROTORCHECK_SAMPLES", _REPO / "data_samples"))


def default_rig_path(rig_id: str) -> Path:
    """The bundled nominal rig for ``rig_id`` (``configs/<rig_id>.yaml``)."""
    path = configs_dir() / f"{rig_id}.yaml"
    if not path.exists():
        msg = f"no bundled rig for rig_id {rig_id!r} ({path} not found); pass --rig"
        raise InputError(None, "--rig", msg)
    return path
