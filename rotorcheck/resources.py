"""Where the bundled rigs and sample sweeps live: package data ``rotorcheck/_bundled/{configs,data_samples}``,
found through importlib.resources, so an installed wheel finds them wherever it is installed.

The repository's top-level ``configs/`` and ``data_samples/`` stay the source of truth: in the checkout
``rotorcheck/_bundled/configs`` and ``rotorcheck/_bundled/data_samples`` are relative symbolic links to
them (so the editable install reads them in place), and building the wheel copies their files in
(``[tool.setuptools.package-data]`` in pyproject.toml).
"""

from __future__ import annotations

import os
from pathlib import Path

from rotorcheck.errors import InputError, check_rig_id


def _bundled(name: str) -> Path:
    """The package-data folder ``rotorcheck/_bundled/<name>`` (an installed wheel is unpacked on disk)."""
    from importlib.resources import files  # lazy: importlib.resources costs ~15 ms (tempfile, zipfile)

    folder = files("rotorcheck") / "_bundled" / name
    return folder if isinstance(folder, Path) else Path(str(folder))


def configs_dir() -> Path:
    """Folder of bundled rig YAML files (``$ROTORCHECK_CONFIGS`` overrides)."""
    return Path(os.environ.get("ROTORCHECK_CONFIGS") or _bundled("configs"))


def samples_dir() -> Path:
    """Folder of bundled sample sweeps (``$ROTORCHECK_SAMPLES`` overrides)."""
    return Path(os.environ.get("ROTORCHECK_SAMPLES") or _bundled("data_samples"))


def default_rig_path(rig_id: str) -> Path:
    """The bundled nominal rig for ``rig_id`` (``configs/<rig_id>.yaml``); a rig_id that is no name (a path)
    is refused: it never loads a file outside the bundled rigs."""
    check_rig_id(rig_id, None, "rig_id")
    path = configs_dir() / f"{rig_id}.yaml"
    if not path.exists():
        msg = f"no bundled rig for rig_id {rig_id!r} ({path} not found); pass --rig"
        raise InputError(None, "--rig", msg)
    return path
