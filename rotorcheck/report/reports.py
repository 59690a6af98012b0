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
from rotorcheck.report.content import best_candidate, headline_damage
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
    """fault_points.csv: one row per fault point."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["frequency_hz", "gamma_healthy", "gamma_required", "damage_dynamics_re_n_per_m",
                "damage_dynamics_im_n_per_m", "damage_bound_min_abs_n_per_m", "damage_bound_max_abs_n_per_m"])
    for i, is_fault in enumerate(report.fault):
        if is_fault:
            w.writerow([f"{report.frequency_hz[i]:.6g}", f"{report.gamma_healthy[i]:.6e}",
                        f"{report.gamma_required[i]:.6e}", f"{report.damage_dynamics_re[i]:.6e}",
                        f"{report.damage_dynamics_im[i]:.6e}", f"{report.damage_bound_min_abs[i]:.6e}",
                        f"{report.damage_bound_max_abs[i]:.6e}"])
    return buf.getvalue()


def _ranges(freqs: list[float], step: float) -> str:
    if not freqs:
        return "none"
    out, start, prev = [], freqs[0], freqs[0]
    for f in freqs[1:]:
        if f - prev > 1.5 * step:
            out.append((start, prev))
            start = f
        prev = f
    out.append((start, prev))
    return ", ".join(f"{a:.1f}" if a == b else f"{a:.1f}-{b:.1f}" for a, b in out) + " Hz"


def render_markdown(report: DetectionReport, plots: list[str]) -> str:
    """report.md: the verdict, where, and what changed."""
    pairs = report.channel_pairs or []
    f = np.asarray(report.frequency_hz, dtype=float)
    step = _step(report)
    fault = np.asarray(report.fault, dtype=bool)
    d = np.asarray(report.damage_dynamics_re) + 1j * np.asarray(report.damage_dynamics_im)
    lines = [
        f"# rotorcheck detection: {report.verdict.upper()}",
        "",
        f"- sweep: `{report.sweep}` (run `{report.run_id}`, {report.speed_rpm:g} rpm), "
        f"sha256 `{report.sweep_sha256[:16]}`",
        f"- rig: `{report.rig_id}` (sha256 `{report.rig_sha256[:16]}`); damage port {report.damage_port}",
        f"- baseline: uncertainty `{report.uncertainty}`"
        + (f" on `{report.parameter}`" if report.parameter else "")
        + f", detection `{report.enclose}`, noise bound {report.noise_bound_m * 1e6:.4g} um "
        f"({report.noise_method})"
        + (f"; family-wise confidence {report.confidence:.0%}, sweep p-value {report.p_value:.3g}"
           if report.confidence is not None else ""),
        f"- band {report.band_hz[0]:g}-{report.band_hz[1]:g} Hz, {report.n_points} points"
        + (f"; {len(pairs)} channel pairs (output<-input): {', '.join(pairs)}" if len(pairs) > 1 else ""),
        "",
        "## Verdict",
        "",
        f"**{report.verdict}**: {report.verdict_reason}.",
        "",
        *headline_damage(report),
        f"Rule: {report.verdict_rule}.",
        "",
        *_joint_section(report),
        "## Where",
        "",
        f"{report.n_fault_points} of {report.n_points} points are certified fault points "
        f"(the healthy uncertain model cannot explain them): {_ranges(list(f[fault]), step)}.",
        "",
    ]
    status = np.asarray(report.status)
    bad = [s for s in np.unique(status) if s not in ("ok", "fault")]
    for s in bad:
        lines.append(f"- {int(np.count_nonzero(status == s))} points with status `{s}`: "
                     f"{_ranges(list(f[status == s]), step)}")
    if bad:
        lines.append("")
    if report.verdict == "damage":
        lines += _what_changed(report, f, fault, d)
    else:  # a healthy (or undecided) verdict shows no finding
        lines += ["## What changed", "", "No finding: the verdict does not support a damage. The damage dynamics "
                  "estimated anyway stay in report.json (damage_dynamics_*), as estimates of a change that is not "
                  "there.", ""]
    for n in (report.notes or []):
        lines.append(f"- note: {n}")
    if plots:
        lines += ["", "## Plots", ""]
        for p in plots:
            name = Path(p).name
            lines += ([f"![{Path(p).stem}]({name})", ""] if name.endswith((".png", ".svg")) else [f"- `{name}`"])
    return "\n".join(lines) + "\n"


def _step(report: DetectionReport) -> float:
    """The grid step (Hz) for writing frequency ranges."""
    f = np.asarray(report.frequency_hz, dtype=float)
    return float(np.median(np.diff(f))) if f.size > 1 else 1.0


def _joint_section(report: DetectionReport) -> list[str]:
    """The joint test: statistic, the best candidate with its interval, benign parameters, detectable size."""
    if report.joint_statistic is None:
        return []
    lines = ["## Joint test", "",
             f"T = {report.joint_statistic:.4g}, threshold {report.joint_threshold:.4g} at false-alarm rate "
             f"{report.false_alarm:g} (p = {report.joint_p_value:.3g}); model-error fraction kappa = "
             f"{report.benign_model_error:g}; {report.learned_benign_directions} benign directions learned "
             "from healthy sweeps.", ""]
    best = best_candidate(report)
    if best is not None:
        lines += [f"Best candidate: {best}.", ""]
    if report.benign_parameters:
        lines += ["| benign parameter | estimate | 95 % interval | at range edge |", "|---|---:|---|---|"]
        for b in report.benign_parameters:
            lo, hi = b["interval"]
            lines.append(f"| {b['name']} | {b['estimate']:+.4g} {b['unit']} | [{lo:+.4g}, {hi:+.4g}] | "
                         f"{'yes' if b['at_range_edge'] else 'no'} |")
        lines.append("")
    beyond = report.fault_beyond_benign_frequencies_hz
    if beyond is not None:
        lines += [f"{len(beyond)} points stay unexplained after the fitted benign change (per point, the noise and "
                  f"the model-error allowance, Sidak at {report.false_alarm:g} over the points)"
                  + (f": {_ranges(list(beyond), _step(report))}." if beyond else "."), ""]
    cert = report.certified_beyond_benign_frequencies_hz
    if cert is not None:
        lines += [f"{len(cert)} points are certified beyond every benign change inside the ranges (parameters real, "
                  f"branch and bound; {report.n_undecided_beyond_benign} undecided; with each parameter a complex "
                  f"disc instead: {report.n_certified_beyond_benign_complex})"
                  + (f": {_ranges(list(cert), _step(report))}." if cert else "."), ""]
    els, det = report.candidate_elements or [], report.detectable_stiffness_loss or []
    if els:
        lines += ["Smallest stiffness loss this sweep could reveal (90 % power at the stated rate): "
                  + ", ".join(f"element {e}: {100 * x:.3g} %" for e, x in zip(els, det)) + ".", ""]
    return lines


def _what_changed(report: DetectionReport, f: np.ndarray, fault: np.ndarray, d: np.ndarray) -> list[str]:
    """The damage dynamics section: the anchored estimate and its bound first, the nominal one after."""
    lines = ["## What changed (damage dynamics D_u at the damage port, N/m)", ""]
    if report.damage_dynamics_anchored_re is not None:
        a = np.asarray(report.damage_dynamics_anchored_re) + 1j * np.asarray(report.damage_dynamics_anchored_im)
        lo = np.asarray(report.damage_anchored_bound_min_abs, dtype=float)
        hi = np.asarray(report.damage_anchored_bound_max_abs, dtype=float)
        conf = report.damage_anchored_bound_confidence
        where = "at the fault points" if np.any(fault) else "over the band"
        sel = fault if np.any(fault) else np.ones_like(fault)
        extra = (" and with the damage-port channels in error as much as the io channel is on the healthy data"
                 if report.damage_anchored_channel_error is not None else "")
        lines.append(f"Anchored estimate (E22 := the measured healthy FRF; bound: every D consistent with both "
                     f"sweeps' noise{f' at {conf:.0%} family-wise confidence' if conf else ''}{extra}), {where}: "
                     f"median Re D_u = {np.median(a[sel].real):.4g} N/m (positive: a stiffness loss).")
        lines.append("")
        idx = np.flatnonzero(sel)
        lines.append(f"All {idx.size} {'fault points' if np.any(fault) else 'points'} (also in fault_points.csv):")
        lines.append("")
        lines.append("| f (Hz) | D_u anchored (N/m) | min abs | max abs | D_u nominal E22 (N/m) |")
        lines.append("|---:|---:|---:|---:|---:|")
        for i in idx:
            lines.append(f"| {f[i]:.2f} | {a[i].real:.4g}{a[i].imag:+.3g}j | {lo[i]:.4g} | {hi[i]:.4g} | "
                         f"{d[i].real:.4g}{d[i].imag:+.3g}j |")
        lines.append("")
        lines.append("The nominal-E22 estimate (last column, report.json `damage_dynamics_re/_im`) also carries the "
                     "nominal model's own error of E22; read the anchored one.")
        lines.append("")
    elif np.any(fault):
        idx = np.flatnonzero(fault)
        lines += [f"All {idx.size} fault points (also in fault_points.csv):", ""]
        lines.append("| f (Hz) | gamma healthy | gamma required | D_u (N/m) | min abs D_u | max abs D_u |")
        lines.append("|---:|---:|---:|---:|---:|---:|")
        for i in idx:
            lines.append(f"| {f[i]:.2f} | {report.gamma_healthy[i]:.3e} | {report.gamma_required[i]:.3e} | "
                         f"{d[i].real:.4g}{d[i].imag:+.3g}j | {report.damage_bound_min_abs[i]:.4g} | "
                         f"{report.damage_bound_max_abs[i]:.4g} |")
        lines.append("")
    return lines


def write_reports(report: DetectionReport, out_dir: str | Path, plots: list[str],
                  baseline_path: str | Path | None = None) -> list[Path]:
    """Render all four files (report.json, report.md, fault_points.csv, report.html with the figures
    embedded), then write each atomically. Returns the paths."""
    from rotorcheck.report.html import render_detection_html

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
