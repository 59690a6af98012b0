"""Detection reports: ``report.json`` (contract keys of cli.md), ``report.md``, ``fault_points.csv`` and the
self-contained ``report.html`` (:mod:`rotorcheck.report.html`).

All four are rendered in memory first and written atomically only when every one rendered, so a
failure never leaves a partial report.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.fileio import atomic_write_text
from rotorcheck.report.content import (
    BENIGN_HEADER,
    benign_rows,
    conclusion,
    damage_columns,
    fault_table,
    fmt_p,
    frequency_ranges,
    grid_step,
    headline_damage,
    method_paragraphs,
    where_paragraphs,
)
from rotorcheck.report.html import render_detection_html
from rotorcheck.report.schema import DetectionReport

REPORT_FILES = ("report.json", "report.md", "fault_points.csv", "report.html")


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        return x if math.isfinite(x) else ("inf" if x > 0 else "-inf" if x < 0 else "nan")
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def render_json(report: dict[str, Any]) -> str:
    """report.json text: non-finite numbers become the strings "inf"/"nan" (strict JSON)."""
    return json.dumps(_jsonable(report), indent=1) + "\n"


def render_csv(report: DetectionReport) -> str:
    """fault_points.csv: one row per fault point; the damage dynamics are the estimate the reports say to read
    (anchored at the healthy data where the detection made one, column ``damage_estimate`` says which)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    re, im, lo, hi, kind = damage_columns(report)  # the estimate the reports say to read (anchored where made)
    w.writerow(["frequency_hz", "gamma_healthy", "gamma_required", "damage_dynamics_re_n_per_m",
                "damage_dynamics_im_n_per_m", "damage_bound_min_abs_n_per_m", "damage_bound_max_abs_n_per_m",
                "damage_estimate"])
    for i, is_fault in enumerate(report.fault):
        if is_fault:
            w.writerow([f"{report.frequency_hz[i]:.6g}", f"{report.gamma_healthy[i]:.6e}",
                        f"{report.gamma_required[i]:.6e}", f"{re[i]:.6e}", f"{im[i]:.6e}", f"{lo[i]:.6e}",
                        f"{hi[i]:.6e}", kind])
    return buf.getvalue()


def render_markdown(report: DetectionReport, plots: list[str]) -> str:
    """report.md: the verdict, where, and what changed."""
    pairs = report.channel_pairs or []
    step = grid_step(report)
    fault = np.asarray(report.fault, dtype=bool)
    lines = [
        f"# rotorcheck detection: {report.verdict.upper()}",
        "",
        "## Conclusion",
        "",
        report.conclusion or conclusion(report),
        "",
        f"- sweep: `{report.sweep}` (run `{report.run_id}`, {report.speed_rpm:g} rpm), "
        f"sha256 `{report.sweep_sha256[:16]}`",
        f"- rig: `{report.rig_id}` (sha256 `{report.rig_sha256[:16]}`); damage port {report.damage_port}",
        f"- baseline: uncertainty `{report.uncertainty}`"
        + (f" on `{report.parameter}`" if report.parameter else "")
        + f", detection `{report.enclose}`, noise bound {report.noise_bound_m * 1e6:.4g} um "
        f"({report.noise_method})"
        + (f"; family-wise confidence {report.confidence:.0%}, sweep p-value {fmt_p(report.p_value)}"
           if report.confidence is not None else ""),
        f"- band {report.band_hz[0]:g}-{report.band_hz[1]:g} Hz, {report.n_points} points"
        + (f"; {len(pairs)} channel pairs (output<-input): {', '.join(pairs)}" if len(pairs) > 1 else ""),
        "",
        "## Verdict",
        "",
        f"**{report.verdict}**: {report.verdict_reason}.",
        "",
        *headline_damage(report),
        "## Where",
        "",
    ]
    lines += [x for para in where_paragraphs(report, lambda fs: frequency_ranges(fs, step)) for x in (para, "")]
    if report.verdict == "damage":
        lines += _what_changed(report, fault)
    else:  # a healthy (or undecided) verdict shows no finding
        lines += ["## What changed", "", "No finding: the verdict does not support a damage. The damage dynamics "
                  "estimated anyway stay in report.json (damage_dynamics_*), as estimates of a change that is not "
                  "there.", ""]
    lines += _method_section(report)
    for n in (report.notes or []):
        lines.append(f"- note: {n}")
    if plots:
        lines += ["", "## Plots", ""]
        for p in plots:
            name = Path(p).name
            lines += ([f"![{Path(p).stem}]({name})", ""] if name.endswith((".png", ".svg")) else [f"- `{name}`"])
    return "\n".join(lines) + "\n"


def _method_section(report: DetectionReport) -> list[str]:
    """The method (rule, joint test, benign change fitted): report.content's paragraphs and table."""
    lines = ["## Method", ""]
    step = grid_step(report)
    for para in method_paragraphs(report, lambda fs: frequency_ranges(fs, step)):
        lines += [para, ""]
    rows = benign_rows(report)
    if rows:
        lines += ["| " + " | ".join(BENIGN_HEADER) + " |", "|---|---:|---|---|---|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        lines.append("")
    return lines


def _what_changed(report: DetectionReport, fault: np.ndarray) -> list[str]:
    """The damage dynamics section: the estimate to read (anchored where made) over the fault points, as the
    other renderings show it (report.content.fault_table)."""
    lines = ["## What changed (damage dynamics D_u at the damage port, N/m)", ""]
    _, _, _, _, kind = damage_columns(report)
    if report.damage_dynamics_anchored_re is not None:
        conf = report.damage_anchored_bound_confidence
        extra = (" and with the damage-port channels in error as much as the io channel is on the healthy data"
                 if report.damage_anchored_channel_error is not None else "")
        a = np.asarray(report.damage_dynamics_anchored_re, dtype=float)
        sel = fault if np.any(fault) else np.ones_like(fault)
        lines += [f"Anchored estimate (E22 := the measured healthy FRF; bound: every D consistent with both sweeps' "
                  f"noise{f' at {conf:.0%} family-wise confidence' if conf else ''}{extra}), "
                  f"{'at the fault points' if np.any(fault) else 'over the band'}: median Re D_u = "
                  f"{np.median(a[sel]):.4g} N/m (positive: a stiffness loss).", ""]
    header, rows = fault_table(report)
    if rows:
        lines += [f"All {len(rows)} fault points (D_u {kind}; also in fault_points.csv):", "",
                  "| " + " | ".join(header) + " |", "|" + "---:|" * len(header)]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        lines.append("")
    if report.damage_dynamics_anchored_re is not None:
        lines += ["The nominal-E22 estimate (report.json `damage_dynamics_re/_im`) also carries the nominal model's "
                  "own error of E22; it is not shown here: read the anchored one.", ""]
    return lines


def write_reports(report: DetectionReport, out_dir: str | Path, plots: list[str],
                  baseline_path: str | Path | None = None) -> list[Path]:
    """Render all four files (report.json, report.md, fault_points.csv, report.html with the figures
    embedded), then write each atomically. Returns the paths."""
    out = Path(out_dir)
    texts = {
        "report.json": render_json(report.to_dict()),
        "report.md": render_markdown(report, plots),
        "fault_points.csv": render_csv(report),
        "report.html": render_detection_html(report, plots, baseline_path),
    }
    paths = []
    for name, text in texts.items():
        atomic_write_text(out / name, text)
        paths.append(out / name)
    return paths
