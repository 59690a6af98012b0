"""Where a fleet's machines, rigs, baselines and sweeps are: a folder layout or a manifest (docs/fleet.md).

Folder layout (``rotorcheck fleet DIR``)::

    DIR/
      <machine>/              one folder per machine (any name without a leading '.' or '_')
        rig.yaml              the machine's rig file
        baseline.h5           its validated baseline (``rotorcheck validate``)
        sweeps/               its sweeps, one HDF5 file each, stamped by time:
          2026-03-01T02-00.h5     time from the name (UTC; see :data:`STAMP`), else the file's
          ...                     root attribute ``measured_utc``, else ``created_utc``
      results/                written by ``rotorcheck fleet`` (not a machine: it has no ``sweeps/``)

Manifest (``rotorcheck fleet fleet.csv`` or ``fleet.yaml``): one row per sweep with the columns
``machine``, ``rig``, ``baseline``, ``sweep`` and optionally ``time`` (ISO 8601, UTC); relative paths are
relative to the manifest's folder. A YAML manifest holds the same rows as a list under ``sweeps:``.

This module is light on purpose (no numpy, no h5py unless a sweep's name carries no time): the
"nothing new" path of a nightly run reads only the folder tree and the results index.
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from rotorcheck.errors import InputError
from rotorcheck.fileio import read_bounded_text

#: the largest fleet manifest read, bytes
MAX_MANIFEST_BYTES = 20_000_000

#: a time stamp in a sweep's file name: 2026-03-01T02-00, 2026-03-01T02-00-30, 2026-03-01T02:00:30Z,
#: 20260301T0200 (read as UTC)
STAMP = re.compile(r"(?P<y>\d{4})-?(?P<mo>\d{2})-?(?P<d>\d{2})[T_ ](?P<h>\d{2})[-:]?(?P<mi>\d{2})"
                   r"(?:[-:]?(?P<s>\d{2}))?")
SWEEP_SUFFIXES = (".h5", ".hdf5")
RIG_FILE = "rig.yaml"
BASELINE_FILE = "baseline.h5"
SWEEPS_DIR = "sweeps"
MANIFEST_COLUMNS = ("machine", "rig", "baseline", "sweep")


@dataclass(frozen=True)
class SweepEntry:
    """One sweep of a machine: its file and its time (ISO 8601 UTC, ``YYYY-MM-DDTHH:MM:SSZ``)."""

    path: Path
    time: str


@dataclass
class Machine:
    """A machine of the fleet: its rig file, its baseline and its sweeps in time order."""

    name: str
    rig: Path
    baseline: Path
    sweeps: list[SweepEntry] = field(default_factory=list)


@dataclass
class Fleet:
    """The fleet as found on disk: machines by name (sorted) and where it came from."""

    source: Path
    machines: list[Machine]


def iso_utc(stamp: dt.datetime) -> str:
    """``stamp`` as ``YYYY-MM-DDTHH:MM:SSZ`` (naive stamps are taken as UTC)."""
    if stamp.tzinfo is not None:
        stamp = stamp.astimezone(dt.timezone.utc).replace(tzinfo=None)
    return stamp.strftime("%Y-%m-%dT%H:%M:%SZ")


def time_from_name(name: str) -> str | None:
    """The time stamp in a file name (UTC), or None when it carries none (or an impossible date)."""
    m = STAMP.search(name)
    if m is None:
        return None
    try:
        t = dt.datetime(int(m["y"]), int(m["mo"]), int(m["d"]), int(m["h"]), int(m["mi"]), int(m["s"] or 0))
    except ValueError:
        return None
    return iso_utc(t)


def parse_time(text: str, file: Path, field_name: str) -> str:
    """An ISO 8601 time (``2026-03-01T02:00``, ``...Z``, ``...+01:00``; or a file-name stamp) as UTC text;
    InputError naming ``file`` and ``field_name`` when it is none."""
    s = text.strip()
    try:
        return iso_utc(dt.datetime.fromisoformat(s.replace("Z", "+00:00")))
    except ValueError:
        pass
    t = time_from_name(s)
    if t is None:
        raise InputError(file, field_name, f"{text!r} is no time (ISO 8601, e.g. 2026-03-01T02:00:00Z)")
    return t


def time_from_file(path: Path) -> str:
    """A sweep's time from its name, else its HDF5 root attribute ``measured_utc`` or ``created_utc``."""
    t = time_from_name(path.name)
    if t is not None:
        return t
    import h5py  # lazy: h5py only for files whose name carries no time

    try:
        with h5py.File(path, "r") as h5:
            for attr in ("measured_utc", "created_utc"):
                v = h5.attrs.get(attr)
                if v is not None and str(v if not isinstance(v, bytes) else v.decode()).strip():
                    text = v.decode() if isinstance(v, bytes) else str(v)
                    return parse_time(text, path, f"/@{attr}")
    except OSError as exc:
        raise InputError(path, "", f"not a readable HDF5 sweep ({exc})") from None
    raise InputError(path, "/@measured_utc", "no time: name the file by its time (e.g. 2026-03-01T02-00.h5) or "
                     "set the root attribute measured_utc")


def _checked_unique(machine: Machine, where: Path) -> None:
    """Two sweeps of one machine at the same time are an error naming both."""
    seen: dict[str, Path] = {}
    for s in machine.sweeps:
        if s.time in seen:
            raise InputError(s.path, "time", f"machine {machine.name!r} has two sweeps at {s.time}: {seen[s.time]} "
                             f"and this one ({where})")
        seen[s.time] = s.path


def discover_dir(root: Path, times: dict[str, str] | None = None, skip: Path | None = None) -> Fleet:
    """The machines of a fleet folder (module docstring). ``times``: known times by sweep path (the results
    index), so that files without a stamp in their name are not opened again; ``skip``: the results folder."""
    if not root.is_dir():
        raise InputError(root, "", "not a folder (a fleet folder or a manifest .csv/.yaml)")
    machines: list[Machine] = []
    skip_r = skip.resolve() if skip is not None and skip.exists() else None
    for entry in sorted(os.scandir(root), key=lambda e: e.name):
        if not entry.is_dir() or entry.name.startswith((".", "_")):
            continue
        folder = Path(entry.path)
        if skip_r is not None and folder.resolve() == skip_r:
            continue
        sweeps_dir = folder / SWEEPS_DIR
        if not sweeps_dir.is_dir():
            continue  # not a machine (e.g. results/)
        rig, base = folder / RIG_FILE, folder / BASELINE_FILE
        for p, what in ((rig, "rig file"), (base, "baseline")):
            if not p.is_file():
                raise InputError(p, "", f"machine {entry.name!r}: its {what} is missing (layout: docs/fleet.md)")
        m = Machine(entry.name, rig, base)
        for f in sorted(os.scandir(sweeps_dir), key=lambda e: e.name):
            if f.is_file() and f.name.lower().endswith(SWEEP_SUFFIXES) and not f.name.startswith("."):
                p = Path(f.path)
                t = (times or {}).get(str(p)) or time_from_file(p)
                m.sweeps.append(SweepEntry(p, t))
        m.sweeps.sort(key=lambda s: (s.time, str(s.path)))
        _checked_unique(m, sweeps_dir)
        machines.append(m)
    if not machines:
        raise InputError(root, "", f"no machine folders (a machine is a folder with {RIG_FILE}, {BASELINE_FILE} and "
                         f"{SWEEPS_DIR}/; docs/fleet.md)")
    return Fleet(root, machines)


def _rows_csv(path: Path) -> list[dict[str, str]]:
    text = read_bounded_text(path, MAX_MANIFEST_BYTES, "fleet manifest").removeprefix("\ufeff")  # Excel's BOM
    reader = csv.DictReader(io.StringIO(text, newline=""))
    try:
        cols = [c.strip() for c in (reader.fieldnames or [])]
        missing = [c for c in MANIFEST_COLUMNS if c not in cols]
        if missing:
            raise InputError(path, f"column {missing[0]!r}", f"missing (a manifest needs the columns "
                             f"{', '.join(MANIFEST_COLUMNS)} and optionally time)")
        return [{(k or "").strip(): (v or "").strip() if isinstance(v, str | None) else "" for k, v in row.items()}
                for row in reader]
    except csv.Error as exc:
        raise InputError(path, f"line {reader.line_num}", f"not CSV: {exc}") from None


def _rows_yaml(path: Path) -> list[dict[str, str]]:
    from rotorcheck.safeload import load_yaml_file  # lazy: yaml only for a YAML manifest

    doc = load_yaml_file(path, MAX_MANIFEST_BYTES, "fleet manifest")
    rows = doc.get("sweeps") if isinstance(doc, dict) else None
    if not isinstance(rows, list):
        raise InputError(path, "sweeps", "missing: a YAML manifest is a list of rows under 'sweeps:' with "
                         f"{', '.join(MANIFEST_COLUMNS)} (and optionally time)")
    out = []
    for i, row in enumerate(rows):
        if not isinstance(row, dict):
            raise InputError(path, f"sweeps[{i}]", "must be a mapping (machine, rig, baseline, sweep, time)")
        out.append({str(k): "" if v is None else str(v) for k, v in row.items()})
    return out


def discover_manifest(path: Path, times: dict[str, str] | None = None) -> Fleet:
    """The machines of a manifest (CSV or YAML, module docstring); every error names the file and the row."""
    if not path.is_file():
        raise InputError(path, "", "no such manifest")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        rows = _rows_csv(path)
        where = "row {n}"  # 1-based data rows (the header is line 1)
    elif suffix in (".yaml", ".yml"):
        rows = _rows_yaml(path)
        where = "sweeps[{i}]"
    else:
        raise InputError(path, "", "a manifest is a .csv or .yaml file (or pass a fleet folder)")
    base_dir = path.parent
    machines: dict[str, Machine] = {}
    for i, row in enumerate(rows):
        loc = where.format(n=i + 2, i=i)
        for c in MANIFEST_COLUMNS:
            if not row.get(c):
                raise InputError(path, f"{loc}: {c}", "missing or empty")
        files = {}
        for c in ("rig", "baseline", "sweep"):
            try:
                p = Path(row[c]).expanduser()
                p = p if p.is_absolute() else base_dir / p
                found = p.is_file()
            except (OSError, RuntimeError, ValueError) as exc:  # a name too long, a NUL byte, no home folder
                raise InputError(path, f"{loc}: {c}", f"unusable path {row[c][:80]!r}: "
                                 f"{getattr(exc, 'strerror', None) or exc}") from None
            if not found:
                raise InputError(path, f"{loc}: {c}", f"no such file {p}")
            files[c] = p
        name = row["machine"]
        m = machines.get(name)
        if m is None:
            m = machines[name] = Machine(name, files["rig"], files["baseline"])
        elif (m.rig, m.baseline) != (files["rig"], files["baseline"]):
            raise InputError(path, f"{loc}: rig/baseline", f"machine {name!r} already has rig {m.rig} and baseline "
                             f"{m.baseline} (one rig and one baseline per machine)")
        t = parse_time(row["time"], path, f"{loc}: time") if row.get("time") else (
            (times or {}).get(str(files["sweep"])) or time_from_file(files["sweep"]))
        m.sweeps.append(SweepEntry(files["sweep"], t))
    if not machines:
        raise InputError(path, "", "no rows")
    for m in machines.values():
        m.sweeps.sort(key=lambda s: (s.time, str(s.path)))
        _checked_unique(m, path)
    return Fleet(path, [machines[k] for k in sorted(machines)])


def discover(source: str | Path, times: dict[str, str] | None = None, skip: Path | None = None) -> Fleet:
    """A fleet from a folder (:func:`discover_dir`) or a manifest (:func:`discover_manifest`)."""
    p = Path(source)
    if p.is_dir():
        return discover_dir(p, times, skip)
    if not p.exists():
        raise InputError(p, "", "no such fleet folder or manifest")
    return discover_manifest(p, times)
