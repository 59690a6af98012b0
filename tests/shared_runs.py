"""Command runs shared across test files and xdist workers (the fixtures are in conftest.py)."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import shutil
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest


@dataclass(frozen=True)
class CliRun:
    """What a shared command sequence left: its output folder (read only) and each command's exit code
    and standard output."""

    out: Path
    codes: tuple[int, ...]
    stdout: tuple[str, ...]

    def copy_to(self, dest: Path) -> Path:
        """A private copy of the output folder at ``dest`` (to write into)."""
        shutil.copytree(self.out, dest)
        return dest

    def json(self, k: int = -1) -> Any:
        """Command ``k``'s standard output as JSON (``--json``)."""
        return json.loads(self.stdout[k])


def shared_root(factory: pytest.TempPathFactory) -> Path:
    """A folder every xdist worker of this run sees: beside the workers' own base folders (popen-gwN)."""
    base = factory.getbasetemp()
    return (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "shared"


def run_key(name: str, steps: Sequence[Sequence[str]]) -> str:
    """``name`` and the sha256 of the commands and of every input file they name."""
    h = hashlib.sha256(json.dumps([list(s) for s in steps]).encode())
    for arg in sorted({a for s in steps for a in s}):
        if os.path.isfile(arg):
            h.update(hashlib.sha256(Path(arg).read_bytes()).digest())
    return f"{name}-{h.hexdigest()[:16]}"


def once(root: Path, key: str, make: Callable[[Path], None], timeout_s: float = 1800.0) -> Path:
    """``root/key`` made by ``make`` exactly once per run across the workers; ``make`` writes
    ``root/key/done.json`` last (that file's presence says the folder is complete)."""
    folder = root / key
    done = folder / "done.json"
    if done.exists():
        return folder
    root.mkdir(parents=True, exist_ok=True)
    try:
        os.close(os.open(root / f"{key}.lock", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:  # another worker makes it: wait
        deadline = time.monotonic() + timeout_s
        while not done.exists():
            failed = root / f"{key}.failed"
            if failed.exists():
                pytest.fail(f"another worker failed to make the shared {key}:\n{failed.read_text()}")
            if time.monotonic() > deadline:
                pytest.fail(f"the shared {key} was not made within {timeout_s:.0f} s")
            time.sleep(0.2)
        return folder
    try:
        folder.mkdir()
        make(folder)
    except BaseException:
        (root / f"{key}.failed").write_text(traceback.format_exc())
        raise
    return folder


def run_steps(folder: Path, steps: Sequence[Sequence[str]]) -> None:
    from rotorcheck.cli import main

    out = folder / "out"
    codes, stdout = [], []
    for argv in steps:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            codes.append(main([a.replace("{out}", str(out)) for a in argv]))
        stdout.append(buf.getvalue())
    tmp = folder / "done.json.tmp"
    tmp.write_text(json.dumps({"codes": codes, "stdout": stdout}))
    tmp.replace(folder / "done.json")


def cli_run(root: Path, name: str, steps: Sequence[Sequence[str]], base: CliRun | None = None) -> CliRun:
    """The ``rotorcheck`` commands ``steps`` (``{out}``: the output folder) run in-process once per pytest run
    under ``root`` (:func:`shared_root`), whichever worker asks first. ``base``: an earlier shared run whose
    output folder the commands start from (a copy): its commands' codes and outputs come first."""

    def make(folder: Path) -> None:
        if base is not None:
            base.copy_to(folder / "out")
        run_steps(folder, steps)

    key = run_key(name, steps) + ("" if base is None else f"-on-{base.out.parent.name}")
    folder = once(root, key, make)
    doc = json.loads((folder / "done.json").read_text())
    first = CliRun(folder, (), ()) if base is None else base
    return CliRun(folder / "out", first.codes + tuple(doc["codes"]), first.stdout + tuple(doc["stdout"]))


def crack_rig_sample(name: str) -> str:
    from rotorcheck.resources import samples_dir

    return str(samples_dir() / "crack_rig" / name)


def validate_0rpm_steps() -> list[list[str]]:
    """fit-noise and validate (measured, no plots) on the crack rig's healthy sweep at standstill."""
    h = crack_rig_sample("healthy_0rpm.h5")
    return [["fit-noise", h, "--out", "{out}"], ["validate", h, "--out", "{out}", "--no-plots"]]




def detect_breathing_1000rpm_steps() -> list[list[str]]:
    """fit-noise, validate (measured, plots) and detect --json (plots) of the crack rig's breathing crack at
    1000 rpm against its healthy sweep."""
    h = crack_rig_sample("healthy_1000rpm.h5")
    return [["fit-noise", h, "--out", "{out}"], ["validate", h, "--out", "{out}"],
            ["detect", crack_rig_sample("breathing_crack_1000rpm.h5"), "--out", "{out}", "--json"]]
