"""One content in every rendering (issue 31): report.md and report.html carry the same numbers (both parsed),
fault_points.csv the same damage estimate as the HTML's fault table (the one the reports say to read), the
conclusion opens every rendering and the CLI summary, and no rule text is cut."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Callable
from html.parser import HTMLParser
from typing import Any

import numpy as np
import pytest

from rotorcheck.report.content import conclusion, fmt_interval, fmt_p
from rotorcheck.report.html import render_detection_html
from rotorcheck.report.reports import render_csv, render_markdown
from rotorcheck.resources import configs_dir, samples_dir

CR = samples_dir() / "crack_rig"
CASES = {  # (rig, healthy, new, expected verdict)
    "breathing": ("crack_rig.yaml", "healthy_1000rpm.h5", "breathing_crack_1000rpm.h5", "damage"),
    "repeat": ("crack_rig.yaml", "healthy_1000rpm.h5", "healthy_1000rpm_repeat.h5", "healthy"),
    "open_crack": ("crack_rig.yaml", "healthy_0rpm.h5", "open_crack_0rpm.h5", "damage"),
}
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


class _Text(HTMLParser):
    """The visible text of an HTML page (images' base64 data left out)."""

    def __init__(self) -> None:
        super().__init__()
        self.parts: list[str] = []

    def handle_data(self, data: str) -> None:
        self.parts.append(data)


def html_text(html: str) -> str:
    p = _Text()
    p.feed(re.sub(r"<style>.*?</style>", "", html, flags=re.S))
    return " ".join(p.parts)


def numbers(text: str) -> set[str]:
    return {m.lstrip("+") for m in NUMBER.findall(text)}


@pytest.fixture(scope="module")
def reports(sample_pipeline: Callable[..., tuple[Any, Any]]) -> dict[str, Any]:
    out = {}
    for name, (rig, healthy, new, _) in CASES.items():
        _, outcome = sample_pipeline(configs_dir() / rig, CR / healthy, CR / new)
        out[name] = outcome.typed_report()
    return out


@pytest.mark.parametrize("case", list(CASES))
def test_markdown_and_html_carry_the_same_numbers(reports: dict[str, Any], case: str) -> None:
    report = reports[case]
    assert report.verdict == CASES[case][3]
    md, html = render_markdown(report, []), html_text(render_detection_html(report, []))
    md_lines = [ln for ln in md.splitlines() if "sha256" not in ln]  # hashes: provenance, printed whole in HTML
    missing = numbers("\n".join(md_lines)) - numbers(html)
    assert not missing, f"numbers in report.md missing from report.html: {sorted(missing)[:20]}"
    for section in ("Conclusion", "Method"):
        assert f"## {section}" in md and section in html


@pytest.mark.parametrize("case", list(CASES))
def test_the_conclusion_opens_every_rendering_whole(reports: dict[str, Any], case: str) -> None:
    report = reports[case]
    text = report.conclusion
    assert text == conclusion(report) and text.startswith(report.verdict.capitalize() + ":")
    assert "Next:" in text and "It rests on:" in text and text.endswith(".")
    md = render_markdown(report, [])
    assert md.split("## Conclusion", 1)[1].strip().startswith(text)  # first section, whole
    html = render_detection_html(report, [])
    assert html.index('id="conclusion"') < html.index("The numbers")
    if report.verdict == "healthy":  # a healthy verdict shows no finding
        assert "most likely place" not in text and "located" not in text
    else:
        assert re.search(r"element \d+ \([\d.]+-[\d.]+ m", text)  # where: element and axial position (m)


@pytest.mark.parametrize("case", list(CASES))
def test_no_rule_text_is_cut(reports: dict[str, Any], case: str) -> None:
    report = reports[case]
    rule = report.verdict_rule
    assert rule.rstrip().endswith((".", ")")), rule  # a whole sentence, not cut mid-clause
    assert rule in render_markdown(report, [])
    assert rule in html_text(render_detection_html(report, []))


def test_csv_carries_the_estimate_the_reports_say_to_read(reports: dict[str, Any]) -> None:
    """fault_points.csv's D_u equals the anchored estimate of the HTML fault table (not the nominal-E22 one)."""
    report = reports["breathing"]
    rows = list(csv.DictReader(io.StringIO(render_csv(report))))
    assert len(rows) == report.n_fault_points > 0
    assert {r["damage_estimate"] for r in rows} == {"anchored at the healthy data"}
    f = np.asarray(report.frequency_hz)
    for r in rows:
        i = int(np.argmin(np.abs(f - float(r["frequency_hz"]))))
        assert float(r["damage_dynamics_re_n_per_m"]) == pytest.approx(report.damage_dynamics_anchored_re[i], rel=1e-6)
        assert float(r["damage_dynamics_re_n_per_m"]) != pytest.approx(report.damage_dynamics_re[i], rel=1e-3)
    html = html_text(render_detection_html(report, []))
    first = rows[0]
    assert format(float(first["damage_dynamics_re_n_per_m"]), ".4g") in html


def test_p_values_and_undefined_intervals_read_alike() -> None:
    assert fmt_p(0.0) == fmt_p(1e-300) == "< 1e-15" and fmt_p(0.0123) == "0.0123" and fmt_p(None) == "not computed"
    assert fmt_interval(float("nan"), 1.0) == "not defined (at the range edge)"
    assert fmt_interval(-0.5, 0.25) == "[-0.5, +0.25]"


RULES = ["rotorcheck.detectability:RULE", "rotorcheck.detectability:DETECTABILITY_RULE_SETS",
         "rotorcheck.robust.real_box:BOX_RULE", "rotorcheck.robust.joint:JOINT_RULE",
         "rotorcheck.robust.measured:MEASURED_RULE", "rotorcheck.robust.severity:SEVERITY_RULE",
         "rotorcheck.workflow.detectors.enclosure:VERDICT_RULE", "rotorcheck.workflow.checking:FILE_RULE",
         "rotorcheck.ranking:RANKING_RULE"]
#: words a whole sentence does not end on (location.json once ended "... a candidate is excluded when every slice is")
DANGLING = {"is", "are", "when", "the", "a", "an", "of", "and", "or", "to", "by", "with", "every", "if", "iff", "at"}


@pytest.mark.parametrize("name", RULES)
def test_no_rule_ends_mid_clause(name: str) -> None:
    import importlib

    module, attr = name.split(":")
    rule = getattr(importlib.import_module(module), attr)
    last = re.findall(r"[A-Za-z]+", rule)[-1].lower()
    assert last not in DANGLING, f"{name} ends on {last!r}: {rule[-80:]!r}"


def test_location_html_and_json_carry_the_rules_whole(located_open_crack: Any) -> None:
    import html as html_lib
    import json

    out = located_open_crack.out
    doc = json.loads((out / "location.json").read_text())
    page = html_lib.unescape((out / "location.html").read_text())
    assert doc["rule"] and doc["rule"] in page
    assert re.findall(r"[A-Za-z]+", doc["rule"])[-1].lower() not in DANGLING
