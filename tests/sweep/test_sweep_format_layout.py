"""The sweep package's split: one concept per module, imports only downwards, one public API."""

from __future__ import annotations

import ast
from pathlib import Path

import rotorcheck.sweep as pkg
from rotorcheck.sweep import compare, hdf5io
from rotorcheck.sweep import format as fmt

SWEEP_DIR = Path(pkg.__file__).parent

#: module -> the rotorcheck modules it may import (lower layers only)
ALLOWED = {
    "format": {"rotorcheck.errors"},  # SweepFormatError is a UserInputError (exit 2 by class, not by name)
    "validation": {"rotorcheck.errors", "rotorcheck.sweep.format"},  # check_rig_id: a rig id is a name
    "hdf5io": {"rotorcheck.fileio", "rotorcheck.netcdf_view", "rotorcheck.sweep.format",
               "rotorcheck.sweep.validation"},
    "compare": {"rotorcheck.sweep.format", "rotorcheck.sweep.hdf5io"},
    "uff": {"rotorcheck.fileio", "rotorcheck.sweep.format", "rotorcheck.sweep.validation"},
    "tidy_csv": {"rotorcheck.fileio", "rotorcheck.sweep.format", "rotorcheck.sweep.validation"},
}


def _rotorcheck_imports(name: str) -> set[str]:
    tree = ast.parse((SWEEP_DIR / f"{name}.py").read_text(encoding="utf-8"))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return {m for m in found if m.split(".")[0] == "rotorcheck"}


def test_imports_only_downwards() -> None:
    for name, allowed in ALLOWED.items():
        assert _rotorcheck_imports(name) <= allowed, name


def test_no_second_atomic_writer() -> None:
    for name in ALLOWED:
        text = (SWEEP_DIR / f"{name}.py").read_text(encoding="utf-8")
        for banned in ("mkstemp", "os.replace", "os.link", "os.umask"):
            assert banned not in text, (name, banned)


def test_public_api_reexported_from_its_home() -> None:
    assert pkg.Sweep is fmt.Sweep and pkg.SweepFormatError is fmt.SweepFormatError
    assert pkg.read_sweep is hdf5io.read_sweep and pkg.write_sweep is hdf5io.write_sweep
    assert pkg.sweep_sha256 is hdf5io.sweep_sha256 and pkg.compare_sweeps is compare.compare_sweeps
    assert sorted(pkg.__all__) == sorted(
        ["Channel", "Run", "Sweep", "SweepFormatError", "compare_sweeps", "read_sweep", "sweep_sha256", "write_sweep"]
    )
