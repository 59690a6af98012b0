"""`rotorcheck info` and `rotorcheck simulate` through cli.main(argv): exit codes, the --json document
on stdout (and nothing else there), messages that name the file and the path inside it, refusals."""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from rotorcheck import cli
from rotorcheck.cli import main
from rotorcheck.config import load_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import receptance
from rotorcheck.sweep import read_sweep

REPO = Path(__file__).resolve().parents[1]
SAMPLES = REPO / "data_samples"
BUNDLED = (
    "crack_rig/healthy_0rpm.h5",
    "crack_rig/open_crack_0rpm.h5",
    "crack_rig/healthy_1000rpm.h5",
    "crack_rig/breathing_crack_1000rpm.h5",
    "crack_rig/healthy_1000rpm_repeat.h5",
    "three_mass/healthy.h5",
    "three_mass/damaged.h5",
)
RUN = "/runs/1000rpm"


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _has(text: str, *needles: str) -> bool:
    """All needles occur in ``text``, ignoring whitespace: rich folds long lines at the console width,
    inside words or at spaces when stderr is narrow, so compare with all whitespace removed."""
    squash = "".join(text.split())
    return all("".join(str(n).split()) in squash for n in needles)


def _run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, str, str]:
    capsys.readouterr()
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


# --------------------------------------------------------------------------------------------
# info
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", BUNDLED)
def test_info_json_on_bundled_sample(capsys: pytest.CaptureFixture[str], name: str) -> None:
    path = SAMPLES / name
    rc, out, err = _run(capsys, ["info", path, "--json"])
    assert rc == 0, err
    doc = json.loads(out)  # the whole of stdout is one JSON document
    sw = read_sweep(path)
    (run,) = sw.runs.values()
    f = run.frequency
    assert doc["rig_id"] == sw.rig_id and doc["n_runs"] == 1
    assert doc["sha256"] == _sha(path)
    assert doc["grid"] == {"min_hz": float(f[0]), "max_hz": float(f[-1]), "n": int(f.size)}
    assert doc["speeds_rpm"] == [run.speed_rpm]
    (jr,) = doc["runs"]
    assert jr["run_id"] == run.run_id and jr["grid"]["n"] == f.size
    assert jr["n_periods_min"] == jr["n_periods_max"] == int(run.n_periods[0])
    # noise estimate, recomputed: median/max std of the mean and the Sidak family-wise 99 % bound
    # V = max sqrt(var) sqrt(-ln(1 - p)), p = 0.99^(1/n)
    s = np.sqrt(run.output_var[:, 0])
    nz = jr["noise"]["all_outputs"]
    assert nz["n_points"] == f.size
    assert nz["median_std_m"] == pytest.approx(float(np.median(s)), rel=1e-12, abs=0.0)
    assert nz["max_std_m"] == pytest.approx(float(s.max()), rel=1e-12, abs=0.0)
    p = 0.99 ** (1.0 / f.size)
    assert nz["sidak_bound_m"] == pytest.approx(float(s.max()) * math.sqrt(-math.log(1.0 - p)), rel=1e-9, abs=0.0)
    if name.startswith("crack_rig"):  # 0.2 um per sample, 64 x 64 samples: sqrt(4 s^2 / 4096) = 6.25 nm
        assert nz["median_std_m"] > 0.9 * 6.25e-9
    assert _has(err, name, "valid rotorcheck.sweep v1")


def test_info_without_json_prints_nothing_on_stdout(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = _run(capsys, ["info", SAMPLES / "crack_rig" / "healthy_0rpm.h5"])
    assert rc == 0 and out == ""
    assert "353 points" in err and "30-800 Hz" in err


def _missing(h5: h5py.File) -> None:
    del h5[f"{RUN}/output_var"]


def _nan(h5: h5py.File) -> None:
    h5[f"{RUN}/output_phasor"][17, 0] = complex(np.nan, 0.0)


def _non_increasing(h5: h5py.File) -> None:
    f = h5[f"{RUN}/frequency"][()]
    f[40], f[41] = f[41], f[40]
    h5[f"{RUN}/frequency"][...] = f


def _schema_version(h5: h5py.File) -> None:
    h5.attrs["schema_version"] = np.int32(4)


MALFORMED = {
    "missing_dataset": (_missing, f"{RUN}/output_var", "missing dataset"),
    "nan": (_nan, f"{RUN}/output_phasor", "non-finite value at index (17, 0)"),
    "non_increasing": (_non_increasing, f"{RUN}/frequency", "frequency not strictly increasing at index 41"),
    "schema_version": (_schema_version, "/@schema_version", "unknown schema_version 4"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_info_malformed_exits_2_naming_file_and_dataset(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str
) -> None:
    edit, inside, reason = MALFORMED[case]
    path = tmp_path / f"{case}.h5"
    shutil.copyfile(SAMPLES / "crack_rig" / "healthy_1000rpm.h5", path)
    with h5py.File(path, "r+") as h5:
        edit(h5)
    rc, out, err = _run(capsys, ["info", path, "--json"])
    assert rc == 2 and out == ""
    assert _has(err, str(path), f"{path}: {inside}: {reason}"), err


def test_info_truncated_file_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "truncated.h5"
    data = (SAMPLES / "crack_rig" / "healthy_1000rpm.h5").read_bytes()
    path.write_bytes(data[: len(data) // 2])
    rc, out, err = _run(capsys, ["info", path, "--json"])
    assert rc == 2 and out == ""
    assert _has(err, f"{path}: /: cannot open as HDF5 (truncated or corrupt file)"), err


def test_info_text_file_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "notes.h5"
    path.write_text("frequency,frf\n30,1e-6\n")
    rc, out, err = _run(capsys, ["info", path])
    assert rc == 2 and out == ""
    assert _has(err, f"{path}: /: not an HDF5 file"), err


def test_info_missing_file_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "absent.h5"
    rc, out, err = _run(capsys, ["info", path])
    assert rc == 2 and out == "" and _has(err, f"{path}: /: no such file")


def test_error_message_keeps_the_file_path_on_one_line(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # what a CI log or a pipe gets: 80 columns (rich reads COLUMNS once, when the Console is made)
    monkeypatch.setattr(cli.err, "_width", 80)
    folder = tmp_path / ("measurements_of_the_crack_rig_" * 3)
    folder.mkdir()
    path = folder / "healthy_1000rpm_missing_output_var.h5"
    shutil.copyfile(SAMPLES / "crack_rig" / "healthy_1000rpm.h5", path)
    with h5py.File(path, "r+") as h5:
        _missing(h5)
    rc, _, err = _run(capsys, ["info", path])
    assert rc == 2
    assert f"{path}: {RUN}/output_var: missing dataset" in err, err


def test_non_increasing_message_prints_plain_numbers(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "swapped.h5"
    shutil.copyfile(SAMPLES / "crack_rig" / "healthy_1000rpm.h5", path)
    with h5py.File(path, "r+") as h5:
        _non_increasing(h5)
    rc, _, err = _run(capsys, ["info", path])
    assert rc == 2
    assert not _has(err, "np.float64"), err


# --------------------------------------------------------------------------------------------
# simulate
# --------------------------------------------------------------------------------------------

SIM = ["--speed", "1000", "--f-min", "40", "--f-max", "60", "--points", "5", "--periods", "8"]


def test_simulate_writes_requested_grid_speed_periods(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "sim.h5"
    rc, out, err = _run(capsys, ["simulate", path, *SIM, "--seed", "3", "--json"])
    assert rc == 0, err
    doc = json.loads(out)  # only the JSON document on stdout
    assert doc["file"] == str(path) and doc["speed_rpm"] == 1000.0 and doc["points"] == 5 and doc["seed"] == 3
    assert doc["fault"] is None
    assert _has(err, f"wrote {path}")
    sw = read_sweep(path)
    assert sw.rig_id == "crack_rig" and sw.source == "simulated"
    (run,) = sw.runs.values()
    assert run.speed_rpm == 1000.0
    np.testing.assert_array_equal(run.frequency, np.linspace(40.0, 60.0, 5))
    np.testing.assert_array_equal(run.n_periods, 8)
    assert run.n_periods.dtype == np.int32
    assert "seed 3;" in run.notes and "8 periods" in run.notes
    np.testing.assert_array_equal(run.input_phasor, 1.0)  # truth rig: 1 N, no input noise


def test_simulate_noiseless_0rpm_equals_truth_receptance(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "clean.h5"
    argv = ["simulate", path, "--speed", "0", "--f-min", "50", "--f-max", "500", "--points", "4",
            "--periods", "4", "--noise", "0"]
    rc, out, err = _run(capsys, argv)
    assert rc == 0 and out == "", err
    (run,) = read_sweep(path).runs.values()
    truth = build_system(load_config(REPO / "configs" / "crack_rig_truth.yaml"))
    h = receptance(truth, run.frequency, 0.0, [truth.dof(6, "x")], [truth.dof(8, "x")], method="solve")
    assert np.max(np.abs(run.frf - h) / np.abs(h)) < 1e-9
    np.testing.assert_array_equal(run.n_periods, 4)


def test_simulate_refuses_overwrite_then_force(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "sim.h5"
    assert _run(capsys, ["simulate", path, *SIM, "--seed", "3"])[0] == 0
    before = _sha(path)
    rc, out, err = _run(capsys, ["simulate", path, *SIM, "--seed", "4", "--json"])
    assert rc == 2 and out == ""
    assert _has(err, f"{path}: exists; refusing to overwrite (use --force)"), err
    assert _sha(path) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim.h5"]  # no temp files left behind
    rc, out, err = _run(capsys, ["simulate", path, *SIM, "--seed", "4", "--force", "--json"])
    assert rc == 0, err
    assert json.loads(out)["seed"] == 4
    assert _sha(path) != before
    (run,) = read_sweep(path).runs.values()
    assert "seed 4;" in run.notes


def test_simulate_unknown_fault_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "x.h5"
    rc, out, err = _run(capsys, ["simulate", path, *SIM, "--fault", "cracked_bearing", "--json"])
    assert rc == 2 and out == ""
    assert _has(err, "--fault", "'cracked_bearing'", "open_crack", "breathing_crack"), err  # known ones listed
    assert not path.exists()


def test_simulate_named_fault_changes_the_data(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    argv = ["--speed", "0", "--f-min", "100", "--f-max", "300", "--points", "3", "--periods", "4", "--noise", "0"]
    assert _run(capsys, ["simulate", tmp_path / "ok.h5", *argv])[0] == 0
    rc, out, err = _run(capsys, ["simulate", tmp_path / "open.h5", *argv, "--fault", "open_crack", "--json"])
    assert rc == 0, err
    assert json.loads(out)["fault"] == "open_crack"
    ok = next(iter(read_sweep(tmp_path / "ok.h5").runs.values())).frf
    cracked_sw = read_sweep(tmp_path / "open.h5")
    assert "open_crack" in cracked_sw.generator
    cracked = next(iter(cracked_sw.runs.values())).frf
    assert np.min(np.abs(cracked - ok) / np.abs(ok)) > 1e-3


def test_simulate_output_respects_umask(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    old = os.umask(0o022)
    try:
        assert _run(capsys, ["simulate", tmp_path / "s.h5", *SIM])[0] == 0
        (tmp_path / "plain.txt").write_text("x")
    finally:
        os.umask(old)
    assert (tmp_path / "plain.txt").stat().st_mode & 0o777 == 0o644  # the umask in effect
    assert (tmp_path / "s.h5").stat().st_mode & 0o777 == 0o644


def test_info_on_version_2_files(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A two-input sweep (patterns) and an FRF-only run: info names the version, the patterns, and the
    FRF-only run's noise statement; the JSON counts match what was written."""
    from rotorcheck.config import Port
    from rotorcheck.sim.rig_sim import simulate_rig_patterns
    from rotorcheck.sweep import write_sweep
    from rotorcheck.sweep.format import Run, Sweep

    cfg = load_config(REPO / "configs" / "crack_rig_truth.yaml")
    f = np.linspace(40.0, 80.0, 9)
    sw = simulate_rig_patterns(cfg, f, [Port(station=8, direction="x"), Port(station=8, direction="y")],
                               [Port(station=6, direction="x"), Port(station=6, direction="y")], speed_rpm=1000.0)
    two = tmp_path / "two_inputs.h5"
    write_sweep(sw, two)
    assert main(["info", str(two), "--json"]) == 0
    out = capsys.readouterr()
    doc = json.loads(out.out)
    assert doc["schema_version"] == 2 and doc["runs"][0]["n_exc"] == 2
    assert "rotorcheck.sweep v2" in out.err and "2 excitation patterns" in out.err
    run = next(iter(sw.runs.values()))
    only = Run.frf_only("frf", 1000.0, f, run.frf, run.frf_variance(), noise_source="assumed: 1 % of |H|")
    fo = tmp_path / "frf_only.h5"
    write_sweep(Sweep(sw.rig_id, "measured", "test", sw.created_utc, sw.channels, {"frf": only}), fo)
    assert main(["info", str(fo), "--json"]) == 0
    out = capsys.readouterr()
    assert json.loads(out.out)["runs"][0]["frf_only"] is True
    assert "FRF only" in out.err and "assumed: 1 % of |H|" in out.err
