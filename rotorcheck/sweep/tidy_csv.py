"""Tidy CSV export/import: one row per run, frequency and output/input channel pair.

Columns (in this order)::

    run_id, speed_rpm, frequency_hz, output, input, frf_re, frf_im, output_var, n_periods
    [, input_re, input_im, output_re, output_im]

``frf`` in m/N, ``output_var`` in m^2 (variance of the mean output phasor), ``output``/``input``
channel names. The four optional phasor columns (input force phasor in N, output displacement
phasor in m; written by default) let :func:`import_tidy_csv` rebuild the sweep. Floats are written
with ``repr`` (shortest round-trip form), so export/import is exact. Rows are ordered by run, then
frequency, then output, then input.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence

import numpy as np

from rotorcheck.fileio import atomic_path
from rotorcheck.sweep.format import Channel, FrfTable, Run, Sweep, SweepFormatError
from rotorcheck.sweep.validation import validate_sweep

__all__ = ["COLUMNS", "PHASOR_COLUMNS", "export_tidy_csv", "import_tidy_csv", "read_tidy_csv"]

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
    header = list(COLUMNS) + (list(PHASOR_COLUMNS) if include_phasors else [])
    ins, outs = sweep.inputs, sweep.outputs
    with atomic_path(target, overwrite=force) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(header)
            for run in sweep.runs.values():
                sp = repr(float(run.speed_rpm))
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
                                repr(float(run.output_var[k, o])),
                                str(int(run.n_periods[k])),
                            ]
                            if include_phasors:
                                u = complex(run.input_phasor[k, i])
                                y = complex(run.output_phasor[k, o])
                                row += [repr(u.real), repr(u.imag), repr(y.real), repr(y.imag)]
                            w.writerow(row)


def _rows(file: str) -> tuple[list[str], list[tuple[int, dict[str, str]]]]:
    if not os.path.exists(file):
        raise SweepFormatError(file, "/", "no such file")
    with open(file, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise SweepFormatError(file, "line 1", "empty file (no header)") from None
        missing = [c for c in COLUMNS if c not in header]
        if missing:
            raise SweepFormatError(file, "line 1", f"missing columns {missing}")
        rows = []
        for lineno, raw in enumerate(reader, start=2):
            if not raw:
                continue
            if len(raw) != len(header):
                raise SweepFormatError(file, f"line {lineno}", f"{len(raw)} fields, header has {len(header)}")
            rows.append((lineno, dict(zip(header, raw, strict=True))))
    if not rows:
        raise SweepFormatError(file, "line 2", "no data rows")
    return header, rows


def _num(file: str, lineno: int, row: dict[str, str], col: str) -> float:
    try:
        return float(row[col])
    except ValueError:
        raise SweepFormatError(file, f"line {lineno}/{col}", f"not a number: {row[col]!r}") from None


def _parse_tables(
    file: str, header: list[str], rows: list[tuple[int, dict[str, str]]], phasors: bool
) -> tuple[dict[str, FrfTable], dict[str, tuple[np.ndarray, np.ndarray]]]:
    runs: dict[str, list[tuple[int, dict[str, str]]]] = {}
    for lineno, row in rows:
        if not row["run_id"]:
            raise SweepFormatError(file, f"line {lineno}/run_id", "empty run_id")
        runs.setdefault(row["run_id"], []).append((lineno, row))
    tables: dict[str, FrfTable] = {}
    phas: dict[str, tuple[np.ndarray, np.ndarray]] = {}
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
        nf, no, ni = len(freqs), len(outs), len(ins)
        frf = np.full((nf, no, ni), np.nan + 1j * np.nan)
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
            v = _num(file, ln, r, "output_var")
            if not np.isnan(var[k, o]) and var[k, o] != v:
                raise SweepFormatError(file, f"line {ln}/output_var", "differs between inputs")
            var[k, o] = v
            try:
                n = int(r["n_periods"])
            except ValueError:
                raise SweepFormatError(
                    file, f"line {ln}/n_periods", f"not an integer: {r['n_periods']!r}"
                ) from None
            if nper[k] not in (-1, n):
                raise SweepFormatError(file, f"line {ln}/n_periods", "differs within a frequency")
            nper[k] = n
            if phasors:
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
        tables[rid] = FrfTable(
            run_id=rid,
            speed_rpm=speeds.pop(),
            frequency=np.asarray(freqs, dtype=np.float64),
            outputs=[Channel(n, "output", 1, "x", "displacement", "m") for n in outs],
            inputs=[Channel(n, "input", 1, "x", "force", "N") for n in ins],
            frf=frf,
            output_var=var,
            n_periods=nper.astype(np.int32),
        )
        phas[rid] = (u, y)
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
) -> Sweep:
    """Rebuild a :class:`Sweep` from a tidy CSV with the phasor columns.

    The CSV carries no channel metadata or header fields, so the caller supplies them
    (``channels`` matched by name). Validated like a sweep file.
    """
    file = os.fspath(path)
    header, rows = _rows(file)
    missing = [c for c in PHASOR_COLUMNS if c not in header]
    if missing:
        raise SweepFormatError(file, "line 1", f"missing columns {missing}: FRF-only CSV, use read_tidy_csv")
    tables, phas = _parse_tables(file, header, rows, phasors=True)
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
        u, y = phas[rid]
        runs[rid] = Run(
            run_id=rid,
            speed_rpm=tab.speed_rpm,
            frequency=tab.frequency,
            input_phasor=u[:, ii],
            output_phasor=y[:, oi],
            output_var=tab.output_var[:, oi],  # type: ignore[index]
            n_periods=tab.n_periods,  # type: ignore[arg-type]
            frf=tab.frf[:, oi][:, :, ii],
        )
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
