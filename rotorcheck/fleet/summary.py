"""The fleet's summary table (CSV and HDF5), its alert list and the rule behind each alert.

One row per sweep (machine, time order): the verdict, fault points, the anchored low-frequency D_u
(N/m) with its standard error and bound, the joint test, the fitted benign parameters (one column of
estimate and two of interval per parameter, in the parameter's unit: % for relative changes), the joint
test's best element and stiffness loss, the located element, and where the sweep's reports are.

Alert rule (:func:`alerts`): a machine is in **alarm** when its last ``confirm`` sweeps (default 2) all
have the verdict damage (``damage-confirmed``; one damage verdict at the joint test's 1 % false-alarm rate
per sweep is expected about once in 100 healthy sweeps, two in a row about once in 10,000), or, with a
limit, when the latest stiffness figure is beyond the limit by more than its confidence half-width
(``limit-exceeded``). It is on **watch** when its latest sweep is damage but not yet confirmed
(``damage-unconfirmed``), or when its latest sweep could not be checked (``sweep-error``).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from rotorcheck.fileio import atomic_path, atomic_write_text

#: the fixed columns, in order, and their units ("" for none)
COLUMNS: tuple[tuple[str, str], ...] = (
    ("machine", ""), ("time", "UTC"), ("verdict", ""), ("n_fault_points", ""), ("n_points", ""),
    ("du_low_re_n_per_m", "N/m"), ("du_low_se_n_per_m", "N/m"), ("du_low_points", ""), ("du_low_band_max_hz", "Hz"),
    ("du_low_bound_min_abs_n_per_m", "N/m"), ("du_low_bound_max_abs_n_per_m", "N/m"),
    ("joint_statistic", ""), ("joint_threshold", ""), ("joint_p_value", ""),
    ("joint_best_element", ""), ("stiffness_loss", "fraction"), ("stiffness_loss_lo", "fraction"),
    ("stiffness_loss_hi", "fraction"), ("location_best_element", ""), ("location_summary", ""),
    ("speed_rpm", "rpm"), ("sweep", ""), ("sweep_sha256", ""), ("result", ""), ("verdict_reason", ""),
)
ALERT_RULES = {
    "damage-confirmed": "alarm: the last {confirm} sweeps all have the verdict damage (joint test, false-alarm rate "
                        "{false_alarm:g} per sweep)",
    "limit-exceeded": "alarm: the latest low-frequency stiffness change exceeds the limit ({limit}) by more than "
                      "its {confidence:.0%} half-width",
    "damage-unconfirmed": "watch: the latest sweep has the verdict damage, not yet {confirm} in a row",
    "sweep-error": "watch: the latest sweep could not be checked (bad input); it neither confirms nor clears an "
                   "alarm",
}


def rule_texts(confirm: int, false_alarm: float, limit_text: str, confidence: float) -> dict[str, str]:
    """Every alert rule in words, with the numbers in use (``limit_text``: the limit as set, e.g.
    ``3000 N/m of the low-frequency Re D_u``, or ``none set: --limit``)."""
    return {k: v.format(confirm=confirm, false_alarm=false_alarm, limit=limit_text, confidence=confidence)
            for k, v in ALERT_RULES.items()}


def _unit_tag(unit: str) -> str:
    return {"%": "pct", "": ""}.get(unit, unit.replace("/", "_per_").replace(" ", "_"))


def benign_columns(rows: list[dict[str, Any]]) -> list[tuple[str, str, str]]:
    """``(column, parameter name, unit)`` of the benign parameters' estimate and interval columns."""
    seen: dict[str, str] = {}
    for r in rows:
        for b in r.get("benign_parameters") or []:
            seen.setdefault(b["name"], b["unit"])
    cols = []
    for name, unit in seen.items():
        stem = f"benign_{name}" + (f"_{_unit_tag(unit)}" if _unit_tag(unit) else "")
        cols += [(stem, name, unit), (f"{stem}_lo", name, unit), (f"{stem}_hi", name, unit)]
    return cols


def table(rows: list[dict[str, Any]]) -> tuple[list[str], list[str], list[list[Any]]]:
    """``(columns, units, values)``: the summary as a table, rows as given."""
    bcols = benign_columns(rows)
    names = [c for c, _ in COLUMNS] + [c for c, _, _ in bcols]
    units = [u for _, u in COLUMNS] + [u for _, _, u in bcols]
    out = []
    for r in rows:
        vals = [r.get(c) for c, _ in COLUMNS]
        by_name = {b["name"]: b for b in r.get("benign_parameters") or []}
        for col, name, _ in bcols:
            b = by_name.get(name)
            if b is None:
                vals.append(None)
            elif col.endswith("_lo"):
                vals.append(b["interval"][0])
            elif col.endswith("_hi"):
                vals.append(b["interval"][1])
            else:
                vals.append(b["estimate"])
        out.append(vals)
    return names, units, out


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    return str(v)


def render_csv(rows: list[dict[str, Any]]) -> str:
    """summary.csv: a header of column names, then one line per sweep (floats in full precision)."""
    names, _, values = table(rows)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(names)
    for vals in values:
        w.writerow([_cell(v) for v in vals])
    return buf.getvalue()


def write_hdf5(rows: list[dict[str, Any]], path: Path) -> None:
    """summary.h5: group ``/summary`` with one dataset per column (numbers float64 with NaN for none,
    text UTF-8), each with a ``units`` attribute; written atomically."""
    import h5py  # lazy: h5py only to write summary.h5
    import numpy as np  # lazy: numpy only for summary.h5 (this module loads without it)

    names, units, values = table(rows)
    with atomic_path(path) as tmp, h5py.File(tmp, "w", track_order=True) as h5:
        h5.attrs["schema"] = "rotorcheck.fleet.summary"
        h5.attrs["schema_version"] = 1
        g = h5.create_group("summary", track_order=True)
        for j, (name, unit) in enumerate(zip(names, units)):
            col = [v[j] for v in values]
            numeric = all(v is None or (isinstance(v, (int, float)) and not isinstance(v, bool)) for v in col)
            if numeric and any(v is not None for v in col):
                data = np.array([np.nan if v is None else float(v) for v in col], dtype=float)
                ds = g.create_dataset(name, data=data, track_times=False)
            else:
                ds = g.create_dataset(name, data=[_cell(v) for v in col], dtype=h5py.string_dtype("utf-8"),
                                      track_times=False)
            ds.attrs["units"] = unit


def read_hdf5(path: Path) -> dict[str, list[Any]]:
    """The columns of a summary.h5 (numbers as floats, text as str)."""
    import h5py  # lazy: h5py only to read summary.h5

    out: dict[str, list[Any]] = {}
    with h5py.File(path, "r") as h5:
        for name, ds in h5["summary"].items():
            data = ds[()]
            out[name] = [x.decode() if isinstance(x, bytes) else float(x) for x in data]
    return out


def alerts(rows_by_machine: dict[str, list[dict[str, Any]]], trends: dict[str, Any], confirm: int = 2,
           false_alarm: float = 0.01, limits: dict[str, float | None] | None = None) -> list[dict[str, Any]]:
    """The alert list (module docstring): one entry per machine in alarm or on watch, alarms first, with
    the rule that made it, since when, and the machine's trend."""
    out = []
    for machine, rows in sorted(rows_by_machine.items()):
        if not rows:
            continue
        # a sweep that could not be checked (an error row: unreadable, truncated) neither confirms nor clears
        # an alarm: the streak counts the checked sweeps only; the unreadable ones get a watch note
        judged = [r for r in rows if r["verdict"] != "error"]
        unchecked = rows[max((i + 1 for i, r in enumerate(rows) if r["verdict"] != "error"), default=0):]
        streak = 0
        while streak < len(judged) and judged[-1 - streak]["verdict"] == "damage":
            streak += 1
        tr = trends.get(machine)
        tr_doc = tr.to_dict() if tr is not None else {}
        limit = (limits or {}).get(machine)
        last = rows[-1]
        entry = {"machine": machine, "latest_time": last["time"], "latest_verdict": last["verdict"],
                 "damage_streak": streak, "du_low_re_n_per_m": last.get("du_low_re_n_per_m"),
                 "location": last.get("location_summary") or "", "trend": tr_doc.get("status", ""),
                 "slope_n_per_m_per_day": tr_doc.get("slope_n_per_m_per_day"),
                 "slope_interval_n_per_m_per_day": tr_doc.get("slope_interval_n_per_m_per_day"),
                 "crossing_time": tr_doc.get("crossing_time"), "crossing_interval": tr_doc.get("crossing_interval")}
        rules = []
        if streak >= confirm:
            rules.append(("alarm", "damage-confirmed", judged[len(judged) - streak + confirm - 1]["time"]))
        fit = getattr(tr, "fit", None)
        if limit is not None and fit is not None:
            from rotorcheck.fleet.trend import days  # lazy: numpy (fleet.trend) only with a limit

            if fit.beyond(limit, days(last["time"])):
                rules.append(("alarm", "limit-exceeded", last["time"]))
        if 0 < streak < confirm:
            rules.append(("watch", "damage-unconfirmed", judged[-1]["time"]))
        if unchecked:
            rules.append(("watch", "sweep-error", unchecked[0]["time"]))
        for level, rule, since in rules:
            text = ALERT_RULES[rule].format(confirm=confirm, false_alarm=false_alarm,
                                            limit="none set" if limit is None else f"{limit:.4g} N/m",
                                            confidence=getattr(fit, "confidence", 0.95))
            out.append({"level": level, "rule": rule, "rule_text": text, "since": since,
                        "first_damage_time": judged[len(judged) - streak]["time"] if streak else None, **entry})
    return sorted(out, key=lambda e: (e["level"] != "alarm", e["machine"], e["rule"]))


def render_alerts_text(entries: list[dict[str, Any]]) -> str:
    """The alert list as plain lines (the terminal, ``make fleet-demo``)."""
    if not entries:
        return "no alerts\n"
    lines = []
    for e in entries:
        lines.append(f"{e['level'].upper():5s} {e['machine']}: {e['rule']} since {e['since']} (latest "
                     f"{e['latest_verdict']} at {e['latest_time']}; D_u low {_fmt(e['du_low_re_n_per_m'])} N/m)")
        if e["trend"]:
            lines.append(f"      trend: {e['trend']}")
        if e["location"]:
            lines.append(f"      location: {e['location']}")
    return "\n".join(lines) + "\n"


def _fmt(x: Any) -> str:
    return "-" if x is None else f"{x:.4g}"


def write_alerts(entries: list[dict[str, Any]], out: Path, rules: dict[str, str] | None = None) -> list[Path]:
    """alerts.json (the entries and the rules in words, :func:`rule_texts`) and alerts.txt
    (:func:`render_alerts_text`), atomically."""
    from rotorcheck.report.reports import render_json  # lazy: numpy (report.reports) only when writing JSON

    atomic_write_text(out / "alerts.json", render_json({"alerts": entries, "rules": rules or ALERT_RULES}))
    atomic_write_text(out / "alerts.txt", render_alerts_text(entries))
    return [out / "alerts.json", out / "alerts.txt"]


def write_summary(rows: list[dict[str, Any]], out: Path) -> list[Path]:
    """summary.csv and summary.h5 in ``out`` (atomically)."""
    atomic_write_text(out / "summary.csv", render_csv(rows))
    write_hdf5(rows, out / "summary.h5")
    return [out / "summary.csv", out / "summary.h5"]


def write_trends(trends: dict[str, Any], out: Path) -> Path:
    """trends.json: every machine's fit, slope interval, crossing and the assumptions."""
    from rotorcheck.report.reports import render_json  # lazy: numpy (report.reports) only when writing JSON

    atomic_write_text(out / "trends.json", render_json({m: t.to_dict() for m, t in sorted(trends.items())}))
    return out / "trends.json"
