"""Suite-wide: the order the files run in under xdist, and artefacts that several test files share.

Order. ``pytest -n 2 --dist loadgroup`` (``make test``) hands each worker whole groups: a file, or the files
of one of :data:`SHARED_GROUPS` together (the units of :func:`pytest_xdist_make_scheduler`), so
that what those files share per worker (:func:`sample_pipeline`, tests/report/figure_checks.py's figures) is
computed once; ``--dist loadfile`` still runs (files apart, the shared work then done in each worker that
needs it). xdist sorts the units by their number of tests (``loadscopereorder``), which puts the few slow
end-to-end files last, where one worker ends up running them alone while the other idles. Here xdist's
reorder is off and the files known to be slow (:data:`SLOW_FIRST`, measured CPU time, longest first) run
first, a group where its first file ranks; the rest keep the collection's order and fill in behind them, so
the two workers finish together (longest processing time first).

Shared artefacts. A sequence of ``rotorcheck`` commands on the bundled samples that several files need (a
validated baseline, a location) runs once per pytest run (:func:`cli_once`): its output folder is kept under
the run's base temporary folder, which every xdist worker of the run sees, keyed by the sha256 of the
commands and of their input files. The first worker that needs it makes it, holding a lock file created
with ``O_EXCL``; another waits for it. The folder is read only for the tests: copy it (:meth:`CliRun.copy_to`)
before writing into it. Library pipelines (fit-noise, validate, detect in-process) are memoised per worker
(:func:`sample_pipeline`): their outcomes are shared objects, to read, never to change.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest

from tests.shared_runs import (
    CliRun,
    cli_run,
    crack_rig_sample,
    detect_breathing_1000rpm_steps,
    shared_root,
    validate_0rpm_steps,
)

#: the slowest test files, longest first: scheduled first under xdist, a SHARED_GROUPS group where its first
#: file ranks. The figures: CPU seconds per file (this process and the subprocesses it waited for) of a whole-suite
#: run with -n 2 --dist loadgroup on 2026-11-27 23:24, the 2-core machine shared (load average 3.5-4.5: about 1.5x
#: the figures of a quiet machine), rounded. test_fleet_runs.py makes the shared small fleet
#: (tests/fleet/conftest.small_fleet) before test_fleet_executors.py and test_fleet_dask_kill.py start, so that
#: neither waits for it; test_locate.py makes the shared open-crack location (conftest.located_open_crack) that
#: report/test_html_report.py reads later on.
SLOW_FIRST: tuple[str, ...] = (
    "tests/test_multichannel.py",  # 42, group sample_pipeline (101 with the three below): x/y end to end
    "tests/test_pipeline.py",  # 28
    "tests/report/test_detection_figures.py",  # 23
    "tests/report/test_report_parity.py",  # 8 (its detections are the files' above)
    "tests/report/test_model_figures.py",  # 28, group figures (43 with the file below)
    "tests/report/test_figure_layout.py",  # 16
    "tests/fleet/test_fleet_demo_trends.py",  # 42: the demo's 3 changing machines x 10 sweeps
    "tests/fleet/test_fleet_runs.py",  # 17 (with small_fleet)
    "tests/fleet/test_fleet_executors.py",  # 31: serial, processes, Dask
    "tests/sweep/test_sweep_simulator.py",  # 22: ODE time integration
    "tests/robust/test_robust_mu.py",  # 18: brute-force references
    # 18 (23 before `make test` let its 15 subprocesses reuse bytecode: 20.8 -> 16.7 s CPU measured alone)
    "tests/test_sigkill.py",  # commands in subprocesses, killed at four moments each
    "tests/faults/test_faults_time_sim.py",  # 17: harmonic balance against time integration
    "tests/test_compressor_rig.py",  # 16
    "tests/test_measured_detection.py",  # 15: Monte Carlo coverage
    "tests/test_cli_streams.py",  # 15
    "tests/fleet/test_fleet_dask_kill.py",  # 15
    "tests/test_golden.py",  # 14: 14 cases through the command line
    "tests/test_harden_claims.py",  # 14
    "tests/test_open_crack_series.py",  # 13
    "tests/test_install.py",  # 13: builds and installs the wheel
    "tests/test_detectability.py",  # 10
    "tests/test_uff_detect.py",  # 10
    "tests/robust/test_damage_block.py",  # 10
    "tests/test_locate.py",  # 9: the shared locate; detect and locate one element
    "tests/test_samples.py",  # 9: regenerates every bundled sample
    "tests/robust/test_severity.py",  # 8
    "tests/test_rig_features.py",  # 8
    "tests/report/test_html_report.py",  # 8
    "tests/fe/test_fe_plots.py",  # 7
    "tests/test_baseline_digest.py",  # 7
    "tests/test_ross_import.py",  # 7
    "tests/test_modal_anchor.py",  # 6
    "tests/robust/test_mixed_mu.py",  # 6
    "tests/fe/test_fe_taper_convergence.py",  # 5
    "tests/test_multirun.py",  # 5
)


#: files that share per-worker work, run by one worker under ``--dist loadgroup`` (group name: files)
SHARED_GROUPS: dict[str, tuple[str, ...]] = {
    # sample_pipeline: the open crack at standstill (measured), the breathing crack and the healthy repeat at
    # 1000 rpm against the measured baseline, each wanted by two of these files
    "sample_pipeline": ("tests/test_multichannel.py", "tests/report/test_report_parity.py",
                        "tests/report/test_detection_figures.py", "tests/test_pipeline.py"),
    # figure_checks.rotor_fig and mode_shapes_fig: the rotor drawings and the compressor's mode shapes
    "figures": ("tests/report/test_model_figures.py", "tests/report/test_figure_layout.py"),
}


#: where the run's temporary folders go when the default one is on a disk: a RAM file system (tmpfs). The suite
#: writes and removes a few thousand files (outputs, sweeps, fleets; each tool output fsync'ed): on this machine's
#: ext4 (mounted with discard) an unlink or fsync costs milliseconds, on tmpfs microseconds
FAST_TEMP_ROOT = Path("/dev/shm")


def use_fast_temp_root() -> None:
    """Put pytest's temporary folders (``tmp_path``, the shared runs) and ``tempfile``'s on :data:`FAST_TEMP_ROOT`
    when it is a writable tmpfs with room (2 GB free) and neither ``PYTEST_DEBUG_TEMPROOT`` nor ``TMPDIR`` names
    another place; else nothing changes. Called before any temporary folder exists; subprocesses inherit it."""
    if os.environ.get("PYTEST_DEBUG_TEMPROOT") or os.environ.get("TMPDIR"):
        return
    try:
        fs = next((line.split()[2] for line in Path("/proc/mounts").read_text().splitlines()
                   if line.split()[1] == str(FAST_TEMP_ROOT)), "")
        if fs != "tmpfs" or not os.access(FAST_TEMP_ROOT, os.W_OK | os.X_OK) or (
                shutil.disk_usage(FAST_TEMP_ROOT).free < 2e9):
            return
    except OSError:
        return
    os.environ["PYTEST_DEBUG_TEMPROOT"] = os.environ["TMPDIR"] = str(FAST_TEMP_ROOT)
    tempfile.tempdir = None  # tempfile.gettempdir() reads TMPDIR again


def pytest_configure(config: pytest.Config) -> None:
    use_fast_temp_root()
    if hasattr(config.option, "loadscopereorder"):  # xdist: keep the order below, not "most tests first"
        config.option.loadscopereorder = False


def unit_of(nodeid: str) -> str:
    """The xdist work unit of a test under ``--dist loadgroup``: its :data:`SHARED_GROUPS` group, else its file."""
    path = nodeid.split("::", 1)[0]
    return next((name for name, paths in SHARED_GROUPS.items() if path in paths), path)


@pytest.hookimpl(tryfirst=True, optionalhook=True)  # optional: pytest without xdist (-p no:xdist)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """``--dist loadgroup`` with the units of :func:`unit_of`, taken from the test ids on the controller.
    (xdist's own loadgroup reads ``xdist_group`` marks that the worker turns into an ``@group`` suffix of the
    test id; under pytest 9 that suffix is lost (the id is ``Node._id``, xdist writes ``_nodeid``), so every
    test was a unit of its own: the shared per-worker work was done in both workers.)"""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class FileGroupScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return unit_of(nodeid)

    return FileGroupScheduling(config, log)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    rank = {path: k for k, path in enumerate(SLOW_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(rank)))  # stable: files stay whole


@pytest.fixture(scope="session")
def cli_once(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str, Sequence[Sequence[str]]], CliRun]:
    """``cli_once(name, steps)``: the ``rotorcheck`` commands ``steps`` (argument lists; ``{out}`` stands for
    the output folder) run once per pytest run in-process, shared by every test and worker (read only)."""
    root = shared_root(tmp_path_factory)

    def run(name: str, steps: Sequence[Sequence[str]]) -> CliRun:
        return cli_run(root, name, steps)

    return run


@pytest.fixture(scope="session")
def validated_0rpm(cli_once: Callable[[str, Sequence[Sequence[str]]], CliRun]) -> CliRun:
    """`rotorcheck fit-noise` and `validate --no-plots` on crack_rig/healthy_0rpm.h5: ``out/baseline.h5``."""
    run = cli_once("validated_0rpm", validate_0rpm_steps())
    assert run.codes == (0, 0)
    return run


@pytest.fixture(scope="session")
def located_open_crack(validated_0rpm: CliRun, tmp_path_factory: pytest.TempPathFactory) -> CliRun:
    """:func:`validated_0rpm`'s commands (its folder copied, not run again), then `rotorcheck locate` of
    crack_rig/open_crack_0rpm.h5 with the candidate elements 1, 4 and 9 and ``--json`` (plots on):
    ``out/location.{json,html,png}``; the codes and outputs of the three commands."""
    return cli_run(shared_root(tmp_path_factory), "located_open_crack", [[
        "locate", crack_rig_sample("open_crack_0rpm.h5"), "--out", "{out}", "--elements", "1,4,9", "--json"]],
        base=validated_0rpm)


@pytest.fixture(scope="session")
def detected_breathing_1000rpm(cli_once: Callable[[str, Sequence[Sequence[str]]], CliRun]) -> CliRun:
    """`rotorcheck fit-noise`, `validate` and `detect --json` (plots on) of crack_rig/breathing_crack_1000rpm.h5
    against healthy_1000rpm.h5: ``out/report.{json,md,html}``, the plots; the last command's JSON (exit 1)."""
    run = cli_once("detected_breathing_1000rpm", detect_breathing_1000rpm_steps())
    assert run.codes == (0, 0, 1)  # fit-noise, validate, detect's DAMAGE
    return run


@pytest.fixture(scope="session")
def sample_pipeline() -> Callable[..., tuple[Any, Any]]:
    """``sample_pipeline(rig, healthy, new, enclose)``: fit-noise, validate (``enclose``) and detect through the
    library (paths to a rig file and two sweeps): the validation and detection outcomes, memoised in this worker
    (a validation shared by every new sweep against it; the outcomes hold closures: no pickling them for the
    other worker). Shared objects: read them, never change them."""
    from rotorcheck import workflow
    from rotorcheck.config import load_config

    validations: dict[tuple[str, str, str], Any] = {}
    detections: dict[tuple[str, str, str, str], Any] = {}

    def run(rig: str | Path, healthy: str | Path, new: str | Path, enclose: str = "measured") -> tuple[Any, Any]:
        key = (str(Path(rig).resolve()), str(Path(healthy).resolve()), enclose)
        if key not in validations:
            cfg = load_config(rig)
            run_h = workflow.load_run(healthy, cfg)
            validations[key] = cfg, workflow.validate(cfg, [run_h], workflow.fit_noise(run_h), enclose=enclose)
        cfg, val = validations[key]
        dkey = (*key, str(Path(new).resolve()))
        if dkey not in detections:
            detections[dkey] = workflow.detect(cfg, val.baseline, workflow.load_run(new, cfg))
        return val, detections[dkey]

    return run
