"""The documentation's links and command names (issue 31): every relative link in README.md and docs/*.md
points to an existing file (and, with a #fragment, to a heading of that file, by GitHub's anchor rule), and
every ``rotorcheck <command>`` written as code in README.md is a command of the CLI."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import typer

from rotorcheck.cli import app

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)
SPAN = re.compile(r"`([^`\n]+)`")
COMMAND = re.compile(r"\brotorcheck +([a-z][a-z-]*)")


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation other than '-' and '_' dropped, spaces to '-'."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    return {_anchor(m.group(1)) for m in re.finditer(r"^#{1,6} +(.+?) *$", text, re.M)}


def _links(page: Path) -> list[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    return LINK.findall(text)


def test_anchor_rule_matches_github() -> None:
    """Two headings of these pages with their anchors as GitHub renders them (punctuation dropped, each space
    a hyphen, so ' -m ' gives '--m')."""
    heading = "Detection power (`python -m bench.detection_power`)"
    assert _anchor(heading) == "detection-power-python--m-benchdetection_power"
    assert _anchor("5. A verdict: `detect`") == "5-a-verdict-detect"


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_relative_links_point_to_existing_files_and_headings(page: Path) -> None:
    links = _links(page)
    broken = []
    for link in links:
        if re.match(r"^[a-z][a-z0-9+.-]*:", link):  # http:, https:, mailto:
            continue
        path, _, fragment = link.partition("#")
        target = (page.parent / path).resolve() if path else page
        if not target.exists():
            broken.append(f"{link}: no file {target}")
        elif fragment and target.suffix == ".md" and fragment not in _anchors(target):
            broken.append(f"{link}: no heading #{fragment} in {target.name}")
    assert not broken, f"{page.name}: " + "; ".join(broken)


def test_the_readme_links_every_docs_page() -> None:
    readme = {(ROOT / link.partition("#")[0]).resolve() for link in _links(ROOT / "README.md")}
    assert set(PAGES[1:]) <= readme, f"not linked from README.md: {sorted(p.name for p in set(PAGES[1:]) - readme)}"


def test_every_command_named_in_the_readme_exists() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    code = [m.group(0) for m in FENCE.finditer(text)] + SPAN.findall(FENCE.sub("", text))
    named = {c for chunk in code for c in COMMAND.findall(chunk)}
    commands = set(typer.main.get_command(app).commands)  # type: ignore[attr-defined]
    assert len(named) >= 10, f"too few commands found in README.md's code: {sorted(named)}"
    assert named <= commands, f"README.md names commands the CLI lacks: {sorted(named - commands)}"
    assert commands <= named, f"commands README.md does not name: {sorted(commands - named)}"
