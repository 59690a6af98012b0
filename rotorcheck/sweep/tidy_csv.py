"""Tidy CSV export/import: one row per run, frequency and output/input channel pair.

Columns (in this order)::

    run_id, speed_rpm, frequency_hz, output, input, frf_re, frf_im, output_var, n_periods
    [, input_re, input_im, output_re, output_im] [, frf_var, noise_source]

``frf`` in m/N, ``output_var`` in m^2 (variance of the mean output phasor), ``output``/``input``
channel names. The four optional phasor columns (input force phasor in N, output displacement
phasor in m; written by default) let :func:`import_tidy_csv` rebuild the sweep. Floats are written
with ``repr`` (shortest round-trip form), so export/import is exact. Rows are ordered by run, then
frequency, then output, then input.

Version 2 (a sweep :func:`~rotorcheck.sweep.format.sweep_schema_version` puts in version 2) adds
the columns ``frf_var`` ((m/N)^2, empty where not stored) and ``noise_source``. A row holds one
output/input pair, so only a one-pattern run keeps its phasors, ``output_var`` and ``n_periods``;
for a run of several patterns or an FRF-only run those cells are empty and the CSV carries its frf
and frf_var, with ``noise_source`` the run's own or, for a run of several patterns whose frf_var
comes from its period scatter, ``"measured"``. :func:`import_tidy_csv` turns a run without phasor
cells into an FRF-only run; its ``noise_source`` is the caller's (when given) or the file's.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Sequence

import numpy as np

from rotorcheck.fileio import atomic_path
from rotorcheck.sweep.format import (
    Channel,
    FrfTable,
    Run,
    Sweep,
    SweepFormatError,
    imported_frf_only,
    sweep_schema_version,
)
from rotorcheck.sweep.validation import validate_sweep

__all__ = ["COLUMNS", "PHASOR_COLUMNS", "V2_COLUMNS", "export_tidy_csv", "import_tidy_csv", "read_tidy_csv"]

COLUMNS = (
    "run_id",
    "speed_rpm",
    "frequency_hz",
    "output",
    "input",
    "frf_re",
    "frf_im",
    "output_var",
    "n_periods",
)
PHASOR_COLUMNS = ("input_re", "input_im", "output_re", "output_im")
V2_COLUMNS = ("frf_var", "noise_source")


def export_tidy_csv(
    sweep: Sweep,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    include_phasors: bool = True,
) -> None:
    """Write the tidy CSV atomically; refuses to overwrite unless ``force``."""
    target = os.fspath(path)
    validate_sweep(sweep, target)
    v2 = sweep_schema_version(sweep) == 2
    header = list(COLUMNS) + (list(PHASOR_COLUMNS) if include_phasors else []) + (list(V2_COLUMNS) if v2 else [])
    ins, outs = sweep.inputs, sweep.outputs
    with atomic_path(target, overwrite=force) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(header)
            for run in sweep.runs.values():
                sp = repr(float(run.speed_rpm))
                single = run.n_exc == 1
                fv = None if run.frf_var is None else np.asarray(run.frf_var, dtype=np.float64)
                noise = run.noise_source if run.noise_source is not None else ("" if single else "measured")
                for k, fk in enumerate(np.asarray(run.frequency, dtype=np.float64)):
                    for o, co in enumerate(outs):
                        for i, ci in enumerate(ins):
                            h = complex(run.frf[k, o, i])
                            row = [
                                run.run_id,
                                sp,
                                repr(float(fk)),
                                co.name,
                                ci.name,
                                repr(h.real),
                                repr(h.imag),
                                repr(float(run.output_var[k, o])) if single else "",
                                str(int(run.n_periods[k])) if single else "",
                            ]
                            if include_phasors and single:
                                u = complex(run.input_phasor[k, i])
                                y = complex(run.output_phasor[k, o])
                                row += [repr(u.real), repr(u.imag), repr(y.real), repr(y.imag)]
                            elif include_phasors:
                                row += ["", "", "", ""]
                            if v2:
                                row += ["" if fv is None else repr(float(fv[k, o, i])), noise]
                            w.writerow(row)


def _rows(file: str) -> tuple[list[str], list[tuple[int, dict[str, str]]]]:
    if not os.path.exists(file):
        raise SweepFormatError(file, "/", "no such file")
    lineno = 1
    # utf-8-sig: Excel's "CSV UTF-8" starts with a byte-order mark, which is no part of the first column's name
    with open(file, newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise SweepFormatError(file, "line 1", f"missing columns {missing}")
            rows = []
            for raw in reader:
                lineno = reader.line_num
                if not raw:
                    continue
                if len(raw) != len(header):
                    raise SweepFormatError(file, f"line {lineno}", f"{len(raw)} fields, header has {len(header)}")
                rows.append((lineno, dict(zip(header, raw, strict=True))))
        except StopIteration:
            raise SweepFormatError(file, "line 1", "empty file (no header)") from None
        except UnicodeDecodeError as exc:
            raise SweepFormatError(file, f"line {lineno + 1}", f"not UTF-8 text (byte {exc.start} of a chunk): "
                                   "save the CSV as UTF-8") from None
        except csv.Error as exc:
            raise SweepFormatError(file, f"line {reader.line_num}", f"not CSV: {exc}") from None
    if not rows:
        raise SweepFormatError(file, "line 2", "no data rows")
    return header, rows


def _num(file: str, lineno: int, row: dict[str, str], col: str) -> float:
    try:
        value = float(row[col])
    except ValueError:
        raise SweepFormatError(file, f"line {lineno}/{col}", f"not a number: {row[col]!r}") from None
    if not math.isfinite(value):
        raise SweepFormatError(file, f"line {lineno}/{col}", f"not a finite number: {row[col]!r}")
    return value


def _all_or_none(file: str, rid: str, col: str, filled: list[bool]) -> bool:
    """True if every row of the run fills ``col``, False if none does; mixed is refused."""
    if all(filled):
        return True
    if any(filled):
        raise SweepFormatError(file, f"column {col}", f"run {rid!r}: filled in some rows only")
    return False


def _parse_tables(
    file: str, header: list[str], rows: list[tuple[int, dict[str, str]]], phasors: bool
) -> tuple[dict[str, FrfTable], dict[str, tuple[np.ndarray, np.ndarray] | None]]:
    runs: dict[str, list[tuple[int, dict[str, str]]]] = {}
    for lineno, row in rows:
        if not row["run_id"]:
            raise SweepFormatError(file, f"line {lineno}/run_id", "empty run_id")
        runs.setdefault(row["run_id"], []).append((lineno, row))
    tables: dict[str, FrfTable] = {}
    phas: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}
    for rid, rr in runs.items():
        speeds = {_num(file, ln, r, "speed_rpm") for ln, r in rr}
        if len(speeds) != 1:
            raise SweepFormatError(file, f"line {rr[0][0]}/speed_rpm", f"run {rid!r}: several speeds")
        outs: list[str] = []
        ins: list[str] = []
        freqs: list[float] = []
        for ln, r in rr:
            fk = _num(file, ln, r, "frequency_hz")
            if not freqs or freqs[-1] != fk:
                if freqs and fk in freqs:
                    raise SweepFormatError(
                        file, f"line {ln}/frequency_hz", f"run {rid!r}: rows of {fk!r} Hz not contiguous"
                    )
                freqs.append(fk)
            if r["output"] not in outs:
                outs.append(r["output"])
            if r["input"] not in ins:
                ins.append(r["input"])
        has_var = _all_or_none(file, rid, "output_var", [r["output_var"] != "" for _, r in rr])
        has_n = _all_or_none(file, rid, "n_periods", [r["n_periods"] != "" for _, r in rr])
        run_phasors = phasors and _all_or_none(
            file, rid, "input_re", [all(r[c] != "" for c in PHASOR_COLUMNS) for _, r in rr]
        )
        has_fv = "frf_var" in header and _all_or_none(file, rid, "frf_var", [r["frf_var"] != "" for _, r in rr])
        noises = {r["noise_source"] for _, r in rr} if "noise_source" in header else {""}
        if len(noises) != 1:
            raise SweepFormatError(file, "column noise_source", f"run {rid!r}: differs between rows")
        nf, no, ni = len(freqs), len(outs), len(ins)
        frf = np.full((nf, no, ni), np.nan + 1j * np.nan)
        fvar = np.full((nf, no, ni), np.nan)
        var = np.full((nf, no), np.nan)
        nper = np.full(nf, -1, dtype=np.int64)
        u = np.full((nf, ni), np.nan + 1j * np.nan)
        y = np.full((nf, no), np.nan + 1j * np.nan)
        seen: set[tuple[int, int, int]] = set()
        fidx = {v: k for k, v in enumerate(freqs)}
        for ln, r in rr:
            k = fidx[_num(file, ln, r, "frequency_hz")]
            o, i = outs.index(r["output"]), ins.index(r["input"])
            if (k, o, i) in seen:
                raise SweepFormatError(file, f"line {ln}", f"run {rid!r}: duplicate row")
            seen.add((k, o, i))
            frf[k, o, i] = complex(_num(file, ln, r, "frf_re"), _num(file, ln, r, "frf_im"))
            if has_fv:
                fvar[k, o, i] = _num(file, ln, r, "frf_var")
            if has_var:
                v = _num(file, ln, r, "output_var")
                if not np.isnan(var[k, o]) and var[k, o] != v:
                    raise SweepFormatError(file, f"line {ln}/output_var", "differs between inputs")
                var[k, o] = v
            if has_n:
                try:
                    n = int(r["n_periods"])
                except ValueError:
                    raise SweepFormatError(
                        file, f"line {ln}/n_periods", f"not an integer: {r['n_periods']!r}"
                    ) from None
                if nper[k] not in (-1, n):
                    raise SweepFormatError(file, f"line {ln}/n_periods", "differs within a frequency")
                nper[k] = n
            if run_phasors:
                uu = complex(_num(file, ln, r, "input_re"), _num(file, ln, r, "input_im"))
                yy = complex(_num(file, ln, r, "output_re"), _num(file, ln, r, "output_im"))
                for arr, idx, val, col in ((u, (k, i), uu, "input_re"), (y, (k, o), yy, "output_re")):
                    if not np.isnan(arr[idx]) and arr[idx] != val:
                        raise SweepFormatError(
                            file, f"line {ln}/{col}", "phasor differs between rows of one point"
                        )
                    arr[idx] = val
        if len(seen) != nf * no * ni:
            raise SweepFormatError(
                file, "/", f"run {rid!r}: {nf * no * ni - len(seen)} frequency/channel rows missing"
            )
        noise = noises.pop()
        tables[rid] = FrfTable(
            run_id=rid,
            speed_rpm=speeds.pop(),
            frequency=np.asarray(freqs, dtype=np.float64),
            outputs=[Channel(n, "output", 1, "x", "displacement", "m") for n in outs],
            inputs=[Channel(n, "input", 1, "x", "force", "N") for n in ins],
            frf=frf,
            output_var=var if has_var else None,
            n_periods=nper.astype(np.int32) if has_n else None,
            frf_var=fvar if has_fv else None,
            noise_source=noise or None,
        )
        phas[rid] = (u, y) if run_phasors else None
    return tables, phas


def read_tidy_csv(path: str | os.PathLike[str]) -> dict[str, FrfTable]:
    """FRF tables per run. The CSV has channel names only: ``node``/``direction`` of the
    returned channels are placeholders (1, ``"x"``); use :func:`import_tidy_csv` with the
    channel table for a full sweep."""
    file = os.fspath(path)
    header, rows = _rows(file)
    return _parse_tables(file, header, rows, phasors=False)[0]


def import_tidy_csv(
    path: str | os.PathLike[str],
    channels: Sequence[Channel],
    *,
    rig_id: str,
    source: str,
    created_utc: str,
    generator: str | None = None,
    noise_source: str | None = None,
) -> Sweep:
    """Rebuild a :class:`Sweep` from a tidy CSV.

    The CSV carries no channel metadata or header fields, so the caller supplies them
    (``channels`` matched by name). A run with the phasor cells comes back as a one-pattern run
    (``frf_var`` kept where the file has it); a run without them becomes an FRF-only run
    (version 2: frf, frf_var where the file has it), which needs a ``noise_source``
    ("measured" or "assumed: <rule>"): the caller's when given (it overrides the file's), else the
    file's ``noise_source`` column, else :class:`SweepFormatError` saying so. Validated like a
    sweep file.
    """
    file = os.fspath(path)
    header, rows = _rows(file)
    phasor_cols = all(c in header for c in PHASOR_COLUMNS)
    tables, phas = _parse_tables(file, header, rows, phasors=phasor_cols)
    chans = list(channels)
    ins = [c for c in chans if c.role == "input"]
    outs = [c for c in chans if c.role == "output"]
    runs: dict[str, Run] = {}
    for rid, tab in tables.items():
        names_o = [c.name for c in tab.outputs]
        names_i = [c.name for c in tab.inputs]
        if sorted(names_o) != sorted(c.name for c in outs) or sorted(names_i) != sorted(c.name for c in ins):
            raise SweepFormatError(
                file,
                "/",
                f"run {rid!r}: CSV channels out={names_o} in={names_i} do not match the "
                f"channel table out={[c.name for c in outs]} in={[c.name for c in ins]}",
            )
        oi = [names_o.index(c.name) for c in outs]
        ii = [names_i.index(c.name) for c in ins]
        frf = tab.frf[:, oi][:, :, ii]
        frf_var = None if tab.frf_var is None else tab.frf_var[:, oi][:, :, ii]
        ph = phas[rid]
        if ph is None:
            what = "content (no phasor columns)" if not phasor_cols else "content (empty phasor cells)"
            runs[rid] = imported_frf_only(file, tab, frf, frf_var, noise_source, what, "read_tidy_csv")
            continue
        if tab.output_var is None or tab.n_periods is None:
            raise SweepFormatError(file, "/", f"run {rid!r}: phasor cells without output_var/n_periods")
        u, y = ph
        run = Run.from_v1(
            rid,
            tab.speed_rpm,
            tab.frequency,
            u[:, ii],
            y[:, oi],
            tab.output_var[:, oi],
            tab.n_periods,
            frf,
        )
        run.frf_var = frf_var
        run.noise_source = tab.noise_source
        runs[rid] = run
    sweep = Sweep(
        rig_id=rig_id,
        source=source,
        generator=generator if generator is not None else f"tidy csv import of {os.path.basename(file)}",
        created_utc=created_utc,
        channels=chans,
        runs=runs,
    )
    validate_sweep(sweep, file)
    return sweep
