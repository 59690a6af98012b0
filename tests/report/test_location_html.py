"""The location tables of location.html and report.html render the typed location result (issue 28): their
numbers are location.json's (parsed from both files), and a hand-made result renders to the rows written
out here."""

from __future__ import annotations

import html
import json
import re

import numpy as np
import pytest

from rotorcheck.location import CandidateResult, LocationResult
from rotorcheck.report.html import location_table, render_detection_html
from rotorcheck.report.schema import DetectionReport, LocationReport
from tests.shared_runs import CliRun

_CELL = r"<td>\[?([^\]<]*)\]?</td>"  # "[lo, hi]", or "none (excluded)" for an excluded element
_ROW = re.compile(r"<tr><td class=\"num\">(\d+)</td><td>(\w+)</td><td class=\"num\">(\d*)</td>" + _CELL + _CELL
                  + r"<td>([^<]*)</td></tr>")


def _rows(text: str, after: str) -> list[tuple[str, ...]]:
    """The candidate rows of the location table that follows ``after`` in an HTML page."""
    body = text.split(after, 1)[1].split("</table>", 1)[0]
    return _ROW.findall(body)


def _percent(cell: str) -> tuple[float | None, float | None]:
    """"12.3, 55.7" -> fractions (0.123, 0.557); "50+" is None; "none (excluded)" is (None, None)."""
    if cell == "none (excluded)":
        return None, None
    lo, hi = (s.strip() for s in cell.split(","))
    return (None if lo == "" else float(lo) / 100.0, None if hi == "50+" else float(hi) / 100.0)


def _assert_rows_match_json(rows: list[tuple[str, ...]], candidates: list[dict]) -> None:
    assert len(rows) == len(candidates) > 0
    for (element, status, rank, loss, depth, excluded), c in zip(rows, candidates, strict=True):
        assert int(element) == c["element"] and status == c["status"]
        assert (None if rank == "" else int(rank)) == c["rank"]
        for cell, want in ((loss, c["loss_interval"]), (depth, c["depth_interval"])):
            got = _percent(cell)
            for g, w in zip(got, want, strict=True):
                if w is None or g is None:  # a blank lower end or "50+" exactly where the JSON has null
                    assert g is None and w is None, (cell, want)
                else:  # 3 significant digits of the percentage
                    assert g == pytest.approx(w, rel=5e-3, abs=5e-6), (cell, want)
        freqs = [float(x) for x in re.findall(r"\d+\.\d", excluded.split("(+")[0])]
        want_f = c["excluding_frequencies_hz"]
        np.testing.assert_allclose(freqs, want_f[:12], atol=0.051)
        more = re.search(r"\(\+(\d+) more\)", excluded)
        assert (int(more.group(1)) if more else 0) == max(len(want_f) - 12, 0)


def test_location_html_numbers_are_location_json(located_open_crack: CliRun) -> None:
    """The shared `locate --elements 1,4,9` of the open crack (conftest.located_open_crack): every candidate
    row, the best element, the speed, the summary and the sweep's sha256 of location.html parsed back equal
    location.json's."""
    out = located_open_crack.out
    doc = json.loads((out / "location.json").read_text())
    text = (out / "location.html").read_text()
    _assert_rows_match_json(_rows(text, "Candidates: all"), doc["candidates"])
    assert [c["element"] for c in doc["candidates"]] == [1, 4, 9]
    best = re.search(r"Best element: <b>(\d+)</b>", text)
    assert best is not None and int(best.group(1)) == doc["best_element"]
    speed = re.search(r"</code> at ([^ ]+) rpm\.</p>", text)
    assert speed is not None and float(speed.group(1)) == pytest.approx(doc["speed_rpm"], rel=1e-6, abs=1e-9)
    reason = re.search(r"<p id=\"reason\">([^<]*)</p>", text)
    assert reason is not None and html.unescape(reason.group(1)) == doc["summary"]
    assert f"<td class=\"hash\">{doc['sweep_sha256']}</td>" in text


def _result() -> LocationResult:
    nan = float("nan")
    freqs = tuple(10.0 + 2.5 * k for k in range(15))
    return LocationResult("open", True, [
        CandidateResult(1, 0.0, 0.1, "excluded", None, (nan, nan), (None, None), freqs),
        CandidateResult(2, 0.1, 0.2, "consistent", 1, (0.1234, 0.5567), (0.3, None), ()),
        CandidateResult(3, 0.2, 0.3, "consistent", 2, (0.0, 0.25), (0.0, 0.2049), ()),
    ], ["x<-f"], 48, 3.1)


def test_a_hand_made_result_renders_to_its_rows() -> None:
    """Rows written out by hand (percent to 3 significant digits; an excluded element's 15 frequencies cut
    after 12), and the same rows parsed back equal the result's JSON."""
    res = _result()
    text = location_table(res)
    assert _rows(text, "<table>") == [
        ("1", "excluded", "", "none (excluded)", "none (excluded)",
         "10.0, 12.5, 15.0, 17.5, 20.0, 22.5, 25.0, 27.5, 30.0, 32.5, 35.0, 37.5 (+3 more)"),
        ("2", "consistent", "1", "12.3, 55.7", "30, 50+", ""),
        ("3", "consistent", "2", "0, 25", "0, 20.5", ""),
    ]
    assert "Best element: <b>2</b>" in text
    _assert_rows_match_json(_rows(text, "<table>"), res.to_dict()["candidates"])


def test_report_html_location_table_and_location_json() -> None:
    """report.html of a detection with a location (detect --locate) shows the typed result's table; report.json
    keeps the location as the result's JSON; location.json is the context keys then the result's."""
    f = np.array([10.0, 20.0, 30.0])
    res = _result()
    rep = DetectionReport(
        verdict="damage", verdict_reason="r", verdict_rule="rule", n_points=3, n_fault_points=1,
        fault_frequencies_hz=[20.0], rig_id="rig", rig_sha256="0", sweep="s.h5", sweep_sha256="1", run_id="r",
        speed_rpm=0.0, band_hz=[10.0, 30.0], noise_bound_m=1e-7, noise_method="m", uncertainty="u", parameter="p",
        enclose="measured", damage_port="d", shaft_orders_removed=0, notes=[], frequency_hz=f,
        gamma_healthy=f * 1e-9, gamma_required=f * 2e-9, gamma_required_upper=f * 3e-9,
        fault=np.array([False, True, False]), status=["ok", "fault", "ok"], damage_dynamics_re=f,
        damage_dynamics_im=f, damage_bound_kind=["a"] * 3, damage_bound_min_abs=f, damage_bound_max_abs=f,
        damage_bound_phase_min_deg=f, damage_bound_phase_max_deg=f, location=res)
    text = render_detection_html(rep, [])
    _assert_rows_match_json(_rows(text, "<h2>Location</h2>"), rep.to_dict()["location"]["candidates"])
    assert rep.to_dict()["location"]["best_element"] == 2
    doc = LocationReport("s.h5", "1", "b.h5", "rig", 0.0, res).to_json()
    assert list(doc)[:6] == ["sweep", "sweep_sha256", "baseline", "rig_id", "speed_rpm", "best_element"]
    assert doc["summary"].startswith("crack most likely in element 2 (0.100-0.200 m), stiffness loss 12.3-55.7 %")
