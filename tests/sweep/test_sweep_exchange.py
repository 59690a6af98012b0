"""UFF58 and tidy CSV export/import, and the sweep summary for ``rotorcheck info``."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
import pyuff
from sweep_helpers import CHANNELS, make_sweep

from rotorcheck.sweep import SweepFormatError, compare_sweeps
from rotorcheck.sweep.summary import sidak_noise_bound, summarize
from rotorcheck.sweep.tidy_csv import COLUMNS, export_tidy_csv, import_tidy_csv, read_tidy_csv
from rotorcheck.sweep.uff import export_uff58, import_uff58, read_uff58_frf

# --------------------------------------------------------------------------------------------
# UFF58
# --------------------------------------------------------------------------------------------


def test_uff58_export_import_frf_to_1e12(tmp_path: Path) -> None:
    s = make_sweep()
    p = tmp_path / "s.uff"
    export_uff58(s, p)
    tables = read_uff58_frf(p)
    assert list(tables) == list(s.runs)
    for rid, run in s.runs.items():
        t = tables[rid]
        err = np.abs(t.frf - run.frf).max() / np.abs(run.frf).max()
        assert err <= 1e-12, err
        np.testing.assert_array_equal(t.frequency, run.frequency)
        assert t.speed_rpm == run.speed_rpm
        assert [c.name for c in t.outputs] == ["d6x", "d6y"] and [c.name for c in t.inputs] == ["F8x"]
    # the whole sweep comes back bit for bit (binary 58b stores IEEE doubles); run notes are
    # not carried by UFF58
    back = import_uff58(p)
    assert compare_sweeps(s, back, ignore=["generator"]) == ["/runs/healthy_1000rpm@notes: 'test run' != ''"]


def test_uff58_records_read_by_plain_pyuff(tmp_path: Path) -> None:
    """Independent reader: pyuff itself sees FRF records with node/direction and Hz abscissa."""
    s = make_sweep()
    p = tmp_path / "s.uff"
    export_uff58(s, p, include_phasors=False)
    sets = pyuff.UFF(str(p)).read_sets()
    assert len(sets) == 2 * 2  # two runs x (2 outputs x 1 input)
    first = sets[0]
    assert first["func_type"] == 4 and first["abscissa_spec_data_type"] == 18
    assert (first["rsp_node"], first["rsp_dir"], first["ref_node"], first["ref_dir"]) == (6, 1, 8, 1)
    assert (sets[1]["rsp_node"], sets[1]["rsp_dir"]) == (6, 2)
    run = s.runs["healthy_1000rpm"]
    np.testing.assert_array_equal(first["x"], run.frequency)
    assert np.abs(first["data"] - run.frf[:, 0, 0]).max() <= 1e-12 * np.abs(run.frf).max()
    assert first["z_axis_value"] == pytest.approx(1000.0)
    with pytest.raises(SweepFormatError, match="FRF-only file"):
        import_uff58(p)


def test_uff58_ascii_precision(tmp_path: Path) -> None:
    """ASCII 58: ordinate 12 significant digits, abscissa only 6 (E13.5), as documented."""
    s = make_sweep()
    p = tmp_path / "a.uff"
    export_uff58(s, p, binary=False, include_phasors=False)
    t = read_uff58_frf(p)["healthy_1000rpm"]
    run = s.runs["healthy_1000rpm"]
    rel = np.abs(t.frf - run.frf) / np.abs(run.frf)
    assert rel.max() < 1e-11
    assert np.abs(t.frequency - run.frequency).max() <= 5e-6 * run.frequency.max()


def test_uff58_refuses_overwrite(tmp_path: Path) -> None:
    p = tmp_path / "s.uff"
    export_uff58(make_sweep(), p)
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        export_uff58(make_sweep(), p)
    export_uff58(make_sweep(seed=3), p, force=True)


# --------------------------------------------------------------------------------------------
# tidy CSV
# --------------------------------------------------------------------------------------------


def test_tidy_csv_roundtrip_exact(tmp_path: Path) -> None:
    s = make_sweep()
    p = tmp_path / "s.csv"
    export_tidy_csv(s, p)
    with open(p, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0])[: len(COLUMNS)] == COLUMNS
    n_rows = sum(r.frequency.size for r in s.runs.values()) * 2 * 1
    assert len(rows) == n_rows
    run = s.runs["healthy_1000rpm"]
    r0, r1 = rows[0], rows[1]
    assert (r0["run_id"], r0["output"], r0["input"], r1["output"]) == ("healthy_1000rpm", "d6x", "F8x", "d6y")
    assert complex(float(r1["frf_re"]), float(r1["frf_im"])) == run.frf[0, 1, 0]
    assert float(r0["output_var"]) == run.output_var[0, 0] and int(r0["n_periods"]) == 64
    tables = read_tidy_csv(p)
    np.testing.assert_array_equal(tables["healthy_0rpm"].frf, s.runs["healthy_0rpm"].frf)
    back = import_tidy_csv(
        p, CHANNELS, rig_id=s.rig_id, source=s.source, created_utc=s.created_utc, generator=s.generator
    )
    assert compare_sweeps(s, back) == ["/runs/healthy_1000rpm@notes: 'test run' != ''"]  # no notes


def test_tidy_csv_missing_row_refused(tmp_path: Path) -> None:
    s = make_sweep()
    p = tmp_path / "s.csv"
    export_tidy_csv(s, p)
    lines = p.read_text().splitlines()
    p.write_text("\n".join(lines[:5] + lines[6:]) + "\n")
    with pytest.raises(SweepFormatError, match=r"s\.csv: /: run 'healthy_1000rpm': 1 frequency/channel"):
        read_tidy_csv(p)


# --------------------------------------------------------------------------------------------
# summary
# --------------------------------------------------------------------------------------------


def test_summary_numbers() -> None:
    s = make_sweep()
    out = summarize(s)
    assert out["n_runs"] == 2 and out["speeds_rpm"] == [0.0, 1000.0]
    assert out["shared_grid"] is False and out["grid"]["n"] is None
    assert [c["name"] for c in out["channels"]] == ["F8x", "d6x", "d6y"]
    r = out["runs"][0]
    run = s.runs["healthy_1000rpm"]
    assert r["grid"] == {"min_hz": run.frequency.min(), "max_hz": run.frequency.max(), "n": 262}
    sd = np.sqrt(run.output_var)
    n = sd.size
    p = 0.99 ** (1 / n)
    v = sd.max() * math.sqrt(-math.log(1 - p))
    noise = r["noise"]["all_outputs"]
    assert noise["median_std_m"] == pytest.approx(np.median(sd), rel=1e-15)
    assert noise["max_std_m"] == pytest.approx(sd.max(), rel=1e-15)
    assert noise["sidak_bound_m"] == pytest.approx(v, rel=1e-9)
    assert r["noise"]["per_output"]["d6y"]["sidak_bound_m"] == pytest.approx(
        sd[:, 1].max() * math.sqrt(-math.log(1 - 0.99 ** (1 / 262))), rel=1e-9
    )


def test_sidak_bound_family_coverage() -> None:
    """Monte Carlo: with equal variances, P(max_k |v_k| <= V) = 0.99 over the family of n."""
    rng = np.random.default_rng(0)
    n, trials, var = 262, 20000, 4e-16
    v_bound = sidak_noise_bound(np.full(n, var), 0.99)
    z = np.sqrt(var / 2) * (rng.standard_normal((trials, n)) + 1j * rng.standard_normal((trials, n)))
    cover = np.mean(np.abs(z).max(axis=1) <= v_bound)
    assert cover == pytest.approx(0.99, abs=4 * math.sqrt(0.99 * 0.01 / trials))
