"""Running a fleet on Dask: a worker killed mid-run loses and duplicates nothing."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fleet_helpers import manifest, summary_rows

from rotorcheck.fleet.runner import FleetOptions, run_fleet


def test_worker_killed_mid_dask_run(small_fleet: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    """The first task attempt kills its Dask worker (os._exit) after writing half a result: Dask restarts
    the worker and runs the task again; every sweep once in the summary, no partial result folder."""
    root, truth = small_fleet
    man = manifest(root, truth, tmp_path / "fleet.csv", {"machine-00": [0], "machine-02": [3], "machine-03": [3]})
    marker = tmp_path / "killed"
    out = tmp_path / "out"
    res = run_fleet(man, FleetOptions(out=out, executor="dask", workers=2, locate="none", kill_marker=str(marker)))
    assert marker.exists()  # a worker did die
    rows = summary_rows(out)
    assert sorted((r["machine"], r["time"]) for r in rows) == sorted(
        (m, truth["machines"][m]["sweeps"][k]["time"]) for m, k in (("machine-00", 0), ("machine-02", 3),
                                                                     ("machine-03", 3)))
    assert len({r["sweep_sha256"] for r in rows}) == 3
    dirs = [p for m in out.iterdir() if m.is_dir() and m.name.startswith("machine") for p in m.iterdir()]
    assert len(dirs) == 3 and all((d / "DONE").exists() and (d / "row.json").exists() for d in dirs)
    assert all(json.loads((d / "report.json").read_text())["verdict"] for d in dirs)  # complete reports
    assert res.n_detected == 3
