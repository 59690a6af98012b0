"""The demo fleet's trends (`make fleet-demo`: 20 machines x 10 weekly sweeps, seed 0) against the simulator's
truth: its two growing cracks and its benign bearing drift, each made exactly as in the demo
(tools.fleet_sim ``only``), checked through ``rotorcheck fleet`` as the demo runs it (``--limit 3000``; here
``--serial``).

The truth: a crack's growth of the low-frequency stiffness figure from the noise-free simulation of the crack
alone (the truth rig, the demo's loss rate), the drift's from the noise-free figure of every sweep
(tools.fleet_trends.true_growth)."""

from __future__ import annotations

import io
import json
import re
from pathlib import Path
from typing import Any

import pytest

from rotorcheck.cli import main
from tools.fleet_sim import make_fleet
from tools.fleet_trends import rows as trend_rows

DEMO = {"machine-01": "crack-A", "machine-02": "benign-drift", "machine-11": "crack-B"}
WORDS = re.compile(r"growing by ([\d.]+) N/m per day \[([\d.]+), ([\d.]+)\] \(95 %\)")


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    root = tmp_path_factory.mktemp("demo") / "fleet"
    root.mkdir()
    truth = make_fleet(root, machines=20, sweeps=10, seed=0, only=set(DEMO))
    assert {m: d["kind"] for m, d in truth["machines"].items()} == DEMO
    return root, truth


@pytest.mark.slow
def test_demo_trends_bracket_the_truth(demo: tuple[Path, Any], capsys: pytest.CaptureFixture[str]) -> None:
    root, _ = demo
    # --serial: the tasks in this process (the executors give the same summary byte for byte:
    # test_fleet_executors.py); a pool of 2 beside xdist's 2 workers on 2 cores costs 4-5 s CPU more (imports)
    rc = main(["fleet", str(root), "--limit", "3000", "--locate", "none", "--serial"])
    err = capsys.readouterr().err
    assert rc == 1  # the cracks are in alarm
    # progress on stderr, per sweep, with the time elapsed and left
    line = r"\[\d+/30\] detect machine-\d\d \S+: elapsed \d:\d\d:\d\d, about \d:\d\d:\d\d left"
    assert len(re.findall(line, err)) == 30
    table = {r["machine"]: r for r in trend_rows(root, root / "results")}
    for m, kind in DEMO.items():
        r = table[m]
        if kind.startswith("crack"):
            # the interval brackets the true growth, in numbers and in the words every report prints
            assert r["lo"] <= r["true"] <= r["hi"], r
            words = WORDS.search(r["trend"])
            assert words is not None and float(words[2]) <= r["true"] <= float(words[3]), r["trend"]
            assert "since the last change point" in r["trend"]
            assert r["verdict"] == "damage" and r["forecast"] and "crosses the limit 3000 N/m on" in r["prognosis"]
        else:  # the benign drift: healthy, and no crossing forecast
            assert r["verdict"] == "healthy" and not r["forecast"]
            assert "no forecast of the limit 3000 N/m: the benign ranges explain the change" in r["prognosis"]
            assert r["lo"] <= r["true"] <= r["hi"], r
    # the rules give the limit in use (they said "limit 0 N/m")
    rules = json.loads((root / "results" / "alerts.json").read_text())["rules"]
    assert "the limit (3000 N/m of the low-frequency Re D_u)" in rules["limit-exceeded"]
    html = (root / "results" / "index.html").read_text()
    assert "3000 N/m of the low-frequency Re D_u" in html and "limit 0 N/m" not in html
    # the alert list carries the trend in words
    assert WORDS.search((root / "results" / "alerts.txt").read_text()) is not None


def test_progress_lines_and_quiet() -> None:
    """The progress reporter off a terminal: one line per finished task with elapsed and left; none quiet."""
    from dataclasses import dataclass

    from rich.console import Console

    from rotorcheck.fleet.command import progress_reporter

    @dataclass
    class Task:
        stage: str = "detect"
        machine: str = "m"
        time: str = "2026-03-01T02:00:00Z"

    for quiet, want in ((False, 3), (True, 0)):
        buf = io.StringIO()
        con = Console(file=buf, force_terminal=False, width=200)
        with progress_reporter(con, quiet) as tick:
            for k in range(4):
                tick(Task(), k, 3)
        lines = [x for x in buf.getvalue().splitlines() if x]
        assert len(lines) == want
        if want:
            assert lines[-1].startswith("[3/3] detect m 2026-03-01T02:00:00Z: elapsed 0:00:0")
            assert lines[-1].endswith("about 0:00:00 left")
