"""Universal File Format dataset 58 (function at nodal DOF) export/import through pyuff.

Export writes, per run, one FRF record (function type 4) per output/input pair: abscissa the
frequency in Hz (uneven spacing, so the grid is kept as given), ordinate the complex FRF in m/N,
response node/direction = output channel, reference node/direction = input channel (``x`` -> 1,
``y`` -> 2, +translation), z-axis value = speed (rpm). With ``include_phasors`` (default) it also
writes the input phasor (per input), output phasor and output variance (per output) and
``n_periods`` as general records (function type 0), so :func:`import_uff58` rebuilds the whole
sweep; ``period_phasor`` and run notes are not exported.

Version 2 (a sweep that :func:`~rotorcheck.sweep.format.sweep_schema_version` puts in version 2):
the phasor records are written per excitation pattern (token ``exc=<e>``), plus ``input_var`` when
stored; ``frf_var`` (when stored) as one general record per output/input pair; a run's
``noise_source`` travels as ``noise=`` on the FRF records. An FRF-only run has FRF (and
``frf_var``) records only; :func:`import_uff58` turns a run without phasor records into an
FRF-only run, which needs a ``noise_source`` (from the file or the caller). A version-1 sweep is
exported exactly as before (no ``exc=`` tokens).

Metadata travel in the ID lines as ``key=value`` tokens (values percent-encoded)::

    id1  rotorcheck kind=<frf|frf_var|input_phasor|output_phasor|output_var|input_var|n_periods>
         [noise=<noise_source>]                 (FRF and frf_var records of a run that states it)
    id2  run=<run_id> speed_rpm=<repr(float)>
    id3  created=<created_utc>
    id4  rig=<rig_id> source=<simulated|measured>
    id5  out=<output name> in=<input name>      (or chan=<name> for single-channel records)
         [exc=<pattern>]                        (phasor records of a version-2 sweep)

A foreign file (FRF records without these tokens) imports as FRF-only runs: the caller gives
``run_id``, ``rig_id``, ``source``, ``created_utc`` and ``noise_source``; its other function types
(coherence, spectra) are ignored.

Precision: binary 58b (default) stores IEEE doubles, export/import is bit-exact. ASCII 58 keeps
12 significant digits of the ordinate (``%20.11e``, relative error <= 5e-12) and only 6 of the
abscissa (``E13.5``), so the frequency grid is rounded: use ASCII only for foreign tools.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from urllib.parse import quote, unquote

import numpy as np
import pyuff

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

__all__ = ["export_uff58", "import_uff58", "read_uff58_frf"]

_DIR_CODE = {"x": 1, "y": 2}
_CODE_DIR = {1: "x", 2: "y"}
_KINDS = ("frf", "frf_var", "input_phasor", "output_phasor", "output_var", "input_var", "n_periods")
_PHASOR_KINDS = ("input_phasor", "output_phasor", "output_var", "n_periods")


def _tok(**kv: object) -> str:
    return " ".join(f"{k}={quote(str(v), safe='')}" for k, v in kv.items())


def _line(text: str) -> str:
    if len(text) > 80:
        raise ValueError(f"UFF ID line longer than 80 characters: {text!r}")
    return text


def _parse(line: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for part in str(line).split():
        if "=" in part:
            k, v = part.split("=", 1)
            out[k] = unquote(v)
    return out


def _record(
    kind: str,
    run: Run,
    sweep: Sweep,
    x: np.ndarray,
    data: np.ndarray,
    rsp: Channel | None,
    ref: Channel | None,
    binary: bool,
    exc: int | None = None,
) -> dict:
    pair = kind in ("frf", "frf_var")
    if pair:
        names = _tok(out=rsp.name, **{"in": ref.name})  # type: ignore[union-attr]
    elif rsp is not None:
        names = _tok(chan=rsp.name)
    else:
        names = "NONE"
    if exc is not None:
        names = _tok(exc=exc) if names == "NONE" else f"{names} {_tok(exc=exc)}"
    id1 = "rotorcheck " + _tok(kind=kind)
    if pair and run.noise_source is not None:
        id1 += " " + _tok(noise=run.noise_source)
    ord_type = {"frf": 8, "frf_var": 0, "input_phasor": 13, "output_phasor": 8, "output_var": 0,
                "input_var": 0, "n_periods": 0}
    ord_unit = {"frf": "m", "frf_var": "m^2/N^2", "input_phasor": "N", "output_phasor": "m",
                "output_var": "m^2", "input_var": "N^2", "n_periods": "1"}
    return {
        "type": 58,
        "binary": 1 if binary else 0,
        "func_type": 4 if kind == "frf" else 0,
        "func_id": 0,
        "ver_num": 0,
        "load_case_id": 0,
        "id1": _line(id1),
        "id2": _line(_tok(run=run.run_id, speed_rpm=repr(float(run.speed_rpm)))),
        "id3": _line(_tok(created=sweep.created_utc)),
        "id4": _line(_tok(rig=sweep.rig_id, source=sweep.source)),
        "id5": _line(names),
        "rsp_ent_name": "NONE",
        "rsp_node": int(rsp.node) if rsp is not None else 0,
        "rsp_dir": _DIR_CODE[rsp.direction] if rsp is not None else 0,
        "ref_ent_name": "NONE",
        "ref_node": int(ref.node) if ref is not None else 0,
        "ref_dir": _DIR_CODE[ref.direction] if ref is not None else 0,
        "abscissa_spacing": 0,
        "abscissa_spec_data_type": 18,
        "abscissa_axis_units_lab": "Hz",
        "ordinate_spec_data_type": ord_type[kind],
        "ordinate_axis_units_lab": ord_unit[kind],
        "orddenom_spec_data_type": 13 if kind == "frf" else 0,
        "orddenom_axis_units_lab": "N" if kind == "frf" else "NONE",
        "z_axis_spec_data_type": 19,
        "z_axis_value": float(run.speed_rpm),
        "x": np.asarray(x, dtype=np.float64),
        "data": data,
    }


def _records(sweep: Sweep, include_phasors: bool, binary: bool) -> list[dict]:
    ins, outs = sweep.inputs, sweep.outputs
    v2 = sweep_schema_version(sweep) == 2
    recs: list[dict] = []
    for run in sweep.runs.values():
        x = np.asarray(run.frequency, dtype=np.float64)
        if x.size < 2:
            raise ValueError(f"run {run.run_id!r}: UFF58 export (pyuff) needs >= 2 frequency points")
        if include_phasors and not run.is_frf_only and not v2:
            for i, ch in enumerate(ins):
                d = np.asarray(run.input_phasor[:, i], dtype=np.complex128)
                recs.append(_record("input_phasor", run, sweep, x, d, ch, None, binary))
            for o, ch in enumerate(outs):
                d = np.asarray(run.output_phasor[:, o], dtype=np.complex128)
                recs.append(_record("output_phasor", run, sweep, x, d, ch, None, binary))
            for o, ch in enumerate(outs):
                d = np.asarray(run.output_var[:, o], dtype=np.float64)
                recs.append(_record("output_var", run, sweep, x, d, ch, None, binary))
            d = np.asarray(run.n_periods, dtype=np.float64)
            recs.append(_record("n_periods", run, sweep, x, d, None, None, binary))
        elif include_phasors and not run.is_frf_only:
            recs += _pattern_records(run, sweep, x, binary)
        for o, co in enumerate(outs):
            for i, ci in enumerate(ins):
                d = np.asarray(run.frf[:, o, i], dtype=np.complex128)
                recs.append(_record("frf", run, sweep, x, d, co, ci, binary))
        if v2 and run.frf_var is not None:
            fv = np.asarray(run.frf_var, dtype=np.float64)
            for o, co in enumerate(outs):
                for i, ci in enumerate(ins):
                    recs.append(_record("frf_var", run, sweep, x, fv[:, o, i], co, ci, binary))
    return recs


def _pattern_records(run: Run, sweep: Sweep, x: np.ndarray, binary: bool) -> list[dict]:
    """Version 2: the phasor records of every excitation pattern (token ``exc=<e>``)."""
    ins, outs = sweep.inputs, sweep.outputs
    assert run.input_phasor_exc is not None and run.output_phasor_exc is not None
    assert run.output_var_exc is not None and run.n_periods_exc is not None
    recs: list[dict] = []
    for e in range(run.n_exc):
        per = (
            ("input_phasor", ins, run.input_phasor_exc, np.complex128),
            ("output_phasor", outs, run.output_phasor_exc, np.complex128),
            ("output_var", outs, run.output_var_exc, np.float64),
            ("input_var", ins, run.input_var_exc, np.float64),
        )
        for kind, chans, arr, dt in per:
            if arr is None:
                continue
            a = np.asarray(arr)
            for c, ch in enumerate(chans):
                recs.append(_record(kind, run, sweep, x, np.asarray(a[:, e, c], dtype=dt), ch, None, binary, e))
        d = np.asarray(run.n_periods_exc[:, e], dtype=np.float64)
        recs.append(_record("n_periods", run, sweep, x, d, None, None, binary, e))
    return recs


def _load_sets(path: str) -> list[dict]:
    if not os.path.exists(path):
        raise SweepFormatError(path, "/", "no such file")
    try:
        uff = pyuff.UFF(path)
        n = uff.get_n_sets()
        types = list(uff.get_set_types())
        sets = [uff.read_sets(i) for i in range(n)]
    except Exception as exc:
        raise SweepFormatError(path, "/", f"not a readable universal file: {exc}") from exc
    if n == 0:
        raise SweepFormatError(path, "/", "no universal file datasets found")
    out = []
    for i, (t, s) in enumerate(zip(types, sets, strict=True)):
        if int(t) != 58:
            raise SweepFormatError(path, f"dataset #{i + 1}", f"type {int(t)}, expected 58")
        lacks = [k for k in ("x", "data", "func_type", "id1", "id2", "id5", "rsp_node", "rsp_dir", "ref_node",
                             "ref_dir") if k not in s or s[k] is None]
        if lacks:
            raise SweepFormatError(path, f"dataset #{i + 1}", f"no {', '.join(lacks)} (a truncated or malformed "
                                   "record)")
        _check_binary(path, f"dataset #{i + 1}", s)
        out.append(s)
    return out


#: UFF specific data types (records 8-11, field 1) of an FRF record's axes
_SPEC_TYPES = {0: "unknown", 1: "general", 2: "stress", 3: "strain", 5: "temperature", 6: "heat flux",
               8: "displacement", 9: "reaction force", 11: "velocity (mobility)", 12: "acceleration (accelerance)",
               13: "excitation force", 15: "pressure", 16: "mass", 17: "time", 18: "frequency", 19: "rpm",
               20: "order"}
#: length units of an FRF ordinate (record 9 label), to m
_LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "micron": 1e-6, "nm": 1e-9}
#: force units of an FRF denominator (record 10 label), to N
_FORCE_UNITS = {"n": 1.0, "kn": 1e3}
_NO_LABEL = ("", "none")


def _label(s: dict, key: str) -> str:
    return str(s.get(key, "") or "").strip()


def _frf_scale(path: str, where: str, s: dict) -> float:
    """The factor that turns an FRF record's ordinate into m/N, from its record 8-10 types, unit exponents and
    labels; an abscissa that is not frequency (in Hz) or an ordinate that is not displacement per force is a
    SweepFormatError naming the record."""
    absc = int(s.get("abscissa_spec_data_type", 0))
    if absc not in (0, 18):
        raise SweepFormatError(path, f"{where}/record 8", f"abscissa is {_SPEC_TYPES.get(absc, 'type ' + str(absc))} "
                               f"(specific data type {absc}), not frequency")
    lab = _label(s, "abscissa_axis_units_lab")
    if lab.lower() not in (*_NO_LABEL, "hz"):
        raise SweepFormatError(path, f"{where}/record 8", f"abscissa unit {lab!r}, not Hz")
    ordt = int(s.get("ordinate_spec_data_type", 0))
    if ordt not in (0, 8):
        what = _SPEC_TYPES.get(ordt, f"type {ordt}")
        raise SweepFormatError(path, f"{where}/record 9", f"FRF ordinate is {what}: rotorcheck needs receptance "
                               "(displacement/force, m/N); convert it in the analyser")
    den_t = int(s.get("orddenom_spec_data_type", 0))
    if den_t not in (0, 9, 13):
        raise SweepFormatError(path, f"{where}/record 10", f"FRF denominator is "
                               f"{_SPEC_TYPES.get(den_t, 'type ' + str(den_t))}, not a force")
    exps = {k: int(s.get(k, 0)) for k in ("ordinate_len_unit_exp", "ordinate_force_unit_exp",
                                          "orddenom_len_unit_exp", "orddenom_force_unit_exp")}
    if exps["ordinate_len_unit_exp"] not in (0, 1) or exps["ordinate_force_unit_exp"] != 0 \
            or exps["orddenom_len_unit_exp"] != 0 or exps["orddenom_force_unit_exp"] not in (0, 1):
        raise SweepFormatError(path, f"{where}/record 9", f"unit exponents {exps}: not a length per force")
    num, den = _label(s, "ordinate_axis_units_lab"), _label(s, "orddenom_axis_units_lab")
    if "/" in num:  # the ordinate labelled as the whole FRF unit, e.g. "mm/N"
        num, per = (t.strip() for t in num.split("/", 1))
        if den.lower() not in _NO_LABEL and den.lower() != per.lower():
            raise SweepFormatError(path, f"{where}/record 10", f"denominator unit {den!r} contradicts the ordinate's "
                                   f"{_label(s, 'ordinate_axis_units_lab')!r}")
        den = per
    length = 1.0 if num.lower() in _NO_LABEL else _LENGTH_UNITS.get(num.lower() if num != "Mm" else num)
    if length is None:
        raise SweepFormatError(path, f"{where}/record 9", f"ordinate unit {num!r} not understood: rotorcheck reads "
                               f"{', '.join(k for k in _LENGTH_UNITS if k.isascii())} (per N)")
    force = 1.0 if den.lower() in _NO_LABEL else _FORCE_UNITS.get(den.lower() if den != "MN" else den)
    if force is None:
        raise SweepFormatError(path, f"{where}/record 10", f"denominator unit {den!r} not understood: rotorcheck "
                               "reads N, kN")
    return length / force


def _plausible(x: np.ndarray, values: np.ndarray) -> bool:
    """Numbers a measured sweep can hold: finite, no subnormal or astronomically large values, an increasing
    non-negative abscissa."""
    v = np.concatenate([x.ravel(), values.real.ravel(), values.imag.ravel()]).astype(np.float64)
    a = np.abs(v)
    return bool(np.all(np.isfinite(v)) and not np.any((a > 0) & (a < 1e-250)) and not np.any(a > 1e250)
                and np.all(x >= 0) and np.all(np.diff(x) > 0))


def _swapped(a: np.ndarray, single: bool) -> np.ndarray:
    """The other byte order's reading of values pyuff decoded (4-byte floats when ``single``)."""
    a = np.asarray(a)
    if np.iscomplexobj(a):
        return _swapped(a.real, single) + 1j * _swapped(a.imag, single)
    return a.astype(np.float32).byteswap().astype(np.float64) if single else a.astype(np.float64).byteswap()


def _check_binary(path: str, where: str, s: dict) -> None:
    """A binary 58b record must be IEEE floats whose byte order is the one record 1 states: data that only
    make sense byte-swapped are refused (naming the byte ordering field), never read as other numbers."""
    if not int(s.get("binary", 0)):
        return
    fp = int(s.get("fp_format", 2))
    if fp != 2:
        raise SweepFormatError(path, f"{where}/record 1", f"floating-point format {fp} (1 VAX, 3 IBM): rotorcheck "
                               "reads IEEE 754 (2) only")
    x = np.asarray(s.get("x"), dtype=np.float64)
    data = np.asarray(s.get("data"))
    if data.dtype.kind not in "fc" or x.shape != data.shape[:1]:
        return
    single = int(s.get("ord_data_type", 6)) in (2, 5)
    even = int(s.get("abscissa_spacing", 0)) == 1  # the abscissa from record 7, not from the data
    if not _plausible(x, data) and _plausible(x if even else _swapped(x, single), _swapped(data, single)):
        order = {1: "little-endian", 2: "big-endian"}.get(int(s.get("byte_ordering", 1)), "?")
        raise SweepFormatError(path, f"{where}/record 1", f"byte ordering {int(s.get('byte_ordering', 1))} "
                               f"({order}) states the wrong byte order: the data read that way are no sweep, "
                               "byte-swapped they are; correct the header")


def _channel(path: str, where: str, name: str | None, node: int, code: int, role: str) -> Channel:
    if int(code) not in _CODE_DIR:
        raise SweepFormatError(path, where, f"direction code {int(code)} not supported (only +X=1, +Y=2)")
    if int(node) < 1:
        raise SweepFormatError(path, where, f"node {int(node)} is not >= 1")
    direction = _CODE_DIR[int(code)]
    nm = name if name else f"{'F' if role == 'input' else 'd'}{int(node)}{direction}"
    qty = "force" if role == "input" else "displacement"
    return Channel(nm, role, int(node), direction, qty, "N" if role == "input" else "m")


def export_uff58(
    sweep: Sweep,
    path: str | os.PathLike[str],
    *,
    force: bool = False,
    binary: bool = True,
    include_phasors: bool = True,
) -> None:
    """Write ``sweep`` as UFF dataset 58 records, atomically (refuses to overwrite unless
    ``force``). Binary 58b by default (bit-exact); the written file is read back and checked."""
    target = os.fspath(path)
    validate_sweep(sweep, target)
    recs = _records(sweep, include_phasors, binary)
    with atomic_path(target, overwrite=force) as tmp:
        try:
            # the temp file is empty; "add" because pyuff's binary "overwrite" truncates the
            # header it has just written (pyuff 2.5)
            pyuff.UFF(str(tmp)).write_sets(recs, mode="add")
        except Exception as exc:
            raise ValueError(f"{target}: pyuff could not write dataset 58: {exc}") from exc
        if binary:
            back = _load_sets(str(tmp))
            ok = len(back) == len(recs) and all(
                np.array_equal(np.asarray(b["data"]), np.asarray(r["data"]))
                and np.array_equal(np.asarray(b["x"]), np.asarray(r["x"]))
                for b, r in zip(back, recs, strict=True)
            )
            if not ok:
                raise ValueError(
                    f"{target}: binary UFF58 read-back differs (a data block contains the "
                    "'    -1' delimiter); export with binary=False"
                )


def read_uff58_frf(path: str | os.PathLike[str], run_id: str | None = None) -> dict[str, FrfTable]:
    """FRF records (function type 4) of a UFF58 file, grouped by run.

    Runs come from the ``run=`` token of ID line 2 (files written by :func:`export_uff58`); for a
    foreign file without it pass ``run_id`` and every FRF record is taken as that one run (speed
    from the z-axis value). Channel names come from the ``out=``/``in=`` tokens, else
    ``d<node><dir>``/``F<node><dir>``. All records of a run must share the abscissa exactly.
    ``frf_var`` records and the ``noise=`` token (version 2) fill ``FrfTable.frf_var`` and
    ``FrfTable.noise_source``.
    """
    file = os.fspath(path)
    sets = _load_sets(file)
    groups: dict[str, list[tuple[int, dict]]] = {}
    var_groups: dict[str, list[tuple[int, dict]]] = {}
    for i, s in enumerate(sets):
        kind = _parse(s.get("id1", "")).get("kind")
        if int(s.get("func_type", -1)) != 4 and kind != "frf_var":
            continue
        tok = _parse(s.get("id2", ""))
        rid = tok.get("run", run_id)
        if rid is None:
            raise SweepFormatError(
                file, f"dataset #{i + 1}/id2", "no run= token; pass run_id to read a foreign file"
            )
        (var_groups if kind == "frf_var" else groups).setdefault(rid, []).append((i, s))
    if not groups:
        raise SweepFormatError(file, "/", "no FRF (function type 4) records")
    for rid, recs in var_groups.items():
        if rid not in groups:
            raise SweepFormatError(
                file, f"dataset #{recs[0][0] + 1}/id2", f"frf_var of run {rid!r} without FRF records"
            )
    return {rid: _frf_table(file, rid, recs, var_groups.get(rid, [])) for rid, recs in groups.items()}


def _frf_table(file: str, rid: str, recs: list[tuple[int, dict]], var_recs: list[tuple[int, dict]]) -> FrfTable:
    outs: list[Channel] = []
    ins: list[Channel] = []
    cells: dict[tuple[int, int], np.ndarray] = {}
    x0: np.ndarray | None = None
    speed: float | None = None
    noise: set[str | None] = set()
    for i, s in recs:
        where = f"dataset #{i + 1}"
        names = _parse(s.get("id5", ""))
        tok = _parse(s.get("id2", ""))
        noise.add(_parse(s.get("id1", "")).get("noise"))
        sp = float(tok["speed_rpm"]) if "speed_rpm" in tok else float(s.get("z_axis_value", 0.0))
        if speed is None:
            speed = sp
        elif sp != speed:
            raise SweepFormatError(file, where, f"speed {sp!r} rpm differs from {speed!r} in run")
        co = _channel(file, f"{where}/record 6", names.get("out"), s["rsp_node"], s["rsp_dir"], "output")
        ci = _channel(file, f"{where}/record 6", names.get("in"), s["ref_node"], s["ref_dir"], "input")
        if co not in outs:
            outs.append(co)
        if ci not in ins:
            ins.append(ci)
        key = (outs.index(co), ins.index(ci))
        if key in cells:
            raise SweepFormatError(file, where, f"duplicate FRF {co.name}/{ci.name} in run {rid!r}")
        x = np.asarray(s["x"], dtype=np.float64)
        if x0 is None:
            x0 = x
        elif x.shape != x0.shape or not np.array_equal(x, x0):
            raise SweepFormatError(file, f"{where}/abscissa", "frequency grid differs within run")
        cells[key] = np.asarray(s["data"], dtype=np.complex128) * _frf_scale(file, where, s)
    assert x0 is not None and speed is not None
    if len(noise) != 1:
        raise SweepFormatError(file, "/", f"run {rid!r}: noise= token differs between FRF records")
    frf = np.empty((x0.size, len(outs), len(ins)), dtype=np.complex128)
    for o in range(len(outs)):
        for i in range(len(ins)):
            if (o, i) not in cells:
                raise SweepFormatError(file, "/", f"run {rid!r}: FRF {outs[o].name}/{ins[i].name} missing")
            frf[:, o, i] = cells[(o, i)]
    frf_var = None
    if var_recs:
        frf_var = np.full(frf.shape, np.nan)
        out_names, in_names = [c.name for c in outs], [c.name for c in ins]
        for i, s in var_recs:
            where = f"dataset #{i + 1}"
            names = _parse(s.get("id5", ""))
            if names.get("out") not in out_names or names.get("in") not in in_names:
                raise SweepFormatError(file, f"{where}/id5", f"frf_var of a pair without FRF in run {rid!r}")
            if not np.array_equal(np.asarray(s["x"], dtype=np.float64), x0):
                raise SweepFormatError(file, f"{where}/abscissa", "frequency grid differs within run")
            frf_var[:, out_names.index(names["out"]), in_names.index(names["in"])] = np.real(s["data"])
        if np.any(np.isnan(frf_var)):
            raise SweepFormatError(file, "/", f"run {rid!r}: frf_var records missing for some pairs")
    return FrfTable(rid, speed, x0, outs, ins, frf, frf_var=frf_var, noise_source=noise.pop())


def import_uff58(
    path: str | os.PathLike[str],
    *,
    generator: str | None = None,
    channels: Sequence[Channel] | None = None,
    noise_source: str | None = None,
    run_id: str | None = None,
    rig_id: str | None = None,
    source: str | None = None,
    created_utc: str | None = None,
) -> Sweep:
    """Rebuild a :class:`Sweep` from a UFF58 file.

    A run with phasor records (written by :func:`export_uff58`) comes back whole: one pattern
    (version 1) or, with ``exc=`` tokens, several (version 2; frf and frf_var as stored). A run
    with FRF records only becomes an FRF-only run (version 2) with ``frf_var`` where the file has
    it; it needs a ``noise_source`` ("measured" or "assumed: <rule>"): the caller's
    ``noise_source`` when given (it overrides the file's), else the file's ``noise=`` token, else
    :class:`SweepFormatError` saying so. Header fields come from the ID lines (a foreign file
    without them: pass ``run_id``, ``rig_id``, ``source`` and ``created_utc``); ``generator``
    defaults to ``"uff58 import of <name>"``. ``channels`` (optional) fixes the channel-table
    order; by default inputs then outputs in file order.
    """
    file = os.fspath(path)
    sets = _load_sets(file)
    foreign = not any("kind" in _parse(s.get("id1", "")) for s in sets)
    frfs = read_uff58_frf(file, run_id=run_id if foreign else None)
    meta: dict[str, str] = {}
    per_run: dict[str, dict[str, dict[tuple[str, int | None], np.ndarray]]] = {}
    if foreign:
        given = {"rig_id": rig_id, "source": source, "created_utc": created_utc}
        missing_meta = [k for k, v in given.items() if v is None]
        if missing_meta:
            raise SweepFormatError(
                file, "/", f"foreign UFF58 file (no rotorcheck ID tokens): pass {missing_meta} to import it"
            )
        meta = {"rig": str(rig_id), "source": str(source), "created": str(created_utc)}
    for i, s in enumerate([] if foreign else sets):
        where = f"dataset #{i + 1}"
        kind = _parse(s.get("id1", "")).get("kind")
        if kind not in _KINDS:
            raise SweepFormatError(file, f"{where}/id1", "not a rotorcheck record (no kind= token)")
        for line, keys in (("id3", ("created",)), ("id4", ("rig", "source"))):
            tok = _parse(s.get(line, ""))
            for k in keys:
                if k not in tok:
                    raise SweepFormatError(file, f"{where}/{line}", f"missing {k}= token")
                if meta.setdefault(k, tok[k]) != tok[k]:
                    raise SweepFormatError(file, f"{where}/{line}", f"{k} differs between records")
        if kind in ("frf", "frf_var"):
            continue
        run_ref = _parse(s.get("id2", "")).get("run")
        if run_ref is None or run_ref not in frfs:
            raise SweepFormatError(file, f"{where}/id2", f"run {run_ref!r} has no FRF records")
        names = _parse(s.get("id5", ""))
        chan = names.get("chan", "")
        exc = int(names["exc"]) if "exc" in names else None
        x = np.asarray(s["x"], dtype=np.float64)
        if not np.array_equal(x, frfs[run_ref].frequency):
            raise SweepFormatError(file, f"{where}/abscissa", "frequency grid differs within run")
        per_run.setdefault(run_ref, {}).setdefault(kind, {})[(chan, exc)] = np.asarray(s["data"])
    first = next(iter(frfs.values()))
    chans = list(channels) if channels is not None else [*first.inputs, *first.outputs]
    ins = [c for c in chans if c.role == "input"]
    outs = [c for c in chans if c.role == "output"]
    in_file = {c.name: c for c in [*first.inputs, *first.outputs]}
    if sorted(c.name for c in chans) != sorted(in_file) or any(in_file[c.name] != c for c in chans):
        raise SweepFormatError(
            file, "/", f"channels {chans!r} do not match the file's {list(in_file.values())!r}"
        )
    runs: dict[str, Run] = {}
    for rid, tab in frfs.items():
        if [c.name for c in tab.inputs] != [c.name for c in first.inputs] or [
            c.name for c in tab.outputs
        ] != [c.name for c in first.outputs]:
            raise SweepFormatError(file, "/", f"run {rid!r}: channels differ from the first run")
        oi = [[c.name for c in tab.outputs].index(c.name) for c in outs]
        ii = [[c.name for c in tab.inputs].index(c.name) for c in ins]
        frf = tab.frf[:, oi][:, :, ii]
        frf_var = None if tab.frf_var is None else tab.frf_var[:, oi][:, :, ii]
        rec = per_run.get(rid, {})
        missing = [k for k in _PHASOR_KINDS if k not in rec]
        if len(missing) == len(_PHASOR_KINDS):
            what = f"file (no {list(_PHASOR_KINDS)} records)"
            runs[rid] = imported_frf_only(file, tab, frf, frf_var, noise_source, what, "read_uff58_frf")
            continue
        if missing:
            raise SweepFormatError(file, "/", f"run {rid!r}: no {missing} records (phasor records incomplete)")
        runs[rid] = _phasor_run(file, rid, tab, rec, ins, outs, frf, frf_var)
    sweep = Sweep(
        rig_id=meta["rig"],
        source=meta["source"],
        generator=generator if generator is not None else f"uff58 import of {os.path.basename(file)}",
        created_utc=meta["created"],
        channels=chans,
        runs=runs,
    )
    validate_sweep(sweep, file)
    return sweep


def _phasor_run(
    file: str,
    rid: str,
    tab: FrfTable,
    rec: dict[str, dict[tuple[str, int | None], np.ndarray]],
    ins: list[Channel],
    outs: list[Channel],
    frf: np.ndarray,
    frf_var: np.ndarray | None,
) -> Run:
    """A run from its phasor records: one pattern without ``exc=`` tokens, else the patterns."""
    excs = {e for kind in rec.values() for (_, e) in kind}
    if excs == {None}:
        patterns: list[int | None] = [None]
    elif None in excs or excs != set(range(len(excs))):
        raise SweepFormatError(file, "/", f"run {rid!r}: exc= tokens {sorted(map(str, excs))} not 0..n_exc-1")
    else:
        patterns = list(range(len(excs)))

    def col(kind: str, ch: list[Channel], e: int | None) -> np.ndarray:
        try:
            return np.stack([rec[kind][(c.name, e)] for c in ch], axis=1)
        except KeyError as exc:
            raise SweepFormatError(
                file, "/", f"run {rid!r}: {kind} record for channel/pattern {exc.args[0]!r} missing"
            ) from None

    def nper(e: int | None) -> np.ndarray:
        try:
            n = np.asarray(rec["n_periods"][("", e)], dtype=np.float64)
        except KeyError:
            raise SweepFormatError(file, "/", f"run {rid!r}: n_periods record of pattern {e} missing") from None
        if np.any(n != np.round(n)):
            raise SweepFormatError(file, "/", f"run {rid!r}: n_periods not integer")
        return n.astype(np.int32)

    if patterns == [None]:
        return Run.from_v1(
            rid,
            tab.speed_rpm,
            tab.frequency,
            col("input_phasor", ins, None).astype(np.complex128),
            col("output_phasor", outs, None).astype(np.complex128),
            np.real(col("output_var", outs, None)).astype(np.float64),
            nper(None),
            frf,
        )
    input_var = None
    if "input_var" in rec:
        input_var = np.stack([np.real(col("input_var", ins, e)) for e in patterns], axis=1).astype(np.float64)
    return Run(
        run_id=rid,
        speed_rpm=tab.speed_rpm,
        frequency=tab.frequency,
        frf=frf,
        frf_var=frf_var,
        noise_source=tab.noise_source,
        input_phasor_exc=np.stack([col("input_phasor", ins, e) for e in patterns], axis=1).astype(np.complex128),
        output_phasor_exc=np.stack([col("output_phasor", outs, e) for e in patterns], axis=1).astype(np.complex128),
        output_var_exc=np.stack([np.real(col("output_var", outs, e)) for e in patterns], axis=1).astype(np.float64),
        n_periods_exc=np.stack([nper(e) for e in patterns], axis=1),
        input_var_exc=input_var,
    )
