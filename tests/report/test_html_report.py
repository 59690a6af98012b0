"""Issue 14: the self-contained HTML report (and report.md) of a detection, checked as files and in a real
headless Chromium (skipped, saying so, where no Chromium is installed)."""

from __future__ import annotations

import base64
import hashlib
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from rotorcheck import __version__, workflow
from rotorcheck.cli import EXIT_DAMAGE
from rotorcheck.resources import samples_dir
from tests.shared_runs import CliRun

CR = samples_dir() / "crack_rig"
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--hide-scrollbars", "--disable-dev-shm-usage"]


def chromium() -> str | None:
    """A Chromium or Chrome executable on PATH (Debian: package chromium), or None."""
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="module")
def detected(detected_breathing_1000rpm: CliRun) -> Path:
    """`rotorcheck fit-noise`, `validate`, `detect` on the breathing crack at 1000 rpm, plots on (the run shared
    with tests/test_pipeline.py: conftest.detected_breathing_1000rpm, exit codes 0, 0, 1; read only)."""
    assert detected_breathing_1000rpm.codes[-1] == EXIT_DAMAGE
    return detected_breathing_1000rpm.out


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_html_is_self_contained_with_every_figure_and_fault_point(detected: Path) -> None:
    import json

    text = (detected / "report.html").read_text(encoding="utf-8")
    rep = json.loads((detected / "report.json").read_text())
    assert text.startswith("<!DOCTYPE html>")
    assert "<script" not in text and "<link" not in text  # nothing to fetch, nothing to run
    srcs = re.findall(r'(?:src|href)="([^"]*)"', text)
    assert srcs and all(s.startswith("data:image/png;base64,") for s in srcs), [s[:40] for s in srcs]
    # each detection figure embedded byte for byte
    embedded = [base64.b64decode(s.split(",", 1)[1]) for s in srcs]
    for stem in workflow.PLOT_STEMS_DETECT:
        assert (detected / f"{stem}.png").read_bytes() in embedded, stem
    # the fault table in full: one row per fault point, the frequencies of report.json
    table = text.split("Fault points: all", 1)[1].split("</table>", 1)[0]
    rows = re.findall(r"<tr><td class=\"num\">([0-9.]+)</td>", table)
    assert len(rows) == rep["n_fault_points"] > 5
    np.testing.assert_allclose([float(r) for r in rows], rep["fault_frequencies_hz"], atol=0.006)
    # inputs with their hashes (computed here from the files), the software version, the rule
    assert _sha256(CR / "breathing_crack_1000rpm.h5") in text
    assert _sha256(detected / "baseline.h5") in text
    assert rep["rig_sha256"] in text
    assert f"<td>rotorcheck</td><td>{__version__}</td>" in text
    assert "joint GLR" in text and ">DAMAGE<" in text


def test_markdown_shows_the_plots_and_the_whole_fault_table(detected: Path) -> None:
    import json

    md = (detected / "report.md").read_text()
    rep = json.loads((detected / "report.json").read_text())
    for stem in workflow.PLOT_STEMS_DETECT:
        assert f"![{stem}]({stem}.png)" in md
    rows = [ln for ln in md.splitlines() if re.match(r"^\| \d+\.\d\d \|", ln)]
    assert len(rows) == rep["n_fault_points"]
    headline = md.split("## Verdict", 1)[1].split("##", 1)[0]
    assert "anchored at the healthy data" in headline  # the headline D_u is the anchored one


def test_locate_writes_its_own_html(located_open_crack: CliRun) -> None:
    """`locate` writes location.html beside location.json: the figure embedded, every candidate element (the
    shared `fit-noise`, `validate`, `locate --elements 1,4,9` of the open crack: conftest.located_open_crack)."""
    import json

    out = located_open_crack.out
    assert located_open_crack.codes == (0, 0, EXIT_DAMAGE)  # fit-noise, validate, locate
    doc = json.loads((out / "location.json").read_text())
    text = (out / "location.html").read_text()
    srcs = re.findall(r'(?:src|href)="([^"]*)"', text)
    assert [base64.b64decode(s.split(",", 1)[1]) for s in srcs] == [(out / "location.png").read_bytes()]
    body = text.split("Candidates: all", 1)[1].split("</table>", 1)[0]
    assert len(re.findall(r"<tr><td class=\"num\">", body)) == len(doc["candidates"])
    assert f"Best element: <b>{doc['best_element']}</b>" in text
    assert _sha256(out / "baseline.h5") in text


def test_report_renders_in_headless_chromium(detected: Path, tmp_path: Path) -> None:
    """Chromium parses the page (the DOM holds the verdict and every figure) and paints it: the screenshot
    is the page's size, not blank, and shows the verdict badge's red at the top."""
    exe = chromium()
    if exe is None:
        pytest.skip("no Chromium on PATH (Debian: apt-get install chromium): the HTML report is checked as a file "
                    "only")
    url = (detected / "report.html").resolve().as_uri()
    profile = tmp_path / "profile"
    dom = subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--dump-dom", url],
                         capture_output=True, text=True, timeout=120, check=True).stdout
    assert 'id="verdict"' in dom and "DAMAGE" in dom
    assert dom.count("<img") == len(workflow.PLOT_STEMS_DETECT)
    shot = tmp_path / "report.png"
    subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--window-size=1200,2400",
                    f"--screenshot={shot}", url], capture_output=True, timeout=120, check=True)
    from matplotlib.image import imread

    img = imread(shot)
    assert img.shape[:2] == (2400, 1200)
    assert float(np.std(img[..., :3])) > 0.05  # painted, not blank
    top = img[:200, :, :3]
    red = (np.abs(top[..., 0] - 0xB0 / 255) < 0.08) & (top[..., 1] < 0.12) & (top[..., 2] < 0.2)
    assert np.count_nonzero(red) > 500  # the DAMAGE badge
    keep = os.environ.get("ROTORCHECK_SCREENSHOT_DIR")
    if keep:
        shutil.copy(shot, Path(keep) / "report_screenshot.png")
