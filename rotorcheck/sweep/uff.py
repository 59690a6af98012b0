"""Universal File Format dataset 58 (function at nodal DOF) export/import through pyuff.

Export writes, per run, one FRF record (function type 4) per output/input pair: abscissa the
frequency in Hz (uneven spacing, so the grid is kept as given), ordinate the complex FRF in m/N,
response node/direction = output channel, reference node/direction = input channel (``x`` -> 1,
``y`` -> 2, +translation), z-axis value = speed (rpm). With ``include_phasors`` (default) it also
writes the input phasor (per input), output phasor and output variance (per output) and
``n_periods`` as general records (function type 0), so :func:`import_uff58` rebuilds the whole
sweep; ``period_phasor`` and run notes are not exported.

Metadata travel in the ID lines as ``key=value`` tokens (values percent-encoded)::

    id1  rotorcheck kind=<frf|input_phasor|output_phasor|output_var|n_periods>
    id2  run=<run_id> speed_rpm=<repr(float)>
    id3  created=<created_utc>
    id4  rig=<rig_id> source=<simulated|measured>
    id5  out=<output name> in=<input name>      (or chan=<name> for single-channel records)

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
from rotorcheck.sweep.format import Channel, FrfTable, Run, Sweep, SweepFormatError
from rotorcheck.sweep.validation import validate_sweep

__all__ = ["export_uff58", "import_uff58", "read_uff58_frf"]

_DIR_CODE = {"x": 1, "y": 2}
_CODE_DIR = {1: "x", 2: "y"}
_KINDS = ("frf", "input_phasor", "output_phasor", "output_var", "n_periods")


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
) -> dict:
    if kind == "frf":
        names = _tok(out=rsp.name, **{"in": ref.name})  # type: ignore[union-attr]
    elif rsp is not None:
        names = _tok(chan=rsp.name)
    else:
        names = "NONE"
    ord_type = {"frf": 8, "input_phasor": 13, "output_phasor": 8, "output_var": 0, "n_periods": 0}
    ord_unit = {"frf": "m", "input_phasor": "N", "output_phasor": "m", "output_var": "m^2", "n_periods": "1"}
    return {
        "type": 58,
        "binary": 1 if binary else 0,
        "func_type": 4 if kind == "frf" else 0,
        "func_id": 0,
        "ver_num": 0,
        "load_case_id": 0,
        "id1": _line("rotorcheck " + _tok(kind=kind)),
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
    recs: list[dict] = []
    for run in sweep.runs.values():
        x = np.asarray(run.frequency, dtype=np.float64)
        if x.size < 2:
            raise ValueError(f"run {run.run_id!r}: UFF58 export (pyuff) needs >= 2 frequency points")
        if include_phasors:
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
        for o, co in enumerate(outs):
            for i, ci in enumerate(ins):
                d = np.asarray(run.frf[:, o, i], dtype=np.complex128)
                recs.append(_record("frf", run, sweep, x, d, co, ci, binary))
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
        out.append(s)
    return out


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
    """
    file = os.fspath(path)
    sets = _load_sets(file)
    groups: dict[str, list[tuple[int, dict]]] = {}
    for i, s in enumerate(sets):
        if int(s.get("func_type", -1)) != 4:
            continue
        tok = _parse(s.get("id2", ""))
        rid = tok.get("run", run_id)
        if rid is None:
            raise SweepFormatError(
                file, f"dataset #{i + 1}/id2", "no run= token; pass run_id to read a foreign file"
            )
        groups.setdefault(rid, []).append((i, s))
    if not groups:
        raise SweepFormatError(file, "/", "no FRF (function type 4) records")
    return {rid: _frf_table(file, rid, recs) for rid, recs in groups.items()}


def _frf_table(file: str, rid: str, recs: list[tuple[int, dict]]) -> FrfTable:
    outs: list[Channel] = []
    ins: list[Channel] = []
    cells: dict[tuple[int, int], np.ndarray] = {}
    x0: np.ndarray | None = None
    speed: float | None = None
    for i, s in recs:
        where = f"dataset #{i + 1}"
        names = _parse(s.get("id5", ""))
        tok = _parse(s.get("id2", ""))
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
        cells[key] = np.asarray(s["data"], dtype=np.complex128)
    assert x0 is not None and speed is not None
    frf = np.empty((x0.size, len(outs), len(ins)), dtype=np.complex128)
    for o in range(len(outs)):
        for i in range(len(ins)):
            if (o, i) not in cells:
                raise SweepFormatError(file, "/", f"run {rid!r}: FRF {outs[o].name}/{ins[i].name} missing")
            frf[:, o, i] = cells[(o, i)]
    return FrfTable(rid, speed, x0, outs, ins, frf)


def import_uff58(
    path: str | os.PathLike[str],
    *,
    generator: str | None = None,
    channels: Sequence[Channel] | None = None,
) -> Sweep:
    """Rebuild a :class:`Sweep` from a file written by :func:`export_uff58` with phasor records.

    Header fields come from the ID lines; ``generator`` defaults to ``"uff58 import of <name>"``.
    ``channels`` (optional) fixes the channel-table order; by default inputs then outputs in
    file order. Raises :class:`SweepFormatError` if the phasor records are missing (then the
    file holds FRFs only: use :func:`read_uff58_frf`).
    """
    file = os.fspath(path)
    sets = _load_sets(file)
    frfs = read_uff58_frf(file)
    meta: dict[str, str] = {}
    per_run: dict[str, dict[str, dict[str, np.ndarray]]] = {}
    for i, s in enumerate(sets):
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
        if kind == "frf":
            continue
        run_ref = _parse(s.get("id2", "")).get("run")
        if run_ref is None or run_ref not in frfs:
            raise SweepFormatError(file, f"{where}/id2", f"run {run_ref!r} has no FRF records")
        chan = _parse(s.get("id5", "")).get("chan", "")
        x = np.asarray(s["x"], dtype=np.float64)
        if not np.array_equal(x, frfs[run_ref].frequency):
            raise SweepFormatError(file, f"{where}/abscissa", "frequency grid differs within run")
        per_run.setdefault(run_ref, {}).setdefault(kind, {})[chan] = np.asarray(s["data"])
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
        rec = per_run.get(rid, {})
        need = ("input_phasor", "output_phasor", "output_var", "n_periods")
        missing = [k for k in need if k not in rec]
        if missing:
            raise SweepFormatError(
                file, "/", f"run {rid!r}: no {missing} records; FRF-only file, use read_uff58_frf"
            )

        def col(kind: str, ch: list[Channel], rid: str = rid, rec: dict = rec) -> np.ndarray:
            try:
                return np.stack([rec[kind][c.name] for c in ch], axis=1)
            except KeyError as exc:
                raise SweepFormatError(
                    file, "/", f"run {rid!r}: {kind} record for channel {exc.args[0]!r} missing"
                ) from None

        oi = [[c.name for c in tab.outputs].index(c.name) for c in outs]
        ii = [[c.name for c in tab.inputs].index(c.name) for c in ins]
        nper = np.asarray(rec["n_periods"][""], dtype=np.float64)
        if np.any(nper != np.round(nper)):
            raise SweepFormatError(file, "/", f"run {rid!r}: n_periods not integer")
        runs[rid] = Run(
            run_id=rid,
            speed_rpm=tab.speed_rpm,
            frequency=tab.frequency,
            input_phasor=col("input_phasor", ins).astype(np.complex128),
            output_phasor=col("output_phasor", outs).astype(np.complex128),
            output_var=np.real(col("output_var", outs)).astype(np.float64),
            n_periods=nper.astype(np.int32),
            frf=tab.frf[:, oi][:, :, ii],
        )
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
