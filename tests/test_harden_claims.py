"""Issue 32: outputs are claimed per run (an O_EXCL claim file beside each): a second run into the same
folder while the first writes is refused naming the first; a forced run removes what an earlier run of the
same command wrote and it did not rewrite (per the folder's manifest), nothing else."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rotorcheck import fileio
from rotorcheck.cli import main
from rotorcheck.errors import InputError
from rotorcheck.resources import samples_dir
from tests.shared_runs import CliRun

SAMPLES = samples_dir() / "crack_rig"
REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def validated(validated_0rpm: CliRun) -> Path:
    """A validated baseline of healthy_0rpm.h5 (the shared fit-noise and validate, conftest; read only: the
    tests pass it as --baseline and write elsewhere)."""
    return validated_0rpm.out / "baseline.h5"


@pytest.fixture
def live_pid() -> int:  # the pid of "the first run", still running
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    yield proc.pid
    proc.kill()
    proc.wait()


def _claim(target: Path, pid: int, command: str = "detect") -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    (target.parent / f".{target.name}{fileio.CLAIM_SUFFIX}").write_text(
        json.dumps({"command": command, "pid": pid, "started_utc": "2026-11-27T13:00:00Z"}))


def test_a_second_detect_while_the_first_writes_is_refused(validated: Path, tmp_path: Path, live_pid: int,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    _claim(out / "report.json", live_pid)
    assert main(["detect", str(SAMPLES / "open_crack_0rpm.h5"), "--baseline", str(validated), "--out", str(out),
                 "--no-plots"]) == 2
    msg = capsys.readouterr().err
    assert (f"error: {out / 'report.json'}: being written by another rotorcheck run (detect, pid {live_pid}, "
            "started 2026-11-27T13:00:00Z)") in msg
    assert sorted(p.name for p in out.iterdir()) == [f".report.json{fileio.CLAIM_SUFFIX}"]  # nothing written,
    # the first run's claim kept, this run's claims released


def test_a_claim_of_a_dead_run_is_taken_over(validated: Path, tmp_path: Path) -> None:
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    out = tmp_path / "out"
    _claim(out / "report.json", dead.pid)
    assert main(["detect", str(SAMPLES / "open_crack_0rpm.h5"), "--baseline", str(validated), "--out", str(out),
                 "--no-plots"]) == 1
    names = sorted(p.name for p in out.iterdir())
    assert "report.json" in names and not [n for n in names if n.endswith(fileio.CLAIM_SUFFIX)]


def test_outputs_published_after_the_first_check_are_refused(tmp_path: Path) -> None:
    """Run B checked an empty folder, run A then wrote and released: B's claim re-checks and refuses."""
    target = tmp_path / "report.json"
    target.write_text("{}")  # A's output
    with pytest.raises(InputError, match="exists; refusing to overwrite"):
        fileio.claim_outputs([target], False, "detect", fresh=[target])
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]  # B's claim released


def test_two_validate_runs_at_once_one_wins(tmp_path: Path) -> None:
    """Two real processes into one fresh folder: exactly one writes the baseline, the other exits 2."""
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "rotorcheck", "validate", str(SAMPLES / "healthy_0rpm.h5"), "--out", str(out),
           "--no-plots"]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    procs = [subprocess.Popen(cmd, env=env, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [(p.wait(timeout=300), p.stderr.read() if p.stderr else "") for p in procs]
    codes = sorted(rc for rc, _ in results)
    assert codes == [0, 2], results
    loser = next(text for rc, text in results if rc == 2)
    assert f"{out / 'baseline.h5'}" in loser and ("being written by another rotorcheck run (validate, pid" in loser
                                                   or "a validated baseline exists; refusing to overwrite" in loser)
    assert [p.name for p in out.iterdir() if p.name.endswith(fileio.CLAIM_SUFFIX)] == []


def test_forced_detect_without_plots_removes_the_older_runs_plots(validated: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.png").write_text("a user's file")
    sweep = str(SAMPLES / "open_crack_0rpm.h5")
    assert main(["detect", sweep, "--baseline", str(validated), "--out", str(out)]) == 1
    plots = sorted(p.name for p in out.glob("*.png") if p.name != "mine.png")
    assert plots  # the detection plots
    edited = out / plots[0]
    edited.write_bytes(edited.read_bytes() + b"edited")  # changed since: not rotorcheck's any more
    assert main(["detect", sweep, "--baseline", str(validated), "--out", str(out), "--no-plots"]) == 2  # no --force
    assert main(["detect", sweep, "--baseline", str(validated), "--out", str(out), "--no-plots", "--force"]) == 1
    left = sorted(p.name for p in out.iterdir())
    assert "mine.png" in left and edited.name in left
    assert not set(plots[1:]) & set(left)  # the older run's plots it did not rewrite are gone
    assert {"report.json", "report.md", "report.html", "fault_points.csv"} <= set(left)
    manifest = json.loads((out / fileio.MANIFEST_NAME).read_text())
    assert set(manifest["files"]) == {"report.json", "report.md", "report.html", "fault_points.csv", edited.name}
    assert set(manifest["commands"].values()) == {"detect"}


def test_a_forced_validate_keeps_what_detect_wrote(tmp_path: Path) -> None:
    out = tmp_path / "out"
    healthy = str(SAMPLES / "healthy_0rpm.h5")
    assert main(["validate", healthy, "--out", str(out), "--no-plots"]) == 0
    assert main(["detect", str(SAMPLES / "open_crack_0rpm.h5"), "--out", str(out), "--no-plots"]) == 1
    assert main(["validate", healthy, "--out", str(out), "--no-plots", "--force"]) == 0
    assert (out / "report.json").exists() and (out / "baseline.h5").exists()
