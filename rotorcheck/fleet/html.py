"""Per-machine trend plots (matplotlib Figure API, no pyplot state) and the fleet's ``index.html``:
self-contained (plots embedded as base64 PNG), with the alert list, the trend table, the summary table and
links to each sweep's reports."""

from __future__ import annotations

import base64
import datetime as dt
import html
import io
from pathlib import Path
from typing import Any

import matplotlib.dates as mdates
import numpy as np
from matplotlib.figure import Figure

from rotorcheck.fileio import atomic_write_bytes, atomic_write_text
from rotorcheck.fleet.trend import ASSUMPTIONS, Trend, datetime_of_days, days

VERDICT_COLOURS = {"healthy": "tab:green", "damage": "tab:red", "inconclusive": "tab:orange", "error": "tab:gray"}


def _dates(x_days: Any) -> list[dt.datetime]:
    return [datetime_of_days(float(x)).replace(tzinfo=None) for x in x_days]


def trend_figure(machine: str, rows: list[dict[str, Any]], trend: Trend) -> Figure:
    """Three panels over time: the low-frequency stiffness change Re D_u (N/m, 95 % error bars, coloured by
    verdict) with the fitted line, its band, the limit and the crossing; the fitted benign parameters with
    their intervals; the joint test's statistic over its threshold."""
    fig = Figure(figsize=(9.0, 8.0), layout="constrained")
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True, height_ratios=[3, 2, 1.4])
    t = np.array([days(r["time"]) for r in rows])
    y = np.array([np.nan if r.get("du_low_re_n_per_m") is None else r["du_low_re_n_per_m"] for r in rows], float)
    se = np.array([np.nan if r.get("du_low_se_n_per_m") is None else r["du_low_se_n_per_m"] for r in rows], float)
    for verdict, colour in VERDICT_COLOURS.items():
        sel = np.array([r["verdict"] == verdict for r in rows])
        if np.any(sel):
            ax1.errorbar(_dates(t[sel]), y[sel], yerr=1.96 * se[sel], fmt="o", color=colour, capsize=3,
                         label=f"{verdict} sweep")
    f = trend.fit
    t0, t1 = float(np.min(t)), float(np.max(t))
    pad = max(0.03 * (t1 - t0), 1.0)
    x_hi = t1 + pad  # the axis fits the data; a crossing beyond half the data's span is written, not drawn
    shown = (trend.crossing_days is not None and trend.crossing_days <= t1 + 0.5 * (t1 - t0 + 1.0))
    if f is not None:
        t_start = f.kink_days if f.kink_days is not None else float(t[trend.used[0]])
        t_end = t1
        if shown:
            c_hi = trend.crossing_interval_days[1]
            t_end = float(max(t1, min(c_hi if c_hi is not None else t1, t1 + 0.5 * (t1 - t0 + 1.0))))
            x_hi = t_end + pad
        tt = np.linspace(t_start, t_end, 100)
        line = np.array([f.value(x) for x in tt])
        band = np.array([f.quantile * f.value_se(x) for x in tt])
        lo, hi = f.slope_interval
        ax1.plot(_dates(tt), line, color="k", lw=1.2,
                 label=f"trend: {f.b:.3g} N/m/day [{lo:.3g}, {hi:.3g}] ({f.confidence * 100:g} %)")
        ax1.fill_between(_dates(tt), line - band, line + band, color="k", alpha=0.12, label="line's confidence band")
        if trend.change_points:
            ax1.axvline(_dates([trend.change_points[-1].time])[0], color="tab:blue", ls=":", lw=1.0,
                        label="last change point")
    if trend.limit_n_per_m is not None:
        ax1.axhline(trend.limit_n_per_m, color="tab:purple", ls="--", lw=1.0,
                    label=f"limit {trend.limit_n_per_m:.4g} N/m")
        if trend.crossing_days is not None and shown:
            ax1.axvline(_dates([trend.crossing_days])[0], color="tab:purple", lw=0.8)
            c_lo, c_hi = trend.crossing_interval_days
            if c_lo is not None and c_hi is not None:
                ax1.axvspan(*_dates([c_lo, min(c_hi, x_hi)]), color="tab:purple", alpha=0.10,
                            label="crossing interval")
        elif trend.crossing_days is not None:
            ax1.text(0.99, 0.03, trend.forecast_words + " (beyond this plot)", transform=ax1.transAxes,
                     ha="right", va="bottom", fontsize=7, color="tab:purple")
    ax1.set_xlim(*_dates([t0 - pad, x_hi]))
    ax1.set_ylabel("Re D_u, low band (N/m)\n(+: stiffness loss)")
    ax1.set_title(f"{machine}: low-frequency stiffness change at the damage port")
    ax1.legend(fontsize=7, loc="upper left")
    ax1.grid(alpha=0.3)
    names: dict[str, str] = {}
    for r in rows:
        for b in r.get("benign_parameters") or []:
            names.setdefault(b["name"], b["unit"])
    for name, unit in names.items():
        est, lo_, hi_ = [], [], []
        for r in rows:
            b = next((b for b in r.get("benign_parameters") or [] if b["name"] == name), None)
            est.append(np.nan if b is None or b["estimate"] is None else b["estimate"])
            lo_.append(np.nan if b is None or b["interval"][0] is None else b["interval"][0])
            hi_.append(np.nan if b is None or b["interval"][1] is None else b["interval"][1])
        e, lo_a, hi_a = np.array(est), np.array(lo_), np.array(hi_)
        yerr = np.vstack([np.where(np.isfinite(lo_a), e - lo_a, 0.0), np.where(np.isfinite(hi_a), hi_a - e, 0.0)])
        ax2.errorbar(_dates(t), e, yerr=yerr, fmt=".-", capsize=2, lw=0.8, label=f"{name} ({unit})")
    ax2.set_ylabel("benign parameter\nestimate (% or unit)")
    ax2.set_title(f"{machine}: fitted benign change (95 % intervals)", fontsize=9)
    if names:
        ax2.legend(fontsize=7, loc="upper left", ncols=2)
    ax2.grid(alpha=0.3)
    ratio = np.array([np.nan if not r.get("joint_statistic") or not r.get("joint_threshold")
                      else r["joint_statistic"] / r["joint_threshold"] for r in rows])
    colours = [VERDICT_COLOURS.get(r["verdict"], "k") for r in rows]
    ax3.scatter(_dates(t), ratio, c=colours, s=18)
    ax3.axhline(1.0, color="k", lw=0.8, ls=":")
    ax3.set_yscale("log")
    ax3.set_ylabel("joint statistic /\nthreshold")
    ax3.set_xlabel("sweep time (UTC)")
    ax3.set_title(f"{machine}: joint test (damage above 1)", fontsize=9)
    ax3.grid(alpha=0.3)
    locator = mdates.AutoDateLocator(minticks=4, maxticks=9)
    ax3.xaxis.set_major_locator(locator)
    ax3.xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))
    return fig


def png_bytes(fig: Figure, dpi: int = 100) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def _e(x: Any) -> str:
    return html.escape("" if x is None else str(x))


def _num(x: Any, fmt: str = ".4g") -> str:
    return "" if x is None else format(x, fmt)


def render_index(out: Path, rows_by_machine: dict[str, list[dict[str, Any]]], trends: dict[str, Trend],
                 alert_entries: list[dict[str, Any]], pngs: dict[str, bytes], meta: dict[str, Any]) -> str:
    """index.html text: alert list, trend table, per machine its plot and its sweeps with links."""
    style = ("body{font-family:sans-serif;margin:1.5em;max-width:1100px}table{border-collapse:collapse;"
             "font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}"
             "td.l{text-align:left}.alarm{color:#b00;font-weight:bold}.watch{color:#b60}"
             ".damage{background:#fdd}.error{background:#eee}")
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>rotorcheck fleet</title>",
             f"<style>{style}</style></head><body>",
             f"<h1>rotorcheck fleet: {_e(meta.get('source'))}</h1>",
             f"<p>{meta.get('n_machines')} machines, {meta.get('n_sweeps')} sweeps. Files: "
             "<a href='summary.csv'>summary.csv</a>, <a href='summary.h5'>summary.h5</a>, "
             "<a href='alerts.json'>alerts.json</a>, <a href='trends.json'>trends.json</a>.</p>",
             "<h2>Alerts</h2>"]
    if not alert_entries:
        parts.append("<p>No alerts.</p>")
    else:
        parts.append("<table><tr><th>level</th><th>machine</th><th>rule</th><th>since</th><th>latest</th>"
                     "<th>Re D_u low (N/m)</th><th>trend</th><th>location</th></tr>")
        for a in alert_entries:
            parts.append(f"<tr><td class='l {a['level']}'>{_e(a['level'])}</td>"
                         f"<td class='l'><a href='#m-{_e(a['machine'])}'>{_e(a['machine'])}</a></td>"
                         f"<td class='l' title='{_e(a['rule_text'])}'>{_e(a['rule'])}</td>"
                         f"<td>{_e(a['since'])}</td><td class='l'>{_e(a['latest_verdict'])} {_e(a['latest_time'])}</td>"
                         f"<td>{_num(a['du_low_re_n_per_m'])}</td><td class='l'>{_e(a['trend'])}</td>"
                         f"<td class='l'>{_e(a['location'])}</td></tr>")
        parts.append("</table>")
    parts.append("<p>Rules: " + "; ".join(f"<b>{_e(k)}</b>: {_e(v)}" for k, v in meta.get("rules", {}).items())
                 + ".</p>")
    parts += ["<h2>Trends</h2>", f"<p>Limit: {_e(meta.get('limit_text'))}. Assumptions: "
              + "; ".join(_e(a) for a in ASSUMPTIONS) + ".</p>",
              "<table><tr><th>machine</th><th>latest verdict</th><th>sweeps since the last change point</th>"
              "<th>slope (N/m/day)</th><th>interval</th><th>trend</th><th>prognosis</th></tr>"]
    for m in sorted(trends):
        d = trends[m].to_dict()
        lo, hi = d["slope_interval_n_per_m_per_day"]
        parts.append(f"<tr><td class='l'><a href='#m-{_e(m)}'>{_e(m)}</a></td><td class='l'>{_e(d['latest_verdict'])}"
                     f"</td><td>{d['n_since_change']}</td><td>{_num(d['slope_n_per_m_per_day'], '.3g')}</td>"
                     f"<td>[{_num(lo, '.3g')}, {_num(hi, '.3g')}]</td><td class='l'>{_e(d['trend'])}</td>"
                     f"<td class='l'>{_e(d['prognosis'])}</td></tr>")
    parts.append("</table><h2>Machines</h2>")
    for m in sorted(rows_by_machine):
        rows = rows_by_machine[m]
        parts.append(f"<h3 id='m-{_e(m)}'>{_e(m)}</h3>")
        if m in pngs:
            b64 = base64.b64encode(pngs[m]).decode("ascii")
            parts.append(f"<img alt='trend of {_e(m)}' src='data:image/png;base64,{b64}' style='max-width:100%'>")
        parts.append("<table><tr><th>time</th><th>verdict</th><th>fault points</th><th>Re D_u low (N/m)</th>"
                     "<th>se</th><th>joint T / threshold</th><th>location</th><th>reports</th></tr>")
        for r in rows:
            ratio = (r["joint_statistic"] / r["joint_threshold"] if r.get("joint_statistic") is not None
                     and r.get("joint_threshold") else None)
            res = r.get("result") or ""
            links = []
            for name in ("report.html", "report.md", "report.json", "fault_points.csv", "location/location.json"):
                if res and (out / res / name).exists():
                    links.append(f"<a href='{_e(res)}/{_e(name)}'>{_e(name)}</a>")
            parts.append(f"<tr class='{_e(r['verdict'])}'><td>{_e(r['time'])}</td><td class='l'>{_e(r['verdict'])}</td>"
                         f"<td>{_e(r.get('n_fault_points'))}/{_e(r.get('n_points'))}</td>"
                         f"<td>{_num(r.get('du_low_re_n_per_m'))}</td>"
                         f"<td>{_num(r.get('du_low_se_n_per_m'), '.3g')}</td>"
                         f"<td>{_num(ratio, '.3g')}</td><td class='l'>{_e(r.get('location_summary'))}</td>"
                         f"<td class='l'>{' '.join(links) or _e(r.get('error'))}</td></tr>")
        parts.append("</table>")
    parts.append("</body></html>\n")
    return "".join(parts)


def write_index(out: Path, rows_by_machine: dict[str, list[dict[str, Any]]], trends: dict[str, Trend],
                alert_entries: list[dict[str, Any]], meta: dict[str, Any]) -> list[Path]:
    """The trend PNGs (``trends/<machine>.png``) and ``index.html`` (embedding them), atomically."""
    pngs: dict[str, bytes] = {}
    written: list[Path] = []
    for m, rows in sorted(rows_by_machine.items()):
        if not rows:
            continue
        pngs[m] = png_bytes(trend_figure(m, rows, trends[m]))  # rendered once: written and embedded
        path = out / "trends" / f"{m}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, pngs[m])
        written.append(path)
    atomic_write_text(out / "index.html", render_index(out, rows_by_machine, trends, alert_entries, pngs, meta))
    return [*written, out / "index.html"]
