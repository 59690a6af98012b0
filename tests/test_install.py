"""Installable (issue 12): the bundled rigs and samples are package data, and the built wheel, installed
into a fresh virtual environment outside the checkout, runs the sample commands.

The fresh environment gets the project's dependencies from this interpreter's site-packages through a
``.pth`` file (no network, no download): a path line in a ``.pth`` file is only appended to sys.path,
the ``.pth`` files inside that folder (the editable install's finder) are not run, so the wheel's
rotorcheck in the new environment is the one imported; the test asserts it.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import shutil
import site
import subprocess
import sys
import zipfile
from importlib.resources import files
from pathlib import Path

import pytest

from rotorcheck import resources
from tests.test_samples import CLI_MD_CONFIGS, CLI_MD_SAMPLES  # cli.md "Bundled files", copied once

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT.parent / "shared" / "spec" / "cli.md"

#: what the wheel is built from (copied out of the checkout, so no build/ or egg-info lands in it)
SOURCE_ITEMS = ("pyproject.toml", "README.md", "MANIFEST.in", "setup.py", "setup.cfg", "rotorcheck", "configs",
                "data_samples")


def test_the_list_is_the_specs() -> None:
    if not SPEC.is_file():
        pytest.skip(f"{SPEC} not beside the checkout")
    text = SPEC.read_text(encoding="utf-8")
    section = text[text.index("Bundled files"):]
    for name in CLI_MD_CONFIGS:
        assert f"configs/{name}" in section
    for name in CLI_MD_SAMPLES:
        assert Path(name).name in section


@pytest.mark.parametrize(("folder", "name"), [("configs", n) for n in CLI_MD_CONFIGS]
                         + [("data_samples", n) for n in CLI_MD_SAMPLES])
def test_importlib_resources_finds_every_bundled_file(folder: str, name: str) -> None:
    bundled = files("rotorcheck").joinpath("_bundled").joinpath(folder).joinpath(name)
    assert bundled.is_file()
    assert bundled.read_bytes() == (ROOT / folder / name).read_bytes()  # the top-level folders are the truth


def test_resources_default_to_the_package_data(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    for var in ("ROTORCHECK_CONFIGS", "ROTORCHECK_SAMPLES"):
        monkeypatch.delenv(var, raising=False)
    package = Path(str(files("rotorcheck")))
    assert resources.configs_dir() == package / "_bundled" / "configs"
    assert resources.samples_dir() == package / "_bundled" / "data_samples"
    assert resources.default_rig_path("crack_rig") == resources.configs_dir() / "crack_rig.yaml"
    monkeypatch.setenv("ROTORCHECK_CONFIGS", str(tmp_path / "c"))
    monkeypatch.setenv("ROTORCHECK_SAMPLES", str(tmp_path / "s"))
    assert (resources.configs_dir(), resources.samples_dir()) == (tmp_path / "c", tmp_path / "s")


# ------------------------------------------------------------------------------------------------
# the wheel, installed outside the checkout


def _env(extra_path: Path | None = None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "ROTORCHECK_CONFIGS", "ROTORCHECK_SAMPLES",
                        "VIRTUAL_ENV")}
    env.update(MPLBACKEND="Agg", PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1",
               OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")  # beside xdist workers
    if extra_path is not None:
        env["PATH"] = f"{extra_path}{os.pathsep}{env.get('PATH', '')}"
    return env


def _run(cmd: list[str], cwd: Path, env: dict[str, str], ok: tuple[int, ...] = (0,)
         ) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode in ok, f"{cmd}: exit {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    return proc


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel built (no build isolation, no index) from a copy of the checkout's sources."""
    work = tmp_path_factory.mktemp("wheel")
    src = work / "src"
    src.mkdir()
    for name in SOURCE_ITEMS:
        if (ROOT / name).is_dir():  # symlinks=True: rotorcheck/_bundled/* stay links into the copy
            shutil.copytree(ROOT / name, src / name, symlinks=True,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc", ".*"))
        elif (ROOT / name).is_file():
            shutil.copy2(ROOT / name, src / name)
    _run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation", "--no-index",
          "-w", str(work / "dist"), str(src)], work, _env())
    (whl,) = (work / "dist").glob("rotorcheck-*.whl")
    return whl


@pytest.mark.install
def test_the_wheel_carries_every_module_config_and_sample(wheel: Path) -> None:
    src = wheel.parents[1] / "src"
    with zipfile.ZipFile(wheel) as zf:
        names = set(zf.namelist())
    expected = {p.relative_to(src).as_posix() for p in (src / "rotorcheck").rglob("*.py")}
    for folder in ("configs", "data_samples"):
        expected |= {f"rotorcheck/_bundled/{p.relative_to(src).as_posix()}"
                     for p in (src / folder).rglob("*") if p.is_file()}
    assert not expected - names, f"missing from the wheel: {sorted(expected - names)}"
    assert "rotorcheck/py.typed" in names


@pytest.mark.install
@pytest.mark.slow
def test_the_installed_wheel_runs_the_samples_outside_the_checkout(wheel: Path, tmp_path: Path) -> None:
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp_path, _env())
    bindir = venv / ("Scripts" if os.name == "nt" else "bin")
    py = bindir / ("python.exe" if os.name == "nt" else "python")
    env = _env(bindir)
    # install first, while the new environment sees nothing of ours (pip then finds no rotorcheck to replace)
    _run([sys.executable, "-m", "pip", "--python", str(py), "install", "--quiet", "--no-deps", "--no-index",
          str(wheel)], tmp_path, env)
    purelib = _run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                   tmp_path, env).stdout.strip()
    deps = [p for p in dict.fromkeys(site.getsitepackages()) if Path(p).is_dir()]
    (Path(purelib) / "_rotorcheck_test_deps.pth").write_text("".join(f"{p}\n" for p in deps), encoding="utf-8")

    run = tmp_path / "run"  # cwd: the checkout is not on sys.path
    run.mkdir()
    probe = _run([str(py), "-c", "import importlib.metadata as m, rotorcheck, rotorcheck.resources as r; "
                  "print(rotorcheck.__file__); print(r.configs_dir()); print(m.version('rotorcheck'))"],
                 run, env).stdout.split("\n")
    assert Path(probe[0]).is_relative_to(venv), f"imported {probe[0]}, not the wheel in {venv}"
    assert Path(probe[1]).is_relative_to(venv) and (Path(probe[1]) / "crack_rig.yaml").is_file()
    assert probe[2] == importlib.metadata.version("rotorcheck")

    exe = str(bindir / "rotorcheck")
    assert _run([exe, "--version"], run, env).stdout == f"rotorcheck {probe[2]}\n"
    samples = Path(_run([exe, "--samples-dir"], run, env).stdout.strip())
    assert samples.is_relative_to(venv)
    assert {str(p.relative_to(samples)) for p in samples.rglob("*.h5")} >= set(CLI_MD_SAMPLES)

    # the README's sequence: fit-noise --demo uses the bundled healthy sweep and its bundled rig
    _run([exe, "fit-noise", "--demo"], run, env)
    _run([exe, "validate", str(samples / "crack_rig" / "healthy_1000rpm.h5"), "--no-plots"], run, env)
    proc = _run([exe, "detect", str(samples / "crack_rig" / "breathing_crack_1000rpm.h5"), "--no-plots", "--json"],
                run, env, ok=(1,))
    report = json.loads(proc.stdout)
    assert report["verdict"] == "damage"
    assert (run / "rotorcheck-out" / "report.json").is_file()
