"""Self-contained HTML reports: ``report.html`` beside a detection's report.json, ``location.html``
beside a location's location.json.

One file that opens offline in any browser: the verdict and the rule that made it, the numbers, every
figure embedded (PNG as base64 data URIs), the tables in full, the inputs with their sha256 and the
software versions. No script, no external style sheet, font or image.
"""

from __future__ import annotations

import base64
import html
import platform
from collections.abc import Iterable, Sequence
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rotorcheck import __version__
from rotorcheck.fileio import file_sha256
from rotorcheck.report.content import (
    BENIGN_HEADER,
    benign_rows,
    best_candidate,
    conclusion,
    fault_table,
    fmt_p,
    frequency_ranges,
    grid_step,
    headline_damage,
    method_paragraphs,
    where_paragraphs,
)
from rotorcheck.report.schema import DetectionReport, LocationReport

if TYPE_CHECKING:  # annotations only
    from rotorcheck.location import LocationResult

VERDICT_COLOUR = {"damage": "#b00020", "healthy": "#1b7a2f", "inconclusive": "#a66a00", "located": "#b00020",
                  "ranked": "#b00020", "not locatable": "#b00020", "nothing to locate": "#1b7a2f"}

_STYLE = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:2em auto;
max-width:1100px;color:#222;line-height:1.4;padding:0 1em}
h1{font-size:1.6em;margin-bottom:.2em} h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
.verdict{display:inline-block;color:#fff;padding:.25em .8em;border-radius:4px;font-weight:700;letter-spacing:.05em}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em} th,td{border:1px solid #ccc;padding:.25em .6em}
th{background:#f2f2f2;text-align:left} td.num{text-align:right;font-variant-numeric:tabular-nums}
figure{margin:1em 0} figure img{max-width:100%;border:1px solid #ddd} figcaption{font-size:.9em;color:#555}
.rule{background:#f7f7f7;border-left:4px solid #888;padding:.4em .8em} code{font-size:.9em}
td.hash{font-family:ui-monospace,monospace;font-size:.85em;word-break:break-all}
"""

#: what each figure shows, by file stem (the caption under it)
CAPTIONS = {
    "detection_decision": "The decision: per frequency the ratio that decides a fault point (above 1: the new data "
                          "cannot be explained), and with the joint test its statistic against the threshold.",
    "detection_bode": "Bode magnitude and phase: the nominal model, the healthy data, the range over the "
                      "uncertainty set, the new data and its fault points (red circles).",
    "detection_complex_plane": "The complex plane at one frequency: the uncertainty set (disk), the data and its "
                               "noise bound; its distance from the set in radii is in the title.",
    "damage_dynamics": "Damage dynamics D_u at the damage port with its bound; faint where the bound holds 0 (not "
                       "significant), hatched where the bound is unbounded.",
    "location": "The shaft: every candidate element by its status, and the certified stiffness-loss intervals.",
}


def _e(x: Any) -> str:
    return html.escape(str(x))


def _num(x: Any, fmt: str = ".4g") -> str:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return _e(x)
    return format(v, fmt) if np.isfinite(v) else _e(x if isinstance(x, str) else ("inf" if v > 0 else "nan"))


def sha256_or_none(path: str | Path) -> str | None:
    """sha256 of a file's bytes, or None when it cannot be read."""
    try:
        return file_sha256(path)
    except OSError:
        return None


def table(header: Sequence[str], rows: Iterable[Sequence[Any]], numeric: Sequence[bool | str] | None = None) -> str:
    """An HTML table; ``rows`` already formatted (escaped here). ``numeric`` per column: True (right-aligned
    numbers), a class name (``"hash"``: a long digest that may break anywhere) or False."""
    cls = [("num" if n is True else (n or "")) for n in (numeric if numeric is not None else [False] * len(header))]
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td class=\"{k}\">{_e(c)}</td>" if k else f"<td>{_e(c)}</td>"
                                    for c, k in zip(r, cls)) + "</tr>" for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def figures_html(plots: Sequence[str | Path]) -> str:
    """Every PNG of ``plots`` embedded as a figure with its caption; other formats listed by name."""
    parts = []
    for p in plots:
        path = Path(p)
        if path.suffix.lower() == ".png" and path.is_file():
            data = base64.b64encode(path.read_bytes()).decode("ascii")
            cap = CAPTIONS.get(path.stem, "")
            parts.append(f"<figure id=\"fig-{_e(path.stem)}\"><img alt=\"{_e(path.stem)}\" "
                         f"src=\"data:image/png;base64,{data}\"><figcaption><b>{_e(path.name)}</b>"
                         f"{': ' + _e(cap) if cap else ''}</figcaption></figure>")
    others = [Path(p).name for p in plots if Path(p).suffix.lower() != ".png"]
    if others:
        parts.append("<p>Also written: " + ", ".join(f"<code>{_e(n)}</code>" for n in others) + ".</p>")
    if not parts:
        parts.append("<p>No figures (run without <code>--no-plots</code> and with PNG in <code>--plot-format</code> "
                     "to embed them).</p>")
    return "\n".join(parts)


def provenance(inputs: Sequence[tuple[str, str | None, str | None]]) -> str:
    """The inputs (what, path, sha256) and the software that made the report."""
    rows = [(what, path or "", sha or "") for what, path, sha in inputs]
    import scipy  # lazy: scipy only for its version (this module needs no scipy otherwise)

    soft = [("rotorcheck", __version__), ("python", platform.python_version()), ("numpy", np.__version__),
            ("scipy", scipy.__version__), ("platform", platform.platform())]
    when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    return ("<h2>Inputs and software</h2>" + table(("input", "file", "sha256"), rows, (False, False, "hash"))
            + table(("software", "version"), soft) + f"<p>Written {_e(when)}.</p>")


def page(title: str, body: str) -> str:
    """A complete HTML5 document, no external resources."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{_e(title)}</title><style>{_STYLE}</style></head><body>\n{body}\n</body></html>\n")


def _verdict_badge(verdict: str) -> str:
    colour = VERDICT_COLOUR.get(verdict, "#555")
    return f"<span class=\"verdict\" id=\"verdict\" style=\"background:{colour}\">{_e(verdict.upper())}</span>"


def _key_numbers(report: DetectionReport) -> list[tuple[str, str]]:
    rows = [("fault points", f"{report.n_fault_points} of {report.n_points}"),
            ("band", f"{_num(report.band_hz[0], 'g')}-{_num(report.band_hz[1], 'g')} Hz"),
            ("speed", f"{_num(report.speed_rpm, 'g')} rpm"),
            ("noise bound (baseline)", f"{_num(report.noise_bound_m * 1e6)} um ({report.noise_method})"),
            ("baseline", f"uncertainty {report.uncertainty}, enclose {report.enclose}")]
    if report.p_value is not None:
        rows.append(("sweep p-value (per-point test)", f"{fmt_p(report.p_value)} at "
                                                        f"{report.confidence:.0%} family-wise confidence"))
    if report.joint_statistic is not None:
        p = fmt_p(report.joint_p_value)
        rows.append(("joint statistic T", f"{_num(report.joint_statistic)} against threshold "
                                          f"{_num(report.joint_threshold)} (p = {p}, "
                                          f"false alarm {report.false_alarm:g} per sweep)"))
        if report.joint_fit_chi2 is not None:
            rows.append(("H0's goodness of fit", f"chi2 = {report.joint_fit_chi2:.5g} on {report.joint_fit_dof} dof "
                                                 f"(p = {fmt_p(report.joint_fit_p_value)})"))
    best = best_candidate(report)
    if best is not None:
        rows.append(("where", best))
    if report.channel_pairs:
        rows.append(("channel pairs (output<-input)", ", ".join(report.channel_pairs)))
    return rows


def render_detection_html(report: DetectionReport, plots: Sequence[str | Path],
                          baseline_path: str | Path | None = None) -> str:
    """report.html of a detection: verdict and rule, the numbers, the figures embedded, every fault point,
    the benign parameters, the location (detect --locate), the inputs with hashes, the software."""
    verdict = str(report.verdict)
    parts = [f"<h1>rotorcheck detection: {_verdict_badge(verdict)}</h1>",
             f"<p>Sweep <code>{_e(report.sweep)}</code> (run <code>{_e(report.run_id)}</code>) on rig "
             f"<code>{_e(report.rig_id)}</code> at {_num(report.speed_rpm, 'g')} rpm; damage port "
             f"{_e(report.damage_port)}.</p>",
             f"<h2>Conclusion</h2><p id=\"conclusion\">{_e(report.conclusion or conclusion(report))}</p>",
             f"<p id=\"reason\"><b>{_e(verdict)}</b>: {_e(report.verdict_reason)}.</p>"]
    parts += [f"<p>{_e(line)}</p>" for line in headline_damage(report) if line]
    parts.append("<h2>The numbers</h2>" + table(("quantity", "value"), _key_numbers(report)))
    step = grid_step(report)
    where = where_paragraphs(report, lambda fs: frequency_ranges(fs, step))
    parts.append("<h2>Where</h2>" + "".join(f"<p>{_e(para)}</p>" for para in where))
    parts.append("<h2>Figures</h2>" + figures_html(plots))
    header, rows = fault_table(report)
    parts.append(f"<h2>Fault points: all {len(rows)}</h2>"
                 + (table(header, rows, [True] * len(header)) if rows else "<p>None.</p>"))
    if report.location is not None:
        parts.append("<h2>Location</h2>" + location_table(report.location))
    method = method_paragraphs(report, lambda fs: frequency_ranges(fs, step))
    parts.append("<h2>Method</h2>" + f"<p class=\"rule\" id=\"rule\"><b>Rule.</b> {_e(report.verdict_rule)}</p>"
                 + "".join(f"<p>{_e(para)}</p>" for para in method[1:]))
    if report.benign_parameters:
        parts.append("<h3>Benign change fitted (inside the rig's variability ranges)</h3>"
                     + table(BENIGN_HEADER, benign_rows(report), (False, True, False, False, False)))
    if report.notes:
        parts.append("<h2>Notes</h2><ul>" + "".join(f"<li>{_e(n)}</li>" for n in report.notes) + "</ul>")
    inputs: list[tuple[str, str, str | None]] = [("sweep", str(report.sweep), report.sweep_sha256),
              ("rig", str(report.rig_id), report.rig_sha256)]
    if baseline_path is not None:
        inputs.append(("baseline", str(baseline_path), sha256_or_none(baseline_path)))
    parts.append(provenance(inputs))
    return page(f"rotorcheck: {verdict} - {Path(str(report.sweep)).name}", "\n".join(parts))


def _percent_interval(lo: float | None, hi: float | None) -> str:
    """A fraction interval in %: ``[lo, hi]``; none where the lower end is undefined (None or not finite: an
    excluded candidate), an undefined upper end "50+" (a depth beyond the strip relation's 50 % of the
    diameter)."""
    def pct(x: float | None) -> str:
        return "" if x is None or not np.isfinite(x) else format(100.0 * float(x), ".3g")

    if not pct(lo):  # no interval: an excluded candidate (every loss excluded) has none
        return "none (excluded)"
    return f"[{pct(lo)}, {pct(hi) or '50+'}]"


def location_table(loc: LocationResult) -> str:
    """Every candidate element: status, rank, certified loss and depth intervals, what excluded it; above it
    the ranking's first with its relative likelihood (the one ranking detect and locate report)."""
    rows = []
    for c in loc.candidates:
        exc = [float(x) for x in c.excluding_frequencies_hz]
        rows.append([c.element, c.status, "" if c.rank is None else c.rank, _percent_interval(*c.loss_interval),
                     _percent_interval(*c.depth_interval),
                     ", ".join(f"{x:.1f}" for x in exc[:12]) + (f" (+{len(exc) - 12} more)" if len(exc) > 12 else "")])
    best = loc.best
    if best is None:
        head = "<p>No element located.</p>"
    else:
        ranked = ", ".join(f"element {c.element} {c.likelihood:.2f}" for c in loc.ranked[:4]
                           if c.likelihood is not None)
        head = f"<p>Best element: <b>{_e(best.element)}</b> ({_e(loc.kind)}; relative likelihoods: {_e(ranked)}).</p>"
    return head + table(("element", "status", "rank", "stiffness loss (%)", "crack depth (% of diameter)",
                         "excluded by (Hz)"), rows, (True, False, True, False, False, False))


def render_location_html(report: LocationReport, plots: Sequence[str | Path], rig_sha256: str | None = None) -> str:
    """location.html of a locate run: the summary, the figure, every candidate, inputs, software."""
    res = report.result
    badge = "nothing to locate" if res.kind == "nothing" else res.kind
    parts = [f"<h1>rotorcheck location: {_verdict_badge(badge)}</h1>",
             f"<p>Sweep <code>{_e(report.sweep)}</code> on rig <code>{_e(report.rig_id)}</code> at "
             f"{_num(report.speed_rpm, 'g')} rpm.</p>",
             f"<p id=\"reason\">{_e(res.summary())}</p>"]
    if res.rule:
        parts.append(f"<p class=\"rule\" id=\"rule\"><b>Rule.</b> {_e(res.rule)}</p>")
    parts.append("<h2>Figure</h2>" + figures_html(plots))
    parts.append("<h2>Candidates: all</h2>" + location_table(res))
    parts.append(provenance([("sweep", report.sweep, report.sweep_sha256),
                             ("rig", report.rig_id, rig_sha256),
                             ("baseline", report.baseline,
                              sha256_or_none(report.baseline) if report.baseline else None)]))
    return page(f"rotorcheck location - {Path(report.sweep).name}", "\n".join(parts))
