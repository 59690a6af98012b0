"""Wide CSV (one row per frequency, a column map says which column is what): an analyser's export with
magnitude in dB and phase in degrees against known complex values, units scaling, the HDF5 -> wide CSV ->
HDF5 round trip to float repr, errors that name the file, the line and the column."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from sweep_helpers import CHANNELS, make_sweep

from rotorcheck.cli import main
from rotorcheck.sweep import Run, Sweep, SweepFormatError, compare_sweeps, read_sweep, write_sweep
from rotorcheck.sweep.wide_csv import export_wide_csv, import_wide_csv, read_column_map

D6X = {"name": "d6x", "node": 6, "direction": "x"}
D6Y = {"name": "d6y", "node": 6, "direction": "y"}
F8X = {"name": "F8x", "node": 8, "direction": "x"}

# an analyser's export: a preamble, ';' separated, decimal commas, extra columns, um/N and dB/degrees
ANALYSER_CSV = """\
Acme Analyser 3000;export of 2026-01-01
Channel;H1 Y6x/F8x;;H2 Y6y/F8x;;
Freq [Hz];|H1| [dB re 1 um/N];arg H1 [deg];H2 re [um/N];H2 im [um/N];Coh 1
10,0;20,0;90,0;1,5;-2,0;0,99
20,0;0,0;180,0;0,0;0,25;0,98
40,0;40,0;-45,0;-3,0;0,0;0,97
"""
# the same FRFs as exact complex values, m/N (20 dB re 1 um/N = 10 um/N, 0 dB = 1 um/N, 40 dB = 100 um/N)
KNOWN_H1 = np.array([10e-6j, -1e-6 + 0j, 100e-6 * (1 - 1j) / math.sqrt(2)])
KNOWN_H2 = np.array([1.5e-6 - 2.0e-6j, 0.25e-6j, -3.0e-6 + 0j])
ANALYSER_MAP = {
    "frequency": "Freq [Hz]",
    "delimiter": ";",
    "decimal": ",",
    "header_row": 3,
    "frf_unit": "um/N",
    "rig_id": "crack_rig",
    "pairs": [
        {"output": D6X, "input": F8X, "mag": "|H1| [dB re 1 um/N]", "mag_unit": "dB",
         "phase": "arg H1 [deg]", "phase_unit": "deg"},
        {"output": D6Y, "input": F8X, "re": "H2 re [um/N]", "im": "H2 im [um/N]"},
    ],
}


def _analyser(tmp_path: Path, csv_text: str = ANALYSER_CSV, **changes: object) -> tuple[Path, Path]:
    csv_path = tmp_path / "analyser.csv"
    csv_path.write_text(csv_text, encoding="utf-8")
    map_path = tmp_path / "analyser_map.yaml"
    map_path.write_text(yaml.safe_dump({**ANALYSER_MAP, **changes}), encoding="utf-8")
    return csv_path, map_path


def _squash(text: str) -> str:
    return "".join(text.split())


def test_analyser_export_magnitude_db_phase_deg_to_known_complex(tmp_path: Path) -> None:
    csv_path, map_path = _analyser(tmp_path)
    sw = import_wide_csv(csv_path, map_path, speed_rpm=1000.0, noise_source="assumed: 1 % of |H|")
    assert [c.name for c in sw.channels] == ["F8x", "d6x", "d6y"]
    run = sw.runs["1000rpm"]
    assert run.is_frf_only and run.frf_var is None and run.speed_rpm == 1000.0
    np.testing.assert_array_equal(run.frequency, [10.0, 20.0, 40.0])
    np.testing.assert_allclose(run.frf[:, 0, 0], KNOWN_H1, rtol=1e-15, atol=1e-21)
    np.testing.assert_allclose(run.frf[:, 1, 0], KNOWN_H2, rtol=1e-15, atol=0)
    # phase in radians and linear magnitude read the same numbers
    rad = ANALYSER_CSV.replace("90,0;", "1,5707963267948966;").replace("180,0;", "3,141592653589793;")
    rad = rad.replace("-45,0;", "-0,7853981633974483;").replace("20,0;1,5", "10,0;1,5")
    rad = rad.replace("20,0;0,0;3", "20,0;1,0;3").replace("40,0;-0,78", "100,0;-0,78")
    rad_csv, rad_map = _analyser(tmp_path, rad, pairs=[
        {**ANALYSER_MAP["pairs"][0], "mag_unit": "linear", "phase_unit": "rad"}, ANALYSER_MAP["pairs"][1]])
    rr = import_wide_csv(rad_csv, rad_map, speed_rpm=1000.0, noise_source="measured").runs["1000rpm"]
    np.testing.assert_allclose(rr.frf[:, 0, 0], KNOWN_H1, rtol=1e-15, atol=1e-21)


def test_variance_columns_and_units_scale(tmp_path: Path) -> None:
    text = "f,re,im,v\n5,1,2,0.25\n6,3,4,4\n"
    (tmp_path / "a.csv").write_text(text)
    cm = {"frequency": "f", "frf_unit": "mm/N", "speed_rpm": 0, "rig_id": "r", "noise_source": "measured",
          "run_id": "bench", "pairs": [{"output": D6X, "input": F8X, "re": "re", "im": "im", "var": "v"}]}
    (tmp_path / "a.json").write_text(json.dumps(cm))
    run = import_wide_csv(tmp_path / "a.csv", tmp_path / "a.json").runs["bench"]
    np.testing.assert_allclose(run.frf[:, 0, 0], [1e-3 + 2e-3j, 3e-3 + 4e-3j], rtol=1e-15)
    np.testing.assert_allclose(run.frf_var[:, 0, 0], [0.25e-6, 4e-6], rtol=1e-15)  # (mm/N)^2 -> (m/N)^2
    assert run.noise_source == "measured"


def test_hdf5_wide_hdf5_round_trip_to_repr(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An FRF-only run comes back bit for bit (repr floats); a run with phasors comes back as its FRF and
    the variance propagated from its phasors, stated "measured"."""
    f = np.sort(30.0 + 570.0 * np.random.default_rng(3).random(50))
    rng = np.random.default_rng(4)
    h = (rng.standard_normal((50, 2, 1)) + 1j * rng.standard_normal((50, 2, 1))) * 1e-6
    var = rng.random((50, 2, 1)) * 1e-15
    run = Run.frf_only("r_1", 1234.5, f, h, var, noise_source="assumed: 1 % of |H| floor", notes="a: b\nc")
    sw = Sweep("crack_rig", "measured", "tests", "2026-01-01T00:00:00Z", list(CHANNELS), {"r_1": run})
    src = tmp_path / "fo.h5"
    write_sweep(sw, src)
    assert main(["convert", str(src), str(tmp_path / "w.csv"), "--wide"]) == 0
    assert main(["convert", str(tmp_path / "w.csv"), str(tmp_path / "back.h5"), "--wide"]) == 0
    assert compare_sweeps(sw, read_sweep(tmp_path / "back.h5")) == []
    assert (tmp_path / "back.h5").read_bytes() == src.read_bytes()
    # the format named instead of taken from the extension: --wide with --to, or --from wide alone
    assert main(["convert", str(tmp_path / "w.csv"), str(tmp_path / "b.dat"), "--wide", "--to", "hdf5"]) == 0
    assert main(["convert", str(tmp_path / "w.csv"), str(tmp_path / "c.dat"), "--from", "wide", "--to", "h5"]) == 0
    assert (tmp_path / "b.dat").read_bytes() == (tmp_path / "c.dat").read_bytes() == src.read_bytes()
    header = (tmp_path / "w.csv").read_text().splitlines()[0]
    assert header == "frequency_hz,d6x/F8x re,d6x/F8x im,d6x/F8x var,d6y/F8x re,d6y/F8x im,d6y/F8x var"

    ph = make_sweep()
    write_sweep(ph, tmp_path / "ph.h5")
    capsys.readouterr()
    rc = main(["convert", str(tmp_path / "ph.h5"), str(tmp_path / "p.csv"), "--wide", "--run-id", "healthy_0rpm",
               "--column-map", str(tmp_path / "p_map.json")])
    assert rc == 0 and (tmp_path / "p_map.json").exists() and not (tmp_path / "p.columns.yaml").exists()
    assert main(["convert", str(tmp_path / "p.csv"), str(tmp_path / "p.h5"), "--wide", "--column-map",
                 str(tmp_path / "p_map.json")]) == 0
    a, b = ph.runs["healthy_0rpm"], read_sweep(tmp_path / "p.h5").runs["healthy_0rpm"]
    assert b.is_frf_only and b.noise_source == "measured"
    assert a.frequency.tobytes() == b.frequency.tobytes() and a.frf.tobytes() == b.frf.tobytes()
    expected_var = a.output_var[:, :, None] / np.abs(a.input_phasor[:, None, :]) ** 2  # output_var / |W|^2
    np.testing.assert_allclose(b.frf_var, expected_var, rtol=1e-15, atol=0)
    # two runs, no --run-id: a wide CSV holds one run
    capsys.readouterr()
    assert main(["convert", str(tmp_path / "ph.h5"), str(tmp_path / "q.csv"), "--wide"]) == 2
    assert "--run-id" in capsys.readouterr().err


def test_cli_import_asks_for_speed_rig_and_noise(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv_path, map_path = _analyser(tmp_path, rig_id=None)
    doc = yaml.safe_load(map_path.read_text())
    del doc["rig_id"]
    map_path.write_text(yaml.safe_dump(doc))
    base = ["convert", str(csv_path), str(tmp_path / "o.h5"), "--wide", "--column-map", str(map_path)]
    steps = [
        ([], "speed_rpm: no speed: pass --speed RPM"),
        (["--speed", "1000"], "rig_id: no rig id: pass --rig-id NAME"),
        (["--speed", "1000", "--rig-id", "crack_rig"], "noise_source: FRF-only data need a noise statement: pass "
                                                       "--noise-source"),
    ]
    for extra, needle in steps:
        capsys.readouterr()
        assert main([*base, *extra]) == 2
        err = capsys.readouterr().err
        assert _squash(f"{csv_path}: {needle}") in _squash(err), err
        assert not (tmp_path / "o.h5").exists()
    capsys.readouterr()
    assert main([*base, "--speed", "1000", "--rig-id", "crack_rig", "--noise-source", "assumed: 1 % of |H|",
                 "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    assert (js["format_in"], js["format_out"], js["n_points"]) == ("wide", "hdf5", 3)
    run = read_sweep(tmp_path / "o.h5").runs["1000rpm"]
    np.testing.assert_allclose(run.frf_var[:, 0, 0], (0.01 * np.abs(KNOWN_H1)) ** 2, rtol=1e-14)
    # no map given and none beside the CSV
    capsys.readouterr()
    assert main(["convert", str(csv_path), str(tmp_path / "p.h5"), "--wide", "--speed", "1"]) == 2
    assert "--column-map" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("edit", "where", "reason"),
    [
        (lambda t: t.replace("0,0;0,25", "0,0;zero"), "line 5, column 'H2 im [um/N]'", "not a number: 'zero'"),
        (lambda t: t.replace("40,0;40,0;-45,0;-3,0;0,0", "40,0;40,0;-45,0;-3,0;"), "line 6, column 'H2 im [um/N]'",
         "empty cell"),
        (lambda t: t.replace("40,0;40,0;-45,0;-3,0;0,0;0,97", "40,0;40,0;-45,0"), "line 6, column 'H2 re [um/N]'",
         "missing cell"),
        (lambda t: t.replace("40,0;40,0", "15,0;40,0"), "line 6, column 'Freq [Hz]'",
         "frequency 15.0 Hz is not above the previous line's 20.0 Hz"),
        (lambda t: t.replace("Freq [Hz]", "Frequency"), "line 3, column 'Freq [Hz]'", "not in the header"),
        (lambda t: t.replace("20,0;0,0;180,0", "20,0;nan;180,0"), "line 5, column '|H1| [dB re 1 um/N]'",
         "not a finite number"),
    ],
)
def test_csv_errors_name_file_line_column(tmp_path: Path, edit, where: str, reason: str) -> None:
    csv_path, map_path = _analyser(tmp_path, edit(ANALYSER_CSV))
    with pytest.raises(SweepFormatError) as ei:
        import_wide_csv(csv_path, map_path, speed_rpm=0.0, noise_source="measured")
    assert str(ei.value).startswith(f"{csv_path}: {where}: {reason}"), str(ei.value)


@pytest.mark.parametrize(
    ("change", "where", "reason"),
    [
        ({"pairs": [{"output": D6X, "input": F8X, "mag": "m", "phase": "p", "phase_unit": "deg"}]},
         "pairs[0].mag_unit", "missing: say which unit (linear | dB)"),
        ({"pairs": [{"output": D6X, "input": F8X, "re": "a"}]}, "pairs[0].im", "missing (re and im go together)"),
        ({"pairs": [{"output": {"name": "d6x", "node": 6}, "input": F8X, "re": "a", "im": "b"}]},
         "pairs[0].output.direction", "missing"),
        ({"pairs": [{"output": D6X, "input": F8X, "re": "a", "im": "b"},
                    {"output": D6X, "input": {"name": "F8y", "node": 8, "direction": "y"}, "re": "c", "im": "d"},
                    {"output": D6Y, "input": F8X, "re": "e", "im": "f"}]},
         "pairs", "no columns for output/input ['d6y/F8y']"),
        ({"frf_unit": "furlong/N"}, "frf_unit", "unit 'furlong/N' not one of"),
        ({"phase_units": "deg"}, "/", "unknown keys ['phase_units']"),
    ],
)
def test_column_map_errors_name_map_and_key(tmp_path: Path, change: dict, where: str, reason: str) -> None:
    _, map_path = _analyser(tmp_path, **change)
    with pytest.raises(SweepFormatError) as ei:
        read_column_map(map_path)
    assert str(ei.value).startswith(f"{map_path}: {where}: {reason}"), str(ei.value)


def test_export_refuses_existing_csv_or_map(tmp_path: Path) -> None:
    sw = make_sweep()
    sw.runs = {"healthy_0rpm": sw.runs["healthy_0rpm"]}
    (tmp_path / "w.columns.yaml").write_text("keep")
    with pytest.raises(FileExistsError):
        export_wide_csv(sw, tmp_path / "w.csv")
    assert not (tmp_path / "w.csv").exists() and (tmp_path / "w.columns.yaml").read_text() == "keep"
    export_wide_csv(sw, tmp_path / "w.csv", force=True)
    assert read_column_map(tmp_path / "w.columns.yaml").run_id == "healthy_0rpm"
