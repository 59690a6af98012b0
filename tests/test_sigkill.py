"""Issue 16: SIGKILL of simulate, validate and detect at spread moments: the output is either absent (or the
previous one, untouched) or complete and readable; never partial. ``ROTORCHECK_KILL_MOMENTS`` sets how many
moments per command (default 4 in the suite; the note's run used 20)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rotorcheck.baseline import read_baseline
from rotorcheck.resources import samples_dir
from rotorcheck.sweep import read_sweep
from tests.shared_runs import CliRun

CR = samples_dir() / "crack_rig"
MOMENTS = int(os.environ.get("ROTORCHECK_KILL_MOMENTS", "4"))


def _cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "rotorcheck", *args]


def _env() -> dict[str, str]:
    return dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")


def _duration(cmd: list[str], cwd: Path) -> float:
    t = time.perf_counter()
    rc = subprocess.run(cmd, cwd=cwd, env=_env(), check=False, capture_output=True).returncode
    assert rc in (0, 1), rc  # 1: detect's DAMAGE
    return time.perf_counter() - t


def _kill_at(cmd: list[str], cwd: Path, delay: float) -> int:
    proc = subprocess.Popen(cmd, cwd=cwd, env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(delay)
    if proc.poll() is None:
        proc.send_signal(signal.SIGKILL)
    return proc.wait()


@pytest.mark.parametrize("command", ["simulate", "validate", "detect"])
def test_sigkill_never_leaves_a_partial_output(tmp_path: Path, command: str, validated_0rpm: CliRun) -> None:
    work = tmp_path / "w"
    work.mkdir()
    out = work / "out"
    if command == "simulate":
        target = work / "s.h5"
        cmd = _cmd("simulate", str(target), "--speed", "1000", "--points", "60", "--periods", "16", "--force")

        def check() -> None:
            read_sweep(target)
    else:
        validated_0rpm.copy_to(out)  # a validated baseline of healthy_0rpm.h5 (the shared one, conftest)
        if command == "validate":
            target = out / "baseline.h5"
            cmd = _cmd("validate", str(CR / "healthy_0rpm.h5"), "--out", str(out), "--no-plots", "--force")

            def check() -> None:
                assert read_baseline(target).validated
        else:
            target = out / "report.json"
            cmd = _cmd("detect", str(CR / "open_crack_0rpm.h5"), "--out", str(out), "--no-plots", "--force")

            def check() -> None:
                import json

                assert json.loads(target.read_text())["verdict"]
    full = _duration(cmd, work)  # also leaves a complete previous output in place
    check()
    killed = 0
    for k in range(MOMENTS):
        delay = full * (0.15 + 0.9 * k / max(MOMENTS - 1, 1))
        rc = _kill_at(cmd, work, delay)
        assert target.exists()  # the previous output is never removed
        check()  # and it is complete: the previous one or the new one, never a mix
        assert rc in (0, 1, -signal.SIGKILL), rc
        killed += rc == -signal.SIGKILL
    assert killed >= 1, "no moment killed the command: it ended before every kill, and nothing was tested"
