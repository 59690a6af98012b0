"""`rotorcheck convert` (rotorcheck.sweep.convert): HDF5 <-> UFF58 (binary/ASCII) <-> tidy CSV <-> wide CSV,
a third-party UFF58 written by pyuff itself, the options for what a foreign file lacks, refusals."""

from __future__ import annotations

import json
import os
from pathlib import Path

import h5py
import numpy as np
import pytest
import pyuff
from sweep_helpers import CHANNELS, make_sweep

from rotorcheck.cli import main
from rotorcheck.sweep import Run, Sweep, compare_sweeps, read_sweep, write_sweep
from rotorcheck.sweep.convert import ConvertOptions, assumed_frf_var, convert

REPO = Path(__file__).resolve().parents[2]
SAMPLE_0RPM = REPO / "data_samples" / "crack_rig" / "healthy_0rpm.h5"  # 353 points 30-800 Hz, no period phasors

# a third-party analyser's FRFs: single-DOF receptance H = 1 / (k - m w^2 + j c w) at 10, 15, ..., 100 Hz
F_FOREIGN = 10.0 + 5.0 * np.arange(19)


def _sdof(f: np.ndarray, k: float, m: float, c: float) -> np.ndarray:
    w = 2.0 * np.pi * f
    return 1.0 / (k - m * w**2 + 1j * c * w)


H_FOREIGN = {6: _sdof(F_FOREIGN, 1.0e6, 1.0, 100.0), 7: _sdof(F_FOREIGN, 4.0e6, 2.0, 300.0)}  # outputs at nodes 6, 7


def _run(capsys: pytest.CaptureFixture[str], argv: list[object]) -> tuple[int, str, str]:
    capsys.readouterr()
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, "".join(err.split())  # rich folds long lines: compare without whitespace


def _squash(text: str) -> str:
    return "".join(text.split())


def _write_foreign_uff(path: Path, binary: bool, **extra: object) -> None:
    """FRF records as a third-party tool writes them with pyuff: no rotorcheck tokens in the ID lines,
    even abscissa spacing, response y at nodes 6 and 7 (+X), reference force at node 8 (+X), plus a
    coherence record rotorcheck ignores."""
    sets = []
    for node, h in H_FOREIGN.items():
        rec = {
            "type": 58, "binary": int(binary), "func_type": 4, "id1": f"Acme FRF {node}X/8X", "id2": "Point 6",
            "id3": "01-JAN-26 12:00:00", "rsp_node": node, "rsp_dir": 1, "ref_node": 8, "ref_dir": 1,
            "abscissa_spacing": 1, "abscissa_spec_data_type": 18, "ordinate_spec_data_type": 8,
            "orddenom_spec_data_type": 13, "x": F_FOREIGN.copy(), "data": h.copy(),
        }
        rec.update(extra)
        sets.append(rec)
    sets.append({**sets[0], "func_type": 6, "id1": "Acme coherence", "data": np.full(F_FOREIGN.size, 0.99),
                 "ordinate_spec_data_type": 0})
    pyuff.UFF(str(path)).write_sets(sets, mode="add")  # a new file; pyuff's binary "overwrite" drops the header


# --------------------------------------------------------------------------------------------
# round trips of rotorcheck's own files
# --------------------------------------------------------------------------------------------


def test_hdf5_binary_uff_hdf5_bit_exact(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "s.h5"
    sw = make_sweep()
    write_sweep(sw, src)
    rc, out, _ = _run(capsys, ["convert", src, tmp_path / "s.uff", "--json"])
    assert rc == 0
    doc = json.loads(out)
    assert (doc["format_in"], doc["format_out"], doc["uff_encoding"]) == ("hdf5", "uff", "binary 58b")
    assert [r["n_points"] for r in doc["runs"]] == [262, 131] and doc["n_points"] == 393
    assert [c["name"] for c in doc["channels"]] == ["F8x", "d6x", "d6y"]
    assert _run(capsys, ["convert", tmp_path / "s.uff", tmp_path / "back.h5"])[0] == 0
    back = read_sweep(tmp_path / "back.h5")
    # every array bit for bit; UFF58 does not carry run notes or the generator
    assert compare_sweeps(sw, back, ignore=["generator"]) == ["/runs/healthy_1000rpm@notes: 'test run' != ''"]


def test_hdf5_tidy_csv_hdf5_bit_exact_with_side_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "s.h5"
    sw = make_sweep()
    write_sweep(sw, src)
    rc, out, _ = _run(capsys, ["convert", src, tmp_path / "t.csv", "--json"])
    assert rc == 0 and json.loads(out)["files"] == [str(tmp_path / "t.csv"), str(tmp_path / "t.columns.yaml")]
    assert _run(capsys, ["convert", tmp_path / "t.csv", tmp_path / "back.h5"])[0] == 0
    assert compare_sweeps(sw, read_sweep(tmp_path / "back.h5")) == []  # header, channels, notes, arrays
    assert (tmp_path / "back.h5").read_bytes() == src.read_bytes()  # and the very same file
    # without the side file the CSV lacks the channels' nodes and directions: exit 2 naming what to pass
    (tmp_path / "t.columns.yaml").rename(tmp_path / "elsewhere.yaml")
    rc, _, err = _run(capsys, ["convert", tmp_path / "t.csv", tmp_path / "b2.h5"])
    assert rc == 2 and _squash(f"{tmp_path / 't.csv'}: channels: a tidy CSV names its channels only") in err
    assert "--column-map" in err and not (tmp_path / "b2.h5").exists()
    assert _run(capsys, ["convert", tmp_path / "t.csv", tmp_path / "b2.h5", "--column-map",
                         tmp_path / "elsewhere.yaml"])[0] == 0


def test_ascii_uff_round_trip_within_its_precision(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """ASCII 58: the frequency keeps 6 significant digits (<= 5e-4 Hz below 1 kHz), the data 12."""
    rc, out, _ = _run(capsys, ["convert", SAMPLE_0RPM, tmp_path / "a.unv", "--ascii", "--json"])
    assert rc == 0 and json.loads(out)["uff_encoding"] == "ascii 58"
    assert b"rotorcheck" in (tmp_path / "a.unv").read_bytes()  # text, with the tokens in the ID lines
    assert _run(capsys, ["convert", tmp_path / "a.unv", tmp_path / "back.h5"])[0] == 0
    a, b = read_sweep(SAMPLE_0RPM).runs["0rpm"], read_sweep(tmp_path / "back.h5").runs["0rpm"]
    df = np.abs(a.frequency - b.frequency)
    assert 0 < df.max() <= 5e-4 + 1e-12, df.max()  # half a unit of the 6th digit (+ the doubles' own error)
    for name in ("frf", "input_phasor", "output_phasor", "output_var"):
        x, y = getattr(a, name), getattr(b, name)
        assert (np.abs(x - y) / np.abs(x)).max() <= 5e-12, name
    np.testing.assert_array_equal(a.n_periods, b.n_periods)


def test_hdf5_to_hdf5_selects_a_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "s.h5"
    sw = make_sweep()
    write_sweep(sw, src)
    assert _run(capsys, ["convert", src, tmp_path / "one.h5", "--run-id", "healthy_0rpm"])[0] == 0
    one = read_sweep(tmp_path / "one.h5")
    assert list(one.runs) == ["healthy_0rpm"]
    sw.runs = {"healthy_0rpm": sw.runs["healthy_0rpm"]}
    assert compare_sweeps(sw, one) == []
    rc, _, err = _run(capsys, ["convert", src, tmp_path / "x.h5", "--run-id", "nope"])
    assert rc == 2 and _squash(f"{src}: --run-id: no run 'nope' (runs: healthy_1000rpm, healthy_0rpm)") in err
    # a speed or rig id that contradicts the file is refused, never applied
    rc, _, err = _run(capsys, ["convert", src, tmp_path / "x.h5", "--run-id", "healthy_0rpm", "--speed", "500"])
    assert rc == 2 and _squash("the file states 0.0 rpm, --speed gives 500.0") in err
    rc, _, err = _run(capsys, ["convert", src, tmp_path / "x.h5", "--rig-id", "other"])
    assert rc == 2 and _squash("the file states 'crack_rig', --rig-id gives 'other'") in err
    # noise options have nothing to act on in a sweep with phasors
    rc, _, err = _run(capsys, ["convert", src, tmp_path / "x.h5", "--noise-var", "1e-20"])
    assert rc == 2 and "noFRF-onlyrunhere" in err and not (tmp_path / "x.h5").exists()


# --------------------------------------------------------------------------------------------
# a third-party UFF58 written by pyuff
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("binary", [True, False], ids=["binary58b", "ascii58"])
def test_foreign_pyuff_file_imports_as_frf_only_v2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], binary: bool
) -> None:
    uff = tmp_path / "acme.uff"
    _write_foreign_uff(uff, binary)
    out = tmp_path / "acme.h5"
    # what the file lacks is asked for, naming the file and the options
    rc, _, err = _run(capsys, ["convert", uff, out])
    assert rc == 2 and not out.exists()
    assert _squash(f"{uff}: foreign UFF58 file (no rotorcheck ID tokens) lacks the speed (pass --speed RPM)") in err
    assert "--noise-source" in err and "--noise-var" in err and "--rig-id" in err
    rc, _, err = _run(capsys, ["convert", uff, out, "--speed", "1000", "--rig-id", "crack_rig"])
    assert rc == 2 and "lacksanoisestatement" in err and "--speed" not in err.split("lacks")[1]
    rc, _, err = _run(capsys, ["convert", uff, out, "--noise-source", "assumed: 2 % of |H|", "--rig-id", "crack_rig"])
    assert rc == 2 and "lacksthespeed(pass--speedRPM)" in err and "noise" not in err.split("lacks")[1]

    rc, js, _ = _run(capsys, ["convert", uff, out, "--speed", "1000", "--rig-id", "crack_rig",
                              "--noise-source", "assumed: 2 % of |H|", "--json"])
    assert rc == 0
    doc = json.loads(js)
    assert doc["schema_version"] == 2 and doc["runs"][0]["frf_only"] is True
    sw = read_sweep(out)
    assert (sw.rig_id, sw.source) == ("crack_rig", "measured")
    assert [(c.name, c.role, c.node, c.direction) for c in sw.channels] == [
        ("F8x", "input", 8, "x"), ("d6x", "output", 6, "x"), ("d7x", "output", 7, "x")]
    run = sw.runs["1000rpm"]
    assert run.is_frf_only and run.speed_rpm == 1000.0 and run.noise_source == "assumed: 2 % of |H|"
    np.testing.assert_array_equal(run.frequency, F_FOREIGN)  # min 1.0e1 and step 5.0 are exact in E13.5
    ref = np.stack([H_FOREIGN[6], H_FOREIGN[7]], axis=1)[:, :, None]
    if binary:
        assert run.frf.tobytes() == ref.tobytes()  # IEEE doubles
    else:
        assert (np.abs(run.frf - ref) / np.abs(ref)).max() <= 5e-12  # %20.11e: 12 significant digits
    # the stated rule, computed: std = 2 % of |H| at each point
    np.testing.assert_allclose(run.frf_var, (0.02 * np.abs(run.frf)) ** 2, rtol=1e-15, atol=0)
    with h5py.File(out, "r") as h5:  # raw: a version-2 FRF-only run
        assert int(h5.attrs["schema_version"]) == 2
        # the contract's FRF-only datasets (no phasors) and the channel-name coordinates of the netCDF view
        assert sorted(h5["runs/1000rpm"]) == ["frequency", "frf", "frf_var", "input", "output"]
        assert h5["runs/1000rpm"].attrs["noise_source"] == "assumed: 2 % of |H|"
    # deterministic: the same conversion again gives the same bytes (created_utc is the UFF's mtime)
    again = tmp_path / "again.h5"
    assert _run(capsys, ["convert", uff, again, "--speed", "1000", "--rig-id", "crack_rig",
                         "--noise-source", "assumed: 2 % of |H|"])[0] == 0
    assert again.read_bytes() == out.read_bytes()
    # and back out to UFF58: rotorcheck tokens now, the noise statement travels
    assert _run(capsys, ["convert", out, tmp_path / "own.uff"])[0] == 0
    assert _run(capsys, ["convert", tmp_path / "own.uff", tmp_path / "own.h5"])[0] == 0
    assert compare_sweeps(sw, read_sweep(tmp_path / "own.h5"), ignore=["generator"]) == []


def test_foreign_uff_speed_from_rpm_z_axis_and_noise_var(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    uff = tmp_path / "z.uff"
    _write_foreign_uff(uff, True, z_axis_spec_data_type=19, z_axis_value=1500.0)
    out = tmp_path / "z.h5"
    # the speed comes from the z axis (type 19, rpm); a contradicting --speed is refused
    rc, _, err = _run(capsys, ["convert", uff, out, "--rig-id", "r", "--noise-var", "1e-18", "--speed", "900"])
    assert rc == 2 and _squash("the file states 1500.0 rpm, --speed gives 900.0") in err
    assert _run(capsys, ["convert", uff, out, "--rig-id", "r", "--noise-var", "1e-18", "--run-id", "acme"])[0] == 0
    run = read_sweep(out).runs["acme"]
    assert run.speed_rpm == 1500.0
    assert run.noise_source == "assumed: frf_var = 1e-18 (m/N)^2 at every point"
    assert run.frf_var.shape == (19, 2, 1) and np.all(run.frf_var == 1e-18)
    # --noise-var on a file that has the variance is refused (state its origin with --noise-source instead)
    rc, _, err = _run(capsys, ["convert", out, tmp_path / "again.h5", "--noise-var", "1e-18"])
    assert rc == 2 and _squash("the file has the FRF's variance: drop --noise-var") in err
    # an assumed rule convert cannot compute, on data without a variance, is refused
    uff2 = tmp_path / "n.uff"
    _write_foreign_uff(uff2, True)
    rc, _, err = _run(capsys, ["convert", uff2, tmp_path / "n.h5", "--speed", "0", "--rig-id", "r",
                               "--noise-source", "assumed: a guess"])
    assert rc == 2 and "isnotaruleconvertcancompute" in err and not (tmp_path / "n.h5").exists()
    assert _run(capsys, ["convert", uff2, tmp_path / "n.h5", "--speed", "0", "--rig-id", "r",
                         "--noise-source", "assumed: a guess", "--noise-var", "4e-18"])[0] == 0
    run = read_sweep(tmp_path / "n.h5").runs["0rpm"]
    assert run.noise_source == "assumed: a guess" and np.all(run.frf_var == 4e-18)


def test_foreign_uff_mobility_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    uff = tmp_path / "v.uff"
    _write_foreign_uff(uff, True, ordinate_spec_data_type=11)
    rc, _, err = _run(capsys, ["convert", uff, tmp_path / "v.h5", "--speed", "0", "--rig-id", "r",
                               "--noise-var", "1e-18"])
    assert rc == 2 and _squash(f"{uff}: dataset #1/record 9: FRF ordinate is velocity (mobility)") in err


def test_assumed_rules() -> None:
    h = np.array([[[3 + 4j]], [[0.3 + 0.4j]]])  # |H| = 5, 0.5
    np.testing.assert_allclose(assumed_frf_var("1 % of |H|", h)[:, 0, 0], [0.05**2, 0.005**2], rtol=1e-15)
    np.testing.assert_allclose(assumed_frf_var("10 % of max |H|", h)[:, 0, 0], [0.25, 0.25], rtol=1e-15)
    assert assumed_frf_var("1 % of |H| floor", h) is None and assumed_frf_var("whatever", h) is None


# --------------------------------------------------------------------------------------------
# refusals
# --------------------------------------------------------------------------------------------


def test_existing_output_refused_untouched_then_force(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "s.h5"
    write_sweep(make_sweep(), src)
    for name in ("o.h5", "o.uff", "o.csv"):
        dst = tmp_path / name
        dst.write_bytes(b"precious")
        os.utime(dst, (1_000_000_000, 1_000_000_000))
        rc, out, err = _run(capsys, ["convert", src, dst, "--json"])
        assert rc == 2 and out == "" and _squash(f"{dst}: exists; refusing to overwrite (use --force)") in err
        assert dst.read_bytes() == b"precious" and dst.stat().st_mtime == 1_000_000_000
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted({"s.h5", *(n for n in ("o.h5", "o.uff", "o.csv")
                                                                               if (tmp_path / n).exists())})
    # the side file counts too: an existing t.columns.yaml blocks writing t.csv
    (tmp_path / "t.columns.yaml").write_text("keep")
    rc, _, err = _run(capsys, ["convert", src, tmp_path / "t.csv"])
    assert rc == 2 and not (tmp_path / "t.csv").exists() and (tmp_path / "t.columns.yaml").read_text() == "keep"
    assert _run(capsys, ["convert", src, tmp_path / "o.h5", "--force"])[0] == 0
    assert compare_sweeps(read_sweep(src), read_sweep(tmp_path / "o.h5")) == []


def test_option_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "s.h5"
    write_sweep(make_sweep(), src)
    cases = [
        (["convert", src, tmp_path / "o.txt"], "cannot tell the format from the extension '.txt'"),
        (["convert", src, tmp_path / "o.h5", "--to", "xlsx"], "--to: unknown format 'xlsx'"),
        (["convert", src, tmp_path / "o.h5", "--ascii"], "--ascii: applies to UFF58 output only"),
        (["convert", src, tmp_path / "o.h5", "--wide"], "--wide: neither IN nor OUT is a .csv file"),
        (["convert", src, tmp_path / "o.h5", "--noise-source", "guessed"], "--noise-source: noise_source 'guessed'"),
        (["convert", src, tmp_path / "o.h5", "--noise-var", "-1"], "--noise-var: -1.0: expected a variance > 0"),
        (["convert", src, tmp_path / "o.csv", "--wide"], "a wide CSV holds one run"),
        (["convert", tmp_path / "missing.h5", tmp_path / "o.h5"], "missing.h5: no such file"),
    ]
    for argv, needle in cases:
        rc, out, err = _run(capsys, argv)
        assert rc == 2 and out == "" and _squash(needle) in err, (argv, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.h5"]


def test_library_call_matches_the_command(tmp_path: Path) -> None:
    """convert() is the command: options object in, summary out."""
    f = np.linspace(20.0, 80.0, 7)
    h = np.stack([_sdof(f, 1e6, 1.0, 50.0), _sdof(f, 2e6, 1.0, 50.0)], axis=1)[:, :, None]
    run = Run.frf_only("r1", 600.0, f, h, np.full(h.shape, 1e-20), noise_source="measured")
    src = tmp_path / "fo.h5"
    write_sweep(Sweep("crack_rig", "measured", "t", "2026-01-01T00:00:00Z", list(CHANNELS), {"r1": run}), src)
    doc = convert(src, tmp_path / "fo.uff", options=ConvertOptions())
    assert doc["runs"] == [{"run_id": "r1", "speed_rpm": 600.0, "n_points": 7, "f_min_hz": 20.0, "f_max_hz": 80.0,
                            "frf_only": True, "frf_var": True, "noise_source": "measured"}]
    doc = convert(tmp_path / "fo.uff", tmp_path / "back.h5")
    assert compare_sweeps(read_sweep(src), read_sweep(tmp_path / "back.h5"), ignore=["generator"]) == []
