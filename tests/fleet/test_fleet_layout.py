"""Fleet layout: folders and manifests, time stamps, and bad input as exit 2 naming the file and field."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest

from rotorcheck.cli import main
from rotorcheck.errors import InputError
from rotorcheck.fleet.layout import discover, time_from_name


def test_time_from_name() -> None:
    assert time_from_name("2026-03-01T02-00.h5") == "2026-03-01T02:00:00Z"
    assert time_from_name("pump7_2026-03-01T02-00-30.h5") == "2026-03-01T02:00:30Z"
    assert time_from_name("20260301T0200.h5") == "2026-03-01T02:00:00Z"
    assert time_from_name("2026-13-01T02-00.h5") is None  # month 13
    assert time_from_name("healthy.h5") is None


def test_folder_layout(small_fleet: tuple[Path, dict[str, Any]]) -> None:
    root, truth = small_fleet
    fleet = discover(root)
    assert [m.name for m in fleet.machines] == sorted(truth["machines"])
    for m in fleet.machines:
        want = [e["time"] for e in truth["machines"][m.name]["sweeps"]]
        assert [s.time for s in m.sweeps] == want
        assert m.rig.name == "rig.yaml" and m.baseline.name == "baseline.h5"


def test_time_from_attribute(tmp_path: Path, small_fleet: tuple[Path, dict[str, Any]]) -> None:
    """A sweep whose name has no stamp: its created_utc attribute (the simulator wrote the sweep's time)."""
    root, truth = small_fleet
    m = tmp_path / "m1"
    (m / "sweeps").mkdir(parents=True)
    src = root / "machine-00"
    shutil.copy(src / "rig.yaml", m / "rig.yaml")
    shutil.copy(src / "baseline.h5", m / "baseline.h5")
    first = truth["machines"]["machine-00"]["sweeps"][1]
    shutil.copy(root / first["file"], m / "sweeps" / "latest.h5")
    (fleet_m,) = discover(tmp_path).machines
    assert fleet_m.sweeps[0].time == first["time"]


def test_manifest_csv_and_yaml(tmp_path: Path, small_fleet: tuple[Path, dict[str, Any]]) -> None:
    root, truth = small_fleet
    rows = ["machine,rig,baseline,sweep,time"]
    yaml_rows = ["sweeps:"]
    for name in ("machine-01", "machine-03"):
        for e in truth["machines"][name]["sweeps"][:2]:
            sweep = root / e["file"]
            rows.append(f"{name},{root / name / 'rig.yaml'},{root / name / 'baseline.h5'},{sweep},")
            yaml_rows.append(f"  - {{machine: {name}, rig: {root / name / 'rig.yaml'}, baseline: "
                             f"{root / name / 'baseline.h5'}, sweep: {sweep}, time: '{e['time']}'}}")
    (tmp_path / "fleet.csv").write_text("\n".join(rows) + "\n")
    (tmp_path / "fleet.yaml").write_text("\n".join(yaml_rows) + "\n")
    for f in ("fleet.csv", "fleet.yaml"):
        fleet = discover(tmp_path / f)
        assert [m.name for m in fleet.machines] == ["machine-01", "machine-03"]
        assert [s.time for s in fleet.machines[0].sweeps] == [e["time"] for e in
                                                             truth["machines"]["machine-01"]["sweeps"][:2]]


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    rc = main(["fleet", *args])
    return rc, capsys.readouterr().err


@pytest.mark.parametrize("case", ["no-rig", "no-time", "csv-column", "csv-file", "same-time", "bad-limit",
                                  "bad-locate", "empty"])
def test_bad_input_exit_2(case: str, tmp_path: Path, small_fleet: tuple[Path, dict[str, Any]],
                          capsys: pytest.CaptureFixture[str]) -> None:
    root, truth = small_fleet
    src = root / "machine-00"
    m = tmp_path / "pump"
    (m / "sweeps").mkdir(parents=True)
    shutil.copy(src / "rig.yaml", m / "rig.yaml")
    shutil.copy(src / "baseline.h5", m / "baseline.h5")
    sweep0 = root / truth["machines"]["machine-00"]["sweeps"][0]["file"]
    shutil.copy(sweep0, m / "sweeps" / "2026-03-01T02-00.h5")
    target, want = str(tmp_path), ""
    extra: list[str] = ["--serial", "--locate", "none"]
    if case == "no-rig":
        (m / "rig.yaml").unlink()
        want = str(m / "rig.yaml")
    elif case == "no-time":
        import h5py

        bad = m / "sweeps" / "nostamp.h5"
        shutil.copy(sweep0, bad)
        with h5py.File(bad, "a") as h5:
            h5.attrs["created_utc"] = ""
        want = f"{bad}: /@measured_utc"
    elif case == "csv-column":
        (tmp_path / "f.csv").write_text("machine,rig,sweep\npump,a,b\n")
        target, want = str(tmp_path / "f.csv"), "column 'baseline'"
    elif case == "csv-file":
        (tmp_path / "f.csv").write_text(f"machine,rig,baseline,sweep\npump,{m / 'rig.yaml'},{m / 'baseline.h5'},"
                                        "missing.h5\n")
        target, want = str(tmp_path / "f.csv"), "row 2: sweep"
    elif case == "same-time":
        shutil.copy(sweep0, m / "sweeps" / "2026-03-01T02-00-00.h5")
        want = "two sweeps at 2026-03-01T02:00:00Z"
    elif case == "bad-limit":
        extra += ["--limit", "much"]
        want = "--limit"
    elif case == "bad-locate":
        extra[-1] = "sometimes"
        want = "--locate"
    elif case == "empty":
        target, want = str(tmp_path / "pump" / "sweeps"), "no machine folders"
    rc, err = _run([target, "--out", str(tmp_path / "out"), *extra], capsys)
    assert rc == 2, err
    assert want in err.replace("\n", ""), err


def test_dask_missing_is_exit_2(monkeypatch: pytest.MonkeyPatch, small_fleet: tuple[Path, dict[str, Any]],
                                tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    rc, err = _run([str(small_fleet[0]), "--out", str(tmp_path), "--dask"], capsys)
    assert rc == 2 and "rotorcheck[fleet]" in err and "--dask" in err
    with pytest.raises(InputError, match="--scheduler"):
        from rotorcheck.fleet.runner import FleetOptions, check_options

        check_options(FleetOptions(scheduler="tcp://127.0.0.1:1"))
