"""End-to-end regression on the bundled samples (the design card's CI regression).

Runs fit-noise, validate and detect through the command line on every bundled case and keeps a
summary (verdicts, fault counts and frequencies, noise bounds, gamma and D_u at a few points).
``python -m tools.golden --write`` (``make golden``) rewrites ``tests/golden/samples.json``;
without ``--write`` it compares and exits 1 on a difference. Nothing else rewrites the file.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.fileio import atomic_write_text
from rotorcheck.resources import configs_dir, samples_dir

GOLDEN = Path(__file__).resolve().parents[1] / "tests" / "golden" / "samples.json"
#: relative tolerance on floats (LMI solutions differ in the last digits across BLAS builds)
RTOL = 1e-5

# (name, rig, healthy sweep, new sweep, enclose)
CASES: tuple[tuple[str, str, str, str, str], ...] = (
    ("open_crack_0rpm_measured", "crack_rig.yaml", "crack_rig/healthy_0rpm.h5", "crack_rig/open_crack_0rpm.h5",
     "measured"),
    ("breathing_1000rpm_measured", "crack_rig.yaml", "crack_rig/healthy_1000rpm.h5",
     "crack_rig/breathing_crack_1000rpm.h5", "measured"),
    ("repeat_1000rpm_measured", "crack_rig.yaml", "crack_rig/healthy_1000rpm.h5",
     "crack_rig/healthy_1000rpm_repeat.h5", "measured"),
    ("free_running_2000rpm_measured", "crack_rig.yaml", "crack_rig/healthy_2000rpm.h5",
     "crack_rig/healthy_2000rpm_repeat.h5", "measured"),
    ("sidebands_10pct_1000rpm_measured", "crack_rig.yaml", "crack_rig_sidebands/healthy_1000rpm.h5",
     "crack_rig_sidebands/breathing_crack_10pct_1000rpm.h5", "measured"),
    ("three_mass_trial3_measured", "three_mass_trial3.yaml", "three_mass/healthy.h5", "three_mass/damaged.h5",
     "measured"),
    ("open_crack_0rpm_system", "crack_rig.yaml", "crack_rig/healthy_0rpm.h5", "crack_rig/open_crack_0rpm.h5", "system"),
    ("open_crack_0rpm_data", "crack_rig.yaml", "crack_rig/healthy_0rpm.h5", "crack_rig/open_crack_0rpm.h5", "data"),
    ("breathing_1000rpm_system", "crack_rig.yaml", "crack_rig/healthy_1000rpm.h5",
     "crack_rig/breathing_crack_1000rpm.h5", "system"),
    ("breathing_1000rpm_data", "crack_rig.yaml", "crack_rig/healthy_1000rpm.h5",
     "crack_rig/breathing_crack_1000rpm.h5", "data"),
    ("repeat_1000rpm_system", "crack_rig.yaml", "crack_rig/healthy_1000rpm.h5",
     "crack_rig/healthy_1000rpm_repeat.h5", "system"),
    ("repeat_1000rpm_data", "crack_rig.yaml", "crack_rig/healthy_1000rpm.h5",
     "crack_rig/healthy_1000rpm_repeat.h5", "data"),
    ("three_mass_trial1", "three_mass_trial1.yaml", "three_mass/healthy.h5", "three_mass/damaged.h5", "data"),
    ("three_mass_trial2", "three_mass_trial2.yaml", "three_mass/healthy.h5", "three_mass/damaged.h5", "data"),
    ("three_mass_trial3", "three_mass_trial3.yaml", "three_mass/healthy.h5", "three_mass/damaged.h5", "data"),
)


def _cli(argv: list[str]) -> tuple[int, str]:
    from rotorcheck.cli import main

    out, errbuf = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(errbuf):
        rc = main(argv)
    return rc, out.getvalue()


def _num(x: Any) -> float:
    return float(x)  # report.json spells non-finite numbers "inf" / "nan"


def run_case(name: str, rig: str, healthy: str, new: str, enclose: str, work: Path,
             shared: dict[tuple[str, ...], tuple[Path, int, str]] | None = None) -> dict[str, Any]:
    """One case through the CLI (library calls underneath); returns its summary.

    ``shared``: fit-noise and validate outputs of earlier cases (folder, exit code, JSON), keyed by rig and
    healthy sweep (and ``enclose``): a case with the same ones copies that folder instead of running the
    commands again (the same deterministic files and documents)."""
    out = work / name
    rig_path = str(configs_dir() / rig)
    h, n = str(samples_dir() / healthy), str(samples_dir() / new)
    memo = {} if shared is None else shared
    noise_key, val_key = ("fit-noise", rig, healthy), ("validate", rig, healthy, enclose)
    if noise_key in memo:
        _, rc_n, noise_doc = memo[noise_key]
    else:
        rc_n, noise_doc = _cli(["fit-noise", h, "--rig", rig_path, "--out", str(out), "--json"])
        memo[noise_key] = (_keep(out, work, "noise", len(memo)), rc_n, noise_doc)
    if val_key in memo:
        kept, rc_v, val_doc = memo[val_key]
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(kept, out)
    else:
        if not out.exists():
            shutil.copytree(memo[noise_key][0], out)
        rc_v, val_doc = _cli(["validate", h, "--rig", rig_path, "--out", str(out), "--enclose", enclose, "--json",
                              "--no-plots"])
        memo[val_key] = (_keep(out, work, "validated", len(memo)), rc_v, val_doc)
    rc_d, rep_doc = _cli(["detect", n, "--rig", rig_path, "--out", str(out), "--json", "--no-plots"])
    if rc_n != 0 or rc_v not in (0, 3) or rc_d not in (0, 1, 3):
        raise RuntimeError(f"{name}: exit codes fit-noise {rc_n}, validate {rc_v}, detect {rc_d}")
    noise = json.loads(noise_doc)
    val = json.loads(val_doc)
    rep = json.loads(rep_doc)
    f = np.asarray(rep["frequency_hz"], dtype=float)
    probe = np.unique(np.linspace(0, f.size - 1, 7).round().astype(int))
    d = np.asarray(rep["damage_dynamics_re"], float) + 1j * np.asarray(rep["damage_dynamics_im"], float)
    return {
        "exit_codes": [rc_n, rc_v, rc_d],
        "noise_bound_m": noise["noise_bound_m"],
        "gamma_median": float(np.median(np.asarray(val["gamma"], float))),
        "gamma_max": float(np.max(np.asarray(val["gamma"], float))),
        "n_not_enclosed": val["n_not_enclosed"],
        "verdict": rep["verdict"],
        "n_points": rep["n_points"],
        "n_fault_points": rep["n_fault_points"],
        "fault_frequencies_hz": rep["fault_frequencies_hz"],
        "probe_frequency_hz": f[probe].tolist(),
        "probe_gamma_required": [_num(rep["gamma_required"][i]) for i in probe],
        "probe_damage_re": d.real[probe].tolist(),
        "probe_damage_im": d.imag[probe].tolist(),
        **_anchored(rep, probe),
        **({} if not rep.get("sideband_test") else {
            "sideband_verdict": rep["sideband_test"]["verdict"],
            "sideband_statistic": rep["sideband_test"]["statistic"],
            "sideband_p_value": rep["sideband_test"]["p_value"]}),
    }


def _keep(out: Path, work: Path, what: str, k: int) -> Path:
    """A copy of the output folder ``out`` as it is now, for later cases to start from (read only)."""
    kept = work / f"_{what}_{k}"
    shutil.copytree(out, kept)
    return kept


def _anchored(rep: dict[str, Any], probe: np.ndarray) -> dict[str, Any]:
    if "damage_dynamics_anchored_re" not in rep:
        return {}
    a = np.asarray(rep["damage_dynamics_anchored_re"], float)
    return {"probe_anchored_re": a[probe].tolist(),
            "probe_anchored_max_abs": [_num(rep["damage_anchored_bound_max_abs"][i]) for i in probe]}


def compute() -> dict[str, Any]:
    """All cases, in a temporary folder (fit-noise once per rig and healthy sweep, validate once per enclose)."""
    with tempfile.TemporaryDirectory() as tmp:
        shared: dict[tuple[str, ...], tuple[Path, int, str]] = {}
        return {c[0]: run_case(*c, work=Path(tmp), shared=shared) for c in CASES}


def _close(a: Any, b: Any, path: str, problems: list[str]) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                problems.append(f"{path}.{k}: missing on one side")
            else:
                _close(a[k], b[k], f"{path}.{k}", problems)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            problems.append(f"{path}: length {len(a)} != {len(b)}")
        else:
            for i, (x, y) in enumerate(zip(a, b)):
                _close(x, y, f"{path}[{i}]", problems)
    elif isinstance(a, float) or isinstance(b, float):
        x, y = float(a), float(b)
        same = x == y or (math.isnan(x) and math.isnan(y))
        if not (same or (math.isfinite(x) and math.isfinite(y) and abs(x - y) <= RTOL * max(abs(x), abs(y), 1e-300))):
            # absolute floor for quantities that should be zero (imaginary parts, gamma 0)
            if not (abs(x) < 1e-9 * 1e-3 and abs(y) < 1e-9 * 1e-3):
                problems.append(f"{path}: {x!r} != {y!r}")
    elif a != b:
        problems.append(f"{path}: {a!r} != {b!r}")


def compare(current: dict[str, Any], golden: dict[str, Any]) -> list[str]:
    """Differences beyond :data:`RTOL` (counts, verdicts and fault frequencies exactly)."""
    problems: list[str] = []
    _close(current, golden, "golden", problems)
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", action="store_true", help="rewrite tests/golden/samples.json")
    args = parser.parse_args(argv)
    current = compute()
    if args.write:
        GOLDEN.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(GOLDEN, json.dumps(current, indent=1, sort_keys=True) + "\n")
        print(f"wrote {GOLDEN}", file=sys.stderr)
        return 0
    if not GOLDEN.exists():
        print(f"{GOLDEN} missing: run 'make golden'", file=sys.stderr)
        return 1
    problems = compare(current, json.loads(GOLDEN.read_text()))
    for p in problems[:50]:
        print(p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
