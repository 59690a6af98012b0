"""Running a fleet: growing cracks alarmed and the others not; serial == processes == Dask; a worker killed
mid-run loses and duplicates nothing; a second run with no new sweep detects nothing, fast."""

from __future__ import annotations

import csv
import io
import json
import time
from pathlib import Path
from typing import Any

import pytest

from rotorcheck.cli import main
from rotorcheck.fleet.runner import FleetOptions, run_fleet
from rotorcheck.fleet.summary import read_hdf5


def _rows(out: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO((out / "summary.csv").read_text())))


@pytest.fixture(scope="module")
def full_run(small_fleet: tuple[Path, dict[str, Any]], tmp_path_factory: pytest.TempPathFactory
             ) -> tuple[Path, Any]:
    root, _ = small_fleet
    out = tmp_path_factory.mktemp("full") / "results"
    res = run_fleet(root, FleetOptions(out=out, workers=2, locate="none", limit="3000"))
    return out, res


def test_cracks_alarmed_others_not(full_run: tuple[Path, Any], small_fleet: tuple[Path, dict[str, Any]]) -> None:
    out, res = full_run
    truth = small_fleet[1]["machines"]
    alarmed = {a["machine"] for a in res.alerts if a["level"] == "alarm"}
    cracked = {m for m, d in truth.items() if d["kind"].startswith("crack")}
    assert alarmed == cracked
    rows = _rows(out)
    assert len(rows) == sum(len(d["sweeps"]) for d in truth.values())
    for r in rows:  # no damage verdict on an uncracked sweep (healthy machines, the benign drift, before onset)
        loss = next(e["loss"] for e in truth[r["machine"]]["sweeps"] if e["time"] == r["time"])
        if loss == 0.0:
            assert r["verdict"] == "healthy", r
    # the figure follows the truth: the largest crack sweep's Re D_u within 15 % of its noise-free value
    for m in cracked:
        last = [r for r in rows if r["machine"] == m][-1]
        want = truth[m]["sweeps"][-1]["du_low_true_n_per_m"]
        assert float(last["du_low_re_n_per_m"]) == pytest.approx(want, rel=0.15)
    # the trend brackets the true growth of the figure (its noise-free rate from the simulated crack)
    for m in cracked:
        lo, hi = res.trends[m].to_dict()["slope_interval_n_per_m_per_day"]
        assert lo <= truth[m]["growth_true_n_per_m_per_day"] <= hi, (m, lo, hi)
    h5 = read_hdf5(out / "summary.h5")
    assert h5["machine"] == [r["machine"] for r in rows]
    assert h5["du_low_re_n_per_m"] == [float(r["du_low_re_n_per_m"]) for r in rows]
    html = (out / "index.html").read_text()
    assert "data:image/png;base64," in html and "machine-01/" in html and "report.md" in html


def test_second_run_does_no_work(full_run: tuple[Path, Any], small_fleet: tuple[Path, dict[str, Any]],
                                 capsys: pytest.CaptureFixture[str]) -> None:
    out, _ = full_run
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()}
    t0 = time.perf_counter()
    res = run_fleet(small_fleet[0], FleetOptions(out=out, workers=2, locate="none", limit="3000"))
    assert time.perf_counter() - t0 < 2.0
    assert res.up_to_date and res.n_detected == 0 and res.n_located == 0
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()} == before  # nothing rewritten
    rc = main(["fleet", str(small_fleet[0]), "--out", str(out), "--locate", "none", "--limit", "3000", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert rc == 1 and doc["n_detected"] == 0 and doc["up_to_date"]


def _h5_text(out: Path) -> dict[str, list[str]]:
    """summary.h5's columns with every value as its repr (NaN equal to NaN)."""
    return {k: [repr(x) for x in v] for k, v in read_hdf5(out / "summary.h5").items()}


def _manifest(root: Path, truth: dict[str, Any], path: Path, picks: dict[str, list[int]]) -> Path:
    lines = ["machine,rig,baseline,sweep"]
    for m, ks in picks.items():
        for k in ks:
            lines.append(f"{m},{root / m / 'rig.yaml'},{root / m / 'baseline.h5'},"
                         f"{root / truth['machines'][m]['sweeps'][k]['file']}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_serial_processes_dask_same_summary(small_fleet: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    root, truth = small_fleet
    man = _manifest(root, truth, tmp_path / "fleet.csv", {"machine-00": [3], "machine-01": [2, 3],
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
    assert [r["verdict"] for r in _rows(tmp_path / "serial")] == ["healthy", "damage", "damage", "damage"]


def test_worker_killed_mid_dask_run(small_fleet: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    """The first task attempt kills its Dask worker (os._exit) after writing half a result: Dask restarts
    the worker and runs the task again; every sweep once in the summary, no partial result folder."""
    root, truth = small_fleet
    man = _manifest(root, truth, tmp_path / "fleet.csv", {"machine-00": [0], "machine-02": [3], "machine-03": [3]})
    marker = tmp_path / "killed"
    out = tmp_path / "out"
    res = run_fleet(man, FleetOptions(out=out, executor="dask", workers=2, locate="none", kill_marker=str(marker)))
    assert marker.exists()  # a worker did die
    rows = _rows(out)
    assert sorted((r["machine"], r["time"]) for r in rows) == sorted(
        (m, truth["machines"][m]["sweeps"][k]["time"]) for m, k in (("machine-00", 0), ("machine-02", 3),
                                                                     ("machine-03", 3)))
    assert len({r["sweep_sha256"] for r in rows}) == 3
    dirs = [p for m in out.iterdir() if m.is_dir() and m.name.startswith("machine") for p in m.iterdir()]
    assert len(dirs) == 3 and all((d / "DONE").exists() and (d / "row.json").exists() for d in dirs)
    assert all(json.loads((d / "report.json").read_text())["verdict"] for d in dirs)  # complete reports
    assert res.n_detected == 3
