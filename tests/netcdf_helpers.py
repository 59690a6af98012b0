"""Small baselines and sweeps for the netCDF-view tests (tests/test_baseline_netcdf.py,
tests/sweep/test_netcdf.py) and for the files in tests/data/legacy/, written by rotorcheck before the
netCDF labels (commit e03973e) with :func:`write_legacy`: the readers must keep reading those."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rotorcheck.baseline import Baseline, DriftModel, HealthyData, ModelBound, NoiseFit, Provenance

LEGACY = Path(__file__).resolve().parent / "data" / "legacy"
CREATED_UTC = "2026-01-01T00:00:00Z"


def _c(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) * 1e-6


def small_baseline(run_id: str, speed_rpm: float, seed: int, uncertainty: str = "additive",
                   parameter: str = "") -> Baseline:
    """A validated 'measured' baseline of 9 points and 2 channel pairs with every optional dataset (per-point
    noise, learned benign directions, the benign correction of 3 parameters); seeded, so the same each time."""
    rng = np.random.default_rng(seed)
    nf, npair, q, p = 9, 2, 2, 3
    f = np.linspace(30.0, 110.0, nf)
    return Baseline(
        Provenance("crack_rig", "a" * 64, ["b" * 64, "c" * 64], run_id, speed_rpm, CREATED_UTC),
        NoiseFit(3e-9, "per-point", 0.95, 1e-9 * (1.0 + rng.random(nf)), uncertainty, parameter),
        ModelBound("measured", uncertainty, parameter, f, 1e-7 * (1.0 + rng.random(nf)), _c(rng, nf, 1, 1),
                   1e-8 * rng.random(nf), np.array(["ok"] * (nf - 1) + ["edge"])),
        HealthyData(_c(rng, nf, npair), 1e-16 * (1.0 + rng.random((nf, npair))), np.full((nf, npair), 126.0),
                    1.0 + _c(rng, nf, 1), _c(rng, nf, 1), 2, 2, [["s6.x", "s8.x"], ["s6.y", "s8.x"]]),
        DriftModel(0.25, _c(rng, q, nf * npair), 1.0 + rng.random(q), _c(rng, p, nf * npair),
                   {"bearings.left.kxx": 0.01}, {"bearings.left.kxx": [0.9, 0.95]}))


def two_run_baseline() -> tuple[Baseline, list[Baseline]]:
    """A baseline file's first set (0 rpm, at the root) and a second run (1000 rpm, in /runs/1000rpm)."""
    return small_baseline("0rpm", 0.0, 1), [small_baseline("1000rpm", 1000.0, 2)]
