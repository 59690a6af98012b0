"""Issue 32: CSV inputs saved by Excel ("CSV UTF-8": a byte-order mark) read as without it; a NaN in a tidy
CSV named by line and column; a CSV that is not UTF-8 or not CSV refused naming file and line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotorcheck.cli import main
from rotorcheck.fleet.layout import _rows_csv
from rotorcheck.resources import samples_dir
from rotorcheck.sweep import read_sweep
from rotorcheck.sweep.format import SweepFormatError
from rotorcheck.sweep.tidy_csv import read_tidy_csv

HEALTHY = samples_dir() / "crack_rig" / "healthy_0rpm.h5"
BOM = "\ufeff"


@pytest.fixture(scope="module")
def csvs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("csv")
    assert main(["convert", str(HEALTHY), str(d / "tidy.csv")]) == 0
    assert main(["convert", str(HEALTHY), str(d / "wide.csv"), "--wide"]) == 0
    return d


def _with_bom(src: Path, dst: Path) -> Path:
    dst.write_text(BOM + src.read_text(encoding="utf-8"), encoding="utf-8")
    side = src.with_name(src.stem + ".columns.yaml")
    dst.with_name(dst.stem + ".columns.yaml").write_text(BOM + side.read_text(), encoding="utf-8")
    return dst


@pytest.mark.parametrize("kind", ["tidy", "wide"])
def test_a_byte_order_mark_is_no_part_of_the_first_column(csvs: Path, tmp_path: Path, kind: str) -> None:
    src = _with_bom(csvs / f"{kind}.csv", tmp_path / f"bom_{kind}.csv")
    assert src.read_bytes().startswith(b"\xef\xbb\xbf")
    out = tmp_path / "back.h5"
    assert main(["convert", str(src), str(out)] + (["--wide"] if kind == "wide" else [])) == 0
    a, b = read_sweep(HEALTHY), read_sweep(out)
    (ra,), (rb,) = a.runs.values(), b.runs.values()
    assert np.array_equal(ra.frequency, rb.frequency)
    np.testing.assert_allclose(rb.frf, ra.frf, rtol=1e-15)


def test_a_fleet_manifest_with_a_byte_order_mark(tmp_path: Path) -> None:
    m = tmp_path / "fleet.csv"
    m.write_text(BOM + "machine,rig,baseline,sweep,time\nm1,r.yaml,b.h5,s.h5,2026-01-01T00:00:00Z\n",
                 encoding="utf-8")
    assert _rows_csv(m) == [{"machine": "m1", "rig": "r.yaml", "baseline": "b.h5", "sweep": "s.h5",
                             "time": "2026-01-01T00:00:00Z"}]


@pytest.mark.parametrize("value", ["nan", "NaN", "inf", "-inf", "1e400"])
def test_a_non_finite_number_in_a_tidy_csv_is_named_by_line_and_column(csvs: Path, tmp_path: Path,
                                                                        value: str) -> None:
    lines = (csvs / "tidy.csv").read_text().splitlines()
    header = lines[0].split(",")
    row = lines[4].split(",")
    row[header.index("frf_im")] = value
    lines[4] = ",".join(row)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(SweepFormatError, match=rf"^{bad}: line 5/frf_im: not a finite number: '{value}'$"):
        read_tidy_csv(bad)


def test_a_tidy_csv_that_is_not_utf8(tmp_path: Path, csvs: Path) -> None:
    bad = tmp_path / "latin1.csv"
    bad.write_bytes((csvs / "tidy.csv").read_bytes() + b"0rpm,0.0,\xe9\n")
    with pytest.raises(SweepFormatError, match=rf"^{bad}: line \d+: not UTF-8 text"):
        read_tidy_csv(bad)
