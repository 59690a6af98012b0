"""Helpers of the fleet tests: the summary's rows, a manifest of chosen sweeps."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any


def summary_rows(out: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO((out / "summary.csv").read_text())))


def manifest(root: Path, truth: dict[str, Any], path: Path, picks: dict[str, list[int]]) -> Path:
    lines = ["machine,rig,baseline,sweep"]
    for m, ks in picks.items():
        for k in ks:
            lines.append(f"{m},{root / m / 'rig.yaml'},{root / m / 'baseline.h5'},"
                         f"{root / truth['machines'][m]['sweeps'][k]['file']}")
    path.write_text("\n".join(lines) + "\n")
    return path
