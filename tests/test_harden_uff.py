"""Issue 32: UFF58 unit fields honoured (record 9/10 labels: mm, um per N), an abscissa that is not frequency
refused, a 58b file whose byte order is not the one its header states refused; a big-endian file that says so
read right."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import pyuff

from rotorcheck.cli import main
from rotorcheck.resources import samples_dir
from rotorcheck.sweep import read_sweep
from rotorcheck.sweep.convert import ConvertOptions, read_any
from rotorcheck.sweep.format import SweepFormatError

HEALTHY = samples_dir() / "crack_rig" / "healthy_0rpm.h5"
OPTS = ConvertOptions(speed_rpm=0.0, rig_id="crack_rig", noise_source="assumed: 1 % of |H|")


@pytest.fixture(scope="module")
def frf_record(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    d = tmp_path_factory.mktemp("uff")
    assert main(["convert", str(HEALTHY), str(d / "own.uff")]) == 0
    u = pyuff.UFF(str(d / "own.uff"))
    rec = next(s for s in (u.read_sets(i) for i in range(u.get_n_sets())) if s["func_type"] == 4)
    for k in ("id1", "id2", "id3", "id4", "id5"):  # a foreign file: no rotorcheck tokens
        rec[k] = "NONE"
    return rec


def _foreign(path: Path, rec: dict[str, Any], binary: bool = True, **edits: Any) -> Path:
    r = {k: v for k, v in rec.items() if k not in ("n_bytes", "n_ascii_lines")}
    r.update(binary=1 if binary else 0, **edits)
    pyuff.UFF(str(path)).write_sets([r], mode="add")
    return path


def _truth() -> np.ndarray:
    (run,) = read_sweep(HEALTHY).runs.values()
    return np.asarray(run.frf[:, 0, 0])


def test_the_foreign_file_in_m_per_n_reads_as_the_sweep(tmp_path: Path, frf_record: dict[str, Any]) -> None:
    sw = read_any(_foreign(tmp_path / "m.uff", frf_record), "uff", OPTS)
    np.testing.assert_allclose(next(iter(sw.runs.values())).frf[:, 0, 0], _truth(), rtol=1e-15)


@pytest.mark.parametrize(("label", "den", "factor"), [("mm", "N", 1e3), ("mm/N", "NONE", 1e3), ("um", "N", 1e6),
                                                       ("µm", "N", 1e6), ("m", "kN", 1e3), ("nm/N", "N", 1e9)])
def test_ordinate_units_are_honoured(tmp_path: Path, frf_record: dict[str, Any], label: str, den: str,
                                     factor: float) -> None:
    """The same FRF stated in mm/N (values 1000x): read as m/N, not 1000x off."""
    p = _foreign(tmp_path / "u.uff", frf_record, data=np.asarray(frf_record["data"]) * factor,
                 ordinate_axis_units_lab=label, orddenom_axis_units_lab=den)
    sw = read_any(p, "uff", OPTS)
    np.testing.assert_allclose(next(iter(sw.runs.values())).frf[:, 0, 0], _truth(), rtol=1e-12)


REFUSALS = [
    (dict(ordinate_axis_units_lab="in"), "record 9", "ordinate unit 'in' not understood"),
    (dict(orddenom_axis_units_lab="lbf"), "record 10", "denominator unit 'lbf' not understood"),
    (dict(ordinate_axis_units_lab="mm/N", orddenom_axis_units_lab="kN"), "record 10", "contradicts"),
    (dict(ordinate_spec_data_type=12), "record 9", "FRF ordinate is acceleration"),
    (dict(ordinate_len_unit_exp=2), "record 9", "unit exponents"),
    (dict(abscissa_spec_data_type=17), "record 8", "abscissa is time (specific data type 17), not frequency"),
    (dict(abscissa_spec_data_type=0, abscissa_axis_units_lab="s"), "record 8", "abscissa unit 's', not Hz"),
]


@pytest.mark.parametrize(("edits", "record", "message"), REFUSALS, ids=[m[:24] for _, _, m in REFUSALS])
def test_units_that_are_not_receptance_over_frequency_are_refused(tmp_path: Path, frf_record: dict[str, Any],
                                                                  capsys: pytest.CaptureFixture[str],
                                                                  edits: dict[str, Any], record: str,
                                                                  message: str) -> None:
    p = _foreign(tmp_path / "bad.uff", frf_record, **edits)
    out = tmp_path / "out.h5"
    assert main(["convert", str(p), str(out), "--speed", "0", "--rig-id", "crack_rig", "--noise-source",
                 "assumed: 1 % of |H|"]) == 2
    err = capsys.readouterr().err
    assert f"error: {p}: dataset #1/{record}: " in err and message in err
    assert not out.exists()


def _swap_data(path: Path, header_order: int) -> Path:
    """Rewrite a 58b file's data block big-endian; its record 1 states ``header_order``."""
    raw = path.read_bytes()
    head, _, rest = raw.partition(b"    58b     1")
    lines = rest.split(b"\n", 12)
    data = lines[12]
    n = len(data) // 8 * 8
    lines[12] = np.frombuffer(data[:n], "<f8").astype(">f8").tobytes() + data[n:]
    path.write_bytes(head + f"    58b     {header_order}".encode() + b"\n".join(lines))
    return path


def test_a_big_endian_file_that_says_so_reads_right(tmp_path: Path, frf_record: dict[str, Any]) -> None:
    p = _swap_data(_foreign(tmp_path / "be.uff", frf_record), header_order=2)
    sw = read_any(p, "uff", OPTS)
    np.testing.assert_array_equal(next(iter(sw.runs.values())).frf[:, 0, 0], _truth())


def test_big_endian_data_under_a_little_endian_header_are_refused(tmp_path: Path, frf_record: dict[str, Any]) -> None:
    p = _swap_data(_foreign(tmp_path / "lie.uff", frf_record), header_order=1)
    with pytest.raises(SweepFormatError, match=rf"^{p}: dataset #1/record 1: byte ordering 1 \(little-endian\) "
                                               "states the wrong byte order"):
        read_any(p, "uff", OPTS)


def test_a_non_ieee_float_format_is_refused(tmp_path: Path, frf_record: dict[str, Any]) -> None:
    p = _foreign(tmp_path / "vax.uff", frf_record)
    p.write_bytes(p.read_bytes().replace(b"    58b     1     2", b"    58b     1     1", 1))
    with pytest.raises(SweepFormatError, match=r"dataset #1/record 1: floating-point format 1"):
        read_any(p, "uff", OPTS)
