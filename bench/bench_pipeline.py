"""End-to-end speed on the bundled samples.

- Validation of the 262-point healthy 1000 rpm sweep (enclose 'data': one LMI per point) against
  the closed form on the same points (baseline in the same run).
- Wall time of ``rotorcheck detect`` as a user runs it (a fresh process, plots included (PNG, the
  default), and with ``--no-plots``), against the start-up of ``rotorcheck --help`` and of
  ``python -c "import numpy"`` in the same run (issue 13's targets: <= 4x and <= 2.5x numpy), and
  the import time of ``detect --no-plots`` charged to each package (``-X importtime``, own times
  summed per package: rotorcheck by subpackage, others by top-level name), the ten largest.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck import workflow
from rotorcheck.config import load_config
from rotorcheck.nominal import nominal_model
from rotorcheck.robust.closed_form import gamma_required_siso
from rotorcheck.robust.validation import validate

ROOT = Path(__file__).resolve().parents[1]
CR = ROOT / "data_samples" / "crack_rig"


def _median(fn: Any, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def _cli(args: list[str], cwd: Path, codes: list[int] | None = None) -> float:
    env = dict(os.environ, MPLBACKEND="Agg")
    t = time.perf_counter()
    rc = subprocess.run([sys.executable, "-m", "rotorcheck", *args], cwd=cwd, env=env, check=False,
                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    if codes is not None:
        codes.append(rc)
    return time.perf_counter() - t


def _group(module: str) -> str:
    """The package an import is charged to: rotorcheck by subpackage, others by top-level name."""
    parts = module.split(".")
    if parts[0] == "rotorcheck" and len(parts) > 1:
        return ".".join(parts[:2])
    return parts[0]


def import_table(args: list[str], cwd: Path, top: int = 10) -> dict[str, Any]:
    """``python -X importtime -m rotorcheck args``: the import time (ms) charged to each package
    (the sum of its modules' own times, so that nothing is counted twice), the ``top`` largest, and
    the total."""
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-X", "importtime", "-m", "rotorcheck", *args], cwd=cwd, env=env,
                          check=False, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    own: dict[str, float] = {}
    for line in proc.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        fields = line[len("import time:"):].split("|")
        if not fields[0].strip().isdigit():
            continue  # the header line
        group = _group(fields[2].strip())
        own[group] = own.get(group, 0.0) + int(fields[0]) / 1000.0
    ranked = sorted(own.items(), key=lambda kv: -kv[1])
    return {"import_total_ms": sum(own.values()), "import_top_ms": dict(ranked[:top])}


def _python(args: list[str], cwd: Path) -> float:
    t = time.perf_counter()
    subprocess.run([sys.executable, *args], cwd=cwd, check=False, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def run(repeat: int = 5) -> dict[str, Any]:
    cfg = load_config(ROOT / "configs" / "crack_rig.yaml")
    run_h = workflow.load_run(CR / "healthy_1000rpm.h5", cfg)
    noise = workflow.fit_noise(run_h)
    model = nominal_model(cfg, run_h.frequency_hz, run_h.speed_rpm)
    t_lmi = _median(lambda: validate(model.me, run_h.W, run_h.Zt, noise, enclose="data"), repeat)
    t_cf = _median(lambda: gamma_required_siso(model.me, run_h.W, run_h.Zt, noise.value_m), max(repeat, 20))
    g_lmi = validate(model.me, run_h.W, run_h.Zt, noise, enclose="data").gamma
    g_cf = gamma_required_siso(model.me, run_h.W, run_h.Zt, noise.value_m)
    scale = np.maximum(np.abs(g_cf), 1e-300)
    err = float(np.max(np.where(g_cf > 0, np.abs(g_lmi - g_cf) / scale, np.abs(g_lmi))))
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        _cli(["validate", str(CR / "healthy_1000rpm.h5"), "--no-plots"], work)
        t_help = statistics.median(_cli(["--help"], work) for _ in range(3))
        t_numpy = statistics.median(_python(["-c", "import numpy"], work) for _ in range(5))
        codes: list[int] = []
        t_detect = statistics.median(
            _cli(["detect", str(CR / "breathing_crack_1000rpm.h5"), "--force"], work, codes) for _ in range(3))
        t_detect_np = statistics.median(
            _cli(["detect", str(CR / "breathing_crack_1000rpm.h5"), "--force", "--no-plots"], work, codes)
            for _ in range(3))
        imports = import_table(["detect", str(CR / "breathing_crack_1000rpm.h5"), "--force", "--no-plots"], work)
    return {
        "points": int(run_h.frequency_hz.size),
        "validate_lmi_s": t_lmi,
        "closed_form_s": t_cf,
        "lmi_over_closed_form": t_lmi / t_cf,
        "lmi_max_rel_error_vs_closed_form": err,
        "cli_help_s": t_help,
        "cli_detect_s": t_detect,
        "cli_detect_no_plots_s": t_detect_np,
        "detect_over_startup": t_detect / t_help,
        "python_import_numpy_s": t_numpy,
        "detect_over_numpy_startup": t_detect / t_numpy,
        "detect_no_plots_over_numpy_startup": t_detect_np / t_numpy,
        "help_over_numpy_startup": t_help / t_numpy,
        "cli_detect_exit_codes": sorted(set(codes)),  # 1: damage detected (the breathing crack)
        **imports,
    }


if __name__ == "__main__":
    for k, v in run().items():
        if isinstance(v, dict):
            print(k)
            for name, ms in v.items():
                print(f"  {name:34s} {ms:8.1f}")
            continue
        print(f"{k:36s} {v:.4g}" if isinstance(v, float) else f"{k:36s} {v}")
