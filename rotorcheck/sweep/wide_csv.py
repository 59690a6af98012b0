"""Wide CSV (one row per frequency, as an analyser or a spreadsheet writes it) import/export.

A wide CSV has a frequency column and, per output/input channel pair, either the FRF's real and
imaginary parts or its magnitude and phase, plus optional variance columns. A **column map**
(YAML or JSON) says which column is what; an import gives one FRF-only run (format version 2)::

    frequency: "Freq [Hz]"          # the frequency column (required)
    frequency_unit: Hz              # Hz (default) | kHz
    frf_unit: m/N                   # m/N (default) | mm/N | um/N | nm/N | a number (factor to m/N)
    delimiter: ","                  # default ","; decimal: "." (default) or ","
    header_row: 1                   # 1-based line of the column names (default 1)
    data_row: 2                     # 1-based first data line (default header_row + 1)
    run_id: 1000rpm                 # optional, else --run-id, else "<speed>rpm"
    speed_rpm: 1000.0               # optional, else --speed (required one way or the other)
    rig_id: crack_rig               # optional, else --rig-id (required one way or the other)
    noise_source: measured          # optional, else --noise-source (the caller's wins)
    source: measured                # optional (default "measured"); created_utc, generator, notes
    channel_order: [F8x, d6x]       # optional order of the channel table (default inputs, outputs)
    pairs:
      - output: {name: d6x, node: 6, direction: x}
        input: {name: F8x, node: 8, direction: x}
        re: "H1 re"                 # real and imaginary part in frf_unit ...
        im: "H1 im"
        var: "H1 var"               # optional: variance of the FRF, (frf_unit)^2
      - output: {name: d6y, node: 6, direction: y}
        input: {name: F8x, node: 8, direction: x}
        mag: "H2 mag"               # ... or magnitude and phase
        mag_unit: dB                # linear (|H| in frf_unit) | dB (20 log10 |H| re 1 frf_unit)
        phase: "H2 phase"
        phase_unit: deg             # deg | rad (both required with mag/phase: nothing is assumed)
        frf_unit: um/N              # optional per pair

Every output/input combination needs exactly one pair; variance columns are given for every pair or
for none (``frf_var``). Columns the map does not name are ignored (coherence, auto spectra ...).
Errors name the file, the line (1-based) and the column (or the map file and its key).

Export (:func:`export_wide_csv`) writes one run: ``frequency_hz`` and per pair ``<out>/<in> re``,
``<out>/<in> im`` and, where the run has a variance (stored ``frf_var`` or propagated from the
phasors), ``<out>/<in> var``, all floats as ``repr`` (shortest round-trip form, so HDF5 -> wide CSV ->
HDF5 is exact), plus its column map ``<stem>.columns.yaml`` beside it (or the path given; JSON for ``.json``) holding
the run's metadata.
"""

from __future__ import annotations

import csv
import datetime as _dt
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rotorcheck.fileio import atomic_path
from rotorcheck.safeload import load_yaml
from rotorcheck.sweep.format import (
    DIRECTIONS,
    SOURCES,
    Channel,
    Run,
    Sweep,
    SweepFormatError,
    noise_source_problem,
)
from rotorcheck.sweep.validation import validate_sweep
from rotorcheck.units import UNITS

__all__ = [
    "FREQUENCY_UNITS",
    "FRF_UNITS",
    "ColumnMap",
    "PairColumns",
    "default_column_map_path",
    "export_wide_csv",
    "import_wide_csv",
    "read_column_map",
]

#: FRF units a column map may name, as the factor to m/N
FRF_UNITS = UNITS["receptance"]
#: frequency units a column map may name, as the factor to Hz
FREQUENCY_UNITS = {"Hz": 1.0, "kHz": 1e3}
MAG_UNITS = ("linear", "dB")
PHASE_UNITS = ("deg", "rad")
_TOP_KEYS = {
    "format", "frequency", "frequency_unit", "frf_unit", "delimiter", "decimal", "header_row", "data_row",
    "run_id", "speed_rpm", "rig_id", "noise_source", "source", "created_utc", "generator", "notes",
    "channel_order", "pairs",
}
_PAIR_KEYS = {"output", "input", "re", "im", "mag", "phase", "mag_unit", "phase_unit", "var", "frf_unit"}
_CHANNEL_KEYS = {"name", "node", "direction"}
#: the export's frequency column
FREQUENCY_COLUMN = "frequency_hz"


@dataclass(frozen=True)
class PairColumns:
    """The columns of one output/input pair and how to read them (``scale``: frf unit -> m/N)."""

    output: Channel
    input: Channel
    re: str | None = None
    im: str | None = None
    mag: str | None = None
    phase: str | None = None
    mag_unit: str | None = None
    phase_unit: str | None = None
    var: str | None = None
    scale: float = 1.0


@dataclass
class ColumnMap:
    """A parsed column map (``file`` names it in messages); see the module docstring."""

    file: str
    frequency: str
    pairs: list[PairColumns]
    frequency_scale: float = 1.0
    delimiter: str = ","
    decimal: str = "."
    header_row: int = 1
    data_row: int | None = None
    run_id: str | None = None
    speed_rpm: float | None = None
    rig_id: str | None = None
    noise_source: str | None = None
    source: str | None = None
    created_utc: str | None = None
    generator: str | None = None
    notes: str = ""
    channel_order: list[str] | None = None


def default_column_map_path(csv_path: str | os.PathLike[str]) -> Path:
    """``<stem>.columns.yaml`` beside the CSV: where :func:`export_wide_csv` writes the map and where
    an import looks when no map is given."""
    p = Path(csv_path)
    return p.with_name(p.stem + ".columns.yaml")


# --------------------------------------------------------------------------------------------
# column map
# --------------------------------------------------------------------------------------------


#: the longest column map (or tidy CSV side file) read, characters
MAX_MAP_BYTES = 1_000_000


def _load_mapping(path: str) -> Mapping[str, Any]:
    if not os.path.exists(path):
        raise SweepFormatError(path, "/", "no such column map file")
    try:
        with open(path, encoding="utf-8-sig") as fh:
            text = fh.read(MAX_MAP_BYTES + 1)
    except (OSError, UnicodeDecodeError) as exc:
        raise SweepFormatError(path, "/", f"cannot read as UTF-8 text: {exc}") from None
    if len(text) > MAX_MAP_BYTES:
        raise SweepFormatError(path, "/", f"over {MAX_MAP_BYTES} characters: no column map is that long")
    try:
        data = json.loads(text) if path.lower().endswith(".json") else load_yaml(text)
    except (ValueError, yaml.YAMLError) as exc:
        kind = "JSON" if path.lower().endswith(".json") else "YAML"
        raise SweepFormatError(path, "/", f"not valid {kind}: {exc}") from exc
    if not isinstance(data, Mapping):
        raise SweepFormatError(path, "/", f"expected a mapping of keys, got {type(data).__name__}")
    return data


def _text(file: str, where: str, v: Any, *, empty: bool = False) -> str:
    if not isinstance(v, str) or (not empty and not v.strip()):
        raise SweepFormatError(file, where, f"expected {'text' if empty else 'non-empty text'}, got {v!r}")
    return v


def _number(file: str, where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(float(v)):
        raise SweepFormatError(file, where, f"expected a finite number, got {v!r}")
    return float(v)


def _line_no(file: str, where: str, v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise SweepFormatError(file, where, f"expected a 1-based line number, got {v!r}")
    return int(v)


def _unit(file: str, where: str, v: Any, table: Mapping[str, float]) -> float:
    if isinstance(v, str):
        if v not in table:
            raise SweepFormatError(file, where, f"unit {v!r} not one of {list(table)} (or give a number)")
        return table[v]
    x = _number(file, where, v)
    if x <= 0:
        raise SweepFormatError(file, where, f"scale factor {x!r} must be > 0")
    return x


def _unknown_keys(file: str, where: str, d: Mapping[str, Any], allowed: set[str]) -> None:
    extra = sorted(str(k) for k in d if k not in allowed)
    if extra:
        raise SweepFormatError(file, where, f"unknown keys {extra} (known: {sorted(allowed)})")


def _channel(file: str, where: str, v: Any, role: str) -> Channel:
    if not isinstance(v, Mapping):
        raise SweepFormatError(file, where, f"expected {{name, node, direction}}, got {v!r}")
    _unknown_keys(file, where, v, _CHANNEL_KEYS)
    for k in sorted(_CHANNEL_KEYS):
        if k not in v:
            raise SweepFormatError(file, f"{where}.{k}", "missing (the model maps channels by node and direction)")
    name = _text(file, f"{where}.name", v["name"])
    node = v["node"]
    if isinstance(node, bool) or not isinstance(node, int) or node < 1:
        raise SweepFormatError(file, f"{where}.node", f"expected a model station (integer >= 1), got {node!r}")
    direction = v["direction"]
    if direction not in DIRECTIONS:
        raise SweepFormatError(file, f"{where}.direction", f"expected one of {list(DIRECTIONS)}, got {direction!r}")
    if role == "input":
        return Channel(name, "input", int(node), str(direction), "force", "N")
    return Channel(name, "output", int(node), str(direction), "displacement", "m")


def _pair(file: str, where: str, v: Any, default_scale: float) -> PairColumns:
    if not isinstance(v, Mapping):
        raise SweepFormatError(file, where, f"expected a mapping, got {type(v).__name__}")
    _unknown_keys(file, where, v, _PAIR_KEYS)
    for k in ("output", "input"):
        if k not in v:
            raise SweepFormatError(file, f"{where}.{k}", "missing")
    out = _channel(file, f"{where}.output", v["output"], "output")
    inp = _channel(file, f"{where}.input", v["input"], "input")
    cols = {k: _text(file, f"{where}.{k}", v[k]) for k in ("re", "im", "mag", "phase", "var") if k in v}
    cart, polar = "re" in cols or "im" in cols, "mag" in cols or "phase" in cols
    if cart == polar:
        raise SweepFormatError(file, where, "give either re and im, or mag and phase (with mag_unit and phase_unit)")
    scale = _unit(file, f"{where}.frf_unit", v["frf_unit"], FRF_UNITS) if "frf_unit" in v else default_scale
    if cart:
        for k in ("re", "im"):
            if k not in cols:
                raise SweepFormatError(file, f"{where}.{k}", "missing (re and im go together)")
        for k in ("mag_unit", "phase_unit"):
            if k in v:
                raise SweepFormatError(file, f"{where}.{k}", "only with mag and phase")
        return PairColumns(out, inp, re=cols["re"], im=cols["im"], var=cols.get("var"), scale=scale)
    for k in ("mag", "phase"):
        if k not in cols:
            raise SweepFormatError(file, f"{where}.{k}", "missing (mag and phase go together)")
    units = {}
    for k, allowed in (("mag_unit", MAG_UNITS), ("phase_unit", PHASE_UNITS)):
        if k not in v:
            raise SweepFormatError(file, f"{where}.{k}", f"missing: say which unit ({' | '.join(allowed)})")
        if v[k] not in allowed:
            raise SweepFormatError(file, f"{where}.{k}", f"expected one of {list(allowed)}, got {v[k]!r}")
        units[k] = str(v[k])
    return PairColumns(out, inp, mag=cols["mag"], phase=cols["phase"], mag_unit=units["mag_unit"],
                       phase_unit=units["phase_unit"], var=cols.get("var"), scale=scale)


def read_column_map(source: str | os.PathLike[str] | Mapping[str, Any], *, name: str = "<column map>") -> ColumnMap:
    """Parse a column map from a YAML/JSON file (``.json``: JSON, else YAML) or a mapping; unknown keys
    and incomplete pairs are refused (:class:`SweepFormatError` naming the map file and key)."""
    if isinstance(source, Mapping):
        file, d = name, source
    else:
        file = os.fspath(source)
        d = _load_mapping(file)
    _unknown_keys(file, "/", d, _TOP_KEYS)
    if d.get("format", "wide") != "wide":
        raise SweepFormatError(file, "format", f"{d['format']!r}: not a wide CSV column map")
    if "frequency" not in d:
        raise SweepFormatError(file, "frequency", "missing: the name of the frequency column")
    cm = ColumnMap(file=file, frequency=_text(file, "frequency", d["frequency"]), pairs=[])
    if "frequency_unit" in d:
        cm.frequency_scale = _unit(file, "frequency_unit", d["frequency_unit"], FREQUENCY_UNITS)
    scale = _unit(file, "frf_unit", d["frf_unit"], FRF_UNITS) if "frf_unit" in d else 1.0
    if "delimiter" in d:
        cm.delimiter = _text(file, "delimiter", d["delimiter"], empty=True)
        if len(cm.delimiter) != 1:
            raise SweepFormatError(file, "delimiter", f"expected one character, got {cm.delimiter!r}")
    if "decimal" in d:
        if d["decimal"] not in (".", ","):
            raise SweepFormatError(file, "decimal", f"expected '.' or ',', got {d['decimal']!r}")
        cm.decimal = str(d["decimal"])
    if cm.decimal == cm.delimiter:
        raise SweepFormatError(file, "decimal", f"decimal mark {cm.decimal!r} is also the delimiter")
    if "header_row" in d:
        cm.header_row = _line_no(file, "header_row", d["header_row"])
    if "data_row" in d:
        cm.data_row = _line_no(file, "data_row", d["data_row"])
        if cm.data_row <= cm.header_row:
            raise SweepFormatError(file, "data_row", f"{cm.data_row} is not after header_row {cm.header_row}")
    for k in ("run_id", "rig_id", "created_utc", "generator"):
        if k in d:
            setattr(cm, k, _text(file, k, d[k], empty=k == "generator"))
    if "notes" in d:
        cm.notes = _text(file, "notes", d["notes"], empty=True)
    if "speed_rpm" in d:
        cm.speed_rpm = _number(file, "speed_rpm", d["speed_rpm"])
    if "source" in d:
        if d["source"] not in SOURCES:
            raise SweepFormatError(file, "source", f"expected one of {list(SOURCES)}, got {d['source']!r}")
        cm.source = str(d["source"])
    if "noise_source" in d:
        cm.noise_source = _text(file, "noise_source", d["noise_source"])
        why = noise_source_problem(cm.noise_source)
        if why is not None:
            raise SweepFormatError(file, "noise_source", why)
    if "channel_order" in d:
        order = d["channel_order"]
        if not isinstance(order, list):
            raise SweepFormatError(file, "channel_order", "expected a list of channel names")
        cm.channel_order = [_text(file, f"channel_order[{i}]", n) for i, n in enumerate(order)]
    pairs = d.get("pairs")
    if not isinstance(pairs, list) or not pairs:
        raise SweepFormatError(file, "pairs", "missing or empty: one entry per output/input pair")
    cm.pairs = [_pair(file, f"pairs[{i}]", p, scale) for i, p in enumerate(pairs)]
    _check_matrix(cm)
    return cm


def _check_matrix(cm: ColumnMap) -> None:
    """Channels consistent between pairs; every output/input combination exactly once."""
    chans: dict[str, Channel] = {}
    for i, p in enumerate(cm.pairs):
        for side, ch in (("output", p.output), ("input", p.input)):
            seen = chans.setdefault(ch.name, ch)
            if seen != ch:
                raise SweepFormatError(
                    cm.file, f"pairs[{i}].{side}",
                    f"channel {ch.name!r} is {ch.role} node {ch.node} {ch.direction} here but {seen.role} node "
                    f"{seen.node} {seen.direction} in an earlier pair",
                )
    outs = list(dict.fromkeys(p.output.name for p in cm.pairs))
    ins = list(dict.fromkeys(p.input.name for p in cm.pairs))
    cells: dict[tuple[str, str], int] = {}
    for i, p in enumerate(cm.pairs):
        key = (p.output.name, p.input.name)
        if key in cells:
            raise SweepFormatError(cm.file, f"pairs[{i}]",
                                   f"output {key[0]} / input {key[1]} already in pairs[{cells[key]}]")
        cells[key] = i
    missing = [f"{o}/{i}" for o in outs for i in ins if (o, i) not in cells]
    if missing:
        raise SweepFormatError(cm.file, "pairs", f"no columns for output/input {missing}: the FRF matrix needs every "
                               "combination of the outputs and inputs named")
    with_var = [p.var is not None for p in cm.pairs]
    if any(with_var) and not all(with_var):
        raise SweepFormatError(cm.file, f"pairs[{with_var.index(False)}].var",
                               "missing: variance columns go with every pair or with none")
    if cm.channel_order is not None and sorted(cm.channel_order) != sorted(chans):
        raise SweepFormatError(cm.file, "channel_order", f"{cm.channel_order} is not an order of the pairs' "
                               f"channels {sorted(chans)}")


# --------------------------------------------------------------------------------------------
# import
# --------------------------------------------------------------------------------------------


def _read_table(file: str, cm: ColumnMap) -> tuple[dict[str, int], list[tuple[int, list[str]]]]:
    """The header (column name -> index) and the data rows with their 1-based line numbers."""
    if not os.path.exists(file):
        raise SweepFormatError(file, "/", "no such file")
    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    first_data = cm.data_row if cm.data_row is not None else cm.header_row + 1
    try:
        with open(file, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh, delimiter=cm.delimiter)
            start = 1
            for row in reader:
                line, start = start, reader.line_num + 1  # a quoted field may span lines: name its first
                if line < cm.header_row:
                    continue
                if header is None:
                    header = [c.strip() for c in row]
                    continue
                if line < first_data or not any(c.strip() for c in row):
                    continue
                rows.append((line, row))
    except UnicodeDecodeError as exc:
        raise SweepFormatError(file, "/", f"not UTF-8 text: {exc}") from exc
    except csv.Error as exc:
        raise SweepFormatError(file, f"line {start}", f"unreadable CSV: {exc}") from exc
    if header is None:
        raise SweepFormatError(file, f"line {cm.header_row}",
                               f"no header line (header_row {cm.header_row} of {cm.file})")
    index: dict[str, int] = {}
    for k, name in enumerate(header):
        index.setdefault(name, k)
    needed = [cm.frequency] + [c for p in cm.pairs for c in (p.re, p.im, p.mag, p.phase, p.var) if c is not None]
    for name in needed:
        if name.strip() not in index:
            raise SweepFormatError(file, f"line {cm.header_row}, column {name!r}",
                                   f"not in the header (named in {cm.file}); the header has {header}")
        if header.count(name.strip()) > 1:
            raise SweepFormatError(file, f"line {cm.header_row}, column {name!r}",
                                   "appears more than once in the header")
    if not rows:
        raise SweepFormatError(file, f"line {first_data}", "no data rows")
    return {n: index[n.strip()] for n in needed}, rows


def _cell(file: str, line: int, row: list[str], col: str, k: int, decimal: str) -> float:
    where = f"line {line}, column {col!r}"
    if k >= len(row):
        raise SweepFormatError(file, where, f"missing cell (the row has {len(row)} fields)")
    s = row[k].strip()
    if not s:
        raise SweepFormatError(file, where, "empty cell")
    try:
        x = float(s.replace(",", ".") if decimal == "," else s)
    except ValueError:
        raise SweepFormatError(file, where, f"not a number: {row[k]!r}") from None
    if not math.isfinite(x):
        raise SweepFormatError(file, where, f"not a finite number: {row[k]!r}")
    return x


def _frf_value(file: str, line: int, row: list[str], p: PairColumns, idx: dict[str, int], dec: str) -> complex:
    if p.re is not None and p.im is not None:
        re = _cell(file, line, row, p.re, idx[p.re], dec)
        im = _cell(file, line, row, p.im, idx[p.im], dec)
        return complex(re * p.scale, im * p.scale)
    assert p.mag is not None and p.phase is not None
    mag = _cell(file, line, row, p.mag, idx[p.mag], dec)
    ph = _cell(file, line, row, p.phase, idx[p.phase], dec)
    if p.mag_unit == "dB":
        mag = 10.0 ** (mag / 20.0)
    elif mag < 0:
        raise SweepFormatError(file, f"line {line}, column {p.mag!r}", f"negative magnitude {mag!r}")
    phi = math.radians(ph) if p.phase_unit == "deg" else ph
    return complex(mag * p.scale * math.cos(phi), mag * p.scale * math.sin(phi))


def _mtime_utc(path: str) -> str:
    t = os.stat(path).st_mtime
    return _dt.datetime.fromtimestamp(int(t), _dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _agree(file: str, what: str, stated: Any, given: Any, option: str) -> Any:
    """The value the file states, else the caller's; both and different is an error."""
    if stated is not None and given is not None and stated != given:
        raise SweepFormatError(file, what, f"the column map states {stated!r}, {option} gives {given!r}: "
                               f"drop {option} or correct the map")
    return stated if stated is not None else given


def import_wide_csv(
    path: str | os.PathLike[str],
    column_map: str | os.PathLike[str] | Mapping[str, Any] | ColumnMap | None = None,
    *,
    speed_rpm: float | None = None,
    run_id: str | None = None,
    rig_id: str | None = None,
    noise_source: str | None = None,
    source: str | None = None,
    created_utc: str | None = None,
    generator: str | None = None,
) -> Sweep:
    """Read a wide CSV as one FRF-only run (version 2) through its column map.

    ``column_map``: a file (YAML/JSON), a mapping or a :class:`ColumnMap`; default
    :func:`default_column_map_path`. ``speed_rpm``, ``run_id`` and ``rig_id`` fill what the map
    does not state (a different value than the map's is an error); ``noise_source`` ("measured" or
    "assumed: <rule>") overrides the map's. The run id defaults to ``"<speed:g>rpm"``, ``source`` to
    "measured", ``created_utc`` to the CSV's modification time (UTC), ``generator`` to
    ``"wide csv import of <name>"``. Speed, rig id and a noise statement are required; a missing one
    raises :class:`SweepFormatError` saying what to pass.
    """
    file = os.fspath(path)
    if isinstance(column_map, ColumnMap):
        cm = column_map
    elif column_map is None:
        default = default_column_map_path(file)
        if not default.exists():
            raise SweepFormatError(file, "column map", f"a wide CSV needs its column map: pass --column-map FILE "
                                   f"(YAML or JSON; none at {default})")
        cm = read_column_map(default)
    else:
        cm = read_column_map(column_map)
    idx, rows = _read_table(file, cm)
    freq = np.empty(len(rows))
    outs = list(dict.fromkeys(p.output for p in cm.pairs))
    ins = list(dict.fromkeys(p.input for p in cm.pairs))
    frf = np.empty((len(rows), len(outs), len(ins)), dtype=np.complex128)
    has_var = cm.pairs[0].var is not None
    var = np.empty(frf.shape) if has_var else None
    cell = {(p.output.name, p.input.name): p for p in cm.pairs}
    for k, (line, row) in enumerate(rows):
        f = _cell(file, line, row, cm.frequency, idx[cm.frequency], cm.decimal) * cm.frequency_scale
        if k and not f > freq[k - 1]:
            raise SweepFormatError(file, f"line {line}, column {cm.frequency!r}",
                                   f"frequency {f!r} Hz is not above the previous line's {float(freq[k - 1])!r} Hz")
        freq[k] = f
        for o, co in enumerate(outs):
            for i, ci in enumerate(ins):
                p = cell[(co.name, ci.name)]
                frf[k, o, i] = _frf_value(file, line, row, p, idx, cm.decimal)
                if var is not None:
                    assert p.var is not None
                    v = _cell(file, line, row, p.var, idx[p.var], cm.decimal)
                    if v < 0:
                        raise SweepFormatError(file, f"line {line}, column {p.var!r}", f"negative variance {v!r}")
                    var[k, o, i] = v * p.scale * p.scale
    speed = _agree(cm.file, "speed_rpm", cm.speed_rpm, None if speed_rpm is None else float(speed_rpm), "--speed")
    if speed is None:
        raise SweepFormatError(file, "speed_rpm", f"no speed: pass --speed RPM (or put speed_rpm: in {cm.file})")
    rig = _agree(cm.file, "rig_id", cm.rig_id, rig_id, "--rig-id")
    if rig is None:
        raise SweepFormatError(file, "rig_id", f"no rig id: pass --rig-id NAME (or put rig_id: in {cm.file})")
    rid = _agree(cm.file, "run_id", cm.run_id, run_id, "--run-id")
    rid = rid if rid is not None else f"{speed:g}rpm"
    ns = noise_source if noise_source is not None else cm.noise_source
    if ns is None:
        raise SweepFormatError(
            file, "noise_source",
            "FRF-only data need a noise statement: pass --noise-source 'measured' (the variance columns come from "
            "the analyser) or --noise-source 'assumed: <rule>' / --noise-var VAR (or put noise_source: in "
            f"{cm.file})",
        )
    why = noise_source_problem(ns)
    if why is not None:
        raise SweepFormatError(file, "noise_source", why)
    chans = [*ins, *outs]
    if cm.channel_order is not None:
        by_name = {c.name: c for c in chans}
        chans = [by_name[n] for n in cm.channel_order]
    sweep = Sweep(
        rig_id=rig,
        source=source if source is not None else (cm.source or "measured"),
        generator=generator if generator is not None else (
            cm.generator if cm.generator is not None else f"wide csv import of {os.path.basename(file)}"),
        created_utc=created_utc if created_utc is not None else (cm.created_utc or _mtime_utc(file)),
        channels=chans,
        runs={rid: Run.frf_only(rid, speed, freq, _reorder(frf, outs, ins, chans), None if var is None else
                                _reorder(var, outs, ins, chans), noise_source=ns, notes=cm.notes)},
    )
    validate_sweep(sweep, file)
    return sweep


def _reorder(a: np.ndarray, outs: list[Channel], ins: list[Channel], chans: list[Channel]) -> np.ndarray:
    """(f, n_out, n_in) from the map's order into the channel table's."""
    oi = [outs.index(c) for c in chans if c.role == "output"]
    ii = [ins.index(c) for c in chans if c.role == "input"]
    return np.ascontiguousarray(a[:, oi][:, :, ii])


# --------------------------------------------------------------------------------------------
# export
# --------------------------------------------------------------------------------------------


def export_wide_csv(
    sweep: Sweep,
    path: str | os.PathLike[str],
    *,
    run_id: str | None = None,
    force: bool = False,
    column_map_path: str | os.PathLike[str] | None = None,
) -> tuple[Path, Path]:
    """Write one run (``run_id``, or the only run) as a wide CSV and its column map (YAML, default
    :func:`default_column_map_path`), each atomically; refuses to overwrite either unless ``force``.
    Returns (csv path, map path)."""
    target = Path(path)
    map_path = Path(column_map_path) if column_map_path is not None else default_column_map_path(target)
    validate_sweep(sweep, os.fspath(target))
    if run_id is None:
        if len(sweep.runs) != 1:
            raise SweepFormatError(os.fspath(target), "/runs", f"a wide CSV holds one run; the sweep has "
                                   f"{list(sweep.runs)}: pass --run-id")
        run = next(iter(sweep.runs.values()))
    elif run_id not in sweep.runs:
        raise SweepFormatError(os.fspath(target), f"/runs/{run_id}", f"no such run (runs: {list(sweep.runs)})")
    else:
        run = sweep.runs[run_id]
    if not force:
        for p in (target, map_path):
            if p.exists():
                raise FileExistsError(f"{p}: exists; refusing to overwrite (pass force=True / --force)")
    ins, outs = sweep.inputs, sweep.outputs
    var = run.frf_variance()
    noise = run.noise_source if run.noise_source is not None else ("measured" if var is not None else None)
    names = [(co.name, ci.name) for co in outs for ci in ins]
    header = [FREQUENCY_COLUMN]
    pairs: list[dict[str, Any]] = []
    for co in outs:
        for ci in ins:
            stem = f"{co.name}/{ci.name}"
            header += [f"{stem} re", f"{stem} im"] + ([f"{stem} var"] if var is not None else [])
            pair: dict[str, Any] = {
                "output": {"name": co.name, "node": int(co.node), "direction": co.direction},
                "input": {"name": ci.name, "node": int(ci.node), "direction": ci.direction},
                "re": f"{stem} re",
                "im": f"{stem} im",
            }
            if var is not None:
                pair["var"] = f"{stem} var"
            pairs.append(pair)
    doc: dict[str, Any] = {
        "format": "wide",
        "frequency": FREQUENCY_COLUMN,
        "frequency_unit": "Hz",
        "frf_unit": "m/N",
        "run_id": run.run_id,
        "speed_rpm": float(run.speed_rpm),
        "rig_id": sweep.rig_id,
        "source": sweep.source,
        "created_utc": sweep.created_utc,
        "generator": sweep.generator,
    }
    if noise is not None:
        doc["noise_source"] = noise
    if run.notes:
        doc["notes"] = run.notes
    doc["channel_order"] = [c.name for c in sweep.channels]
    doc["pairs"] = pairs
    frf = np.asarray(run.frf, dtype=np.complex128)
    with atomic_path(target, overwrite=force) as tmp_csv, atomic_path(map_path, overwrite=force) as tmp_map:
        with open(tmp_csv, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(header)
            for k, fk in enumerate(np.asarray(run.frequency, dtype=np.float64)):
                row = [repr(float(fk))]
                for o in range(len(outs)):
                    for i in range(len(ins)):
                        h = complex(frf[k, o, i])
                        row += [repr(h.real), repr(h.imag)]
                        if var is not None:
                            row.append(repr(float(var[k, o, i])))
                w.writerow(row)
        if map_path.suffix.lower() == ".json":
            text = json.dumps(doc, indent=1, ensure_ascii=False) + "\n"  # floats as repr: exact
        else:
            text = (f"# rotorcheck wide CSV column map for {target.name}: run {run.run_id!r}, {len(names)} "
                    "output/input pairs, FRF in m/N\n" + yaml.safe_dump(doc, sort_keys=False, allow_unicode=True))
        tmp_map.write_text(text, encoding="utf-8")
    return target, map_path
