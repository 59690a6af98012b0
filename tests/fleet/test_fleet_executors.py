"""Running a fleet: serial == processes == Dask, the same summary byte for byte."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fleet_helpers import manifest, summary_rows

from rotorcheck.fleet.runner import FleetOptions, run_fleet
from rotorcheck.fleet.summary import read_hdf5


def _h5_text(out: Path) -> dict[str, list[str]]:
    """summary.h5's columns with every value as its repr (NaN equal to NaN)."""
    return {k: [repr(x) for x in v] for k, v in read_hdf5(out / "summary.h5").items()}


def test_serial_processes_dask_same_summary(small_fleet: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    root, truth = small_fleet
    man = manifest(root, truth, tmp_path / "fleet.csv", {"machine-00": [3], "machine-01": [2, 3],
                                                          "machine-03": [3]})
    texts = {}
    for how, opts in (("serial", FleetOptions(executor="serial")), ("processes", FleetOptions(workers=2)),
                      ("dask", FleetOptions(executor="dask", workers=2))):
        opts.out, opts.locate = tmp_path / how, "none"
        res = run_fleet(man, opts)
        assert res.n_detected == 4
        texts[how] = (tmp_path / how / "summary.csv").read_text()
        assert _h5_text(tmp_path / how) == _h5_text(tmp_path / "serial")
    assert texts["processes"] == texts["serial"] and texts["dask"] == texts["serial"]
    assert [r["verdict"] for r in summary_rows(tmp_path / "serial")] == ["healthy", "damage", "damage", "damage"]
