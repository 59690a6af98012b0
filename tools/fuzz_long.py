"""Fuzz every reader of rotorcheck (issue 32): sweep HDF5, baseline, rig YAML, UFF58, tidy and wide CSV, ROSS
TOML (import-ross), fleet manifest (CSV and YAML).

Each input is a seed file mutated with a fixed seed (bit flips, truncation, spans deleted, duplicated or
overwritten, tokens such as ``nan``, ``*a``, ``[`` or a byte-order mark inserted; for HDF5 also attributes
and datasets replaced by wrongly typed ones). Every parse runs in a forked child with a time bound per
input; the outcome of each input is one of

- ``refused``: a documented error (``UserInputError``: InputError, ConfigError, SweepFormatError) whose
  message names the file;
- ``accepted``: the reader returned and its output passed the reader's check (a sweep validates, a
  baseline's numbers are numbers, ...);
- ``other``: anything else (another exception, a refusal not naming the file, a failed output check, a
  hang past the time bound, a crash of the child).

The suite (tests/test_fuzz_readers.py) runs a few inputs per reader and wants ``other == 0``; this script
runs for longer::

    PYTHONPATH=. python tools/fuzz_long.py --seconds 300 [--seed 1] [--timeout 5] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import select
import shutil
import signal
import sys
import tempfile
import time
import traceback
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]

TOKENS = [b"nan", b"NaN", b"inf", b"-inf", b"1e400", b"-0", b"0", b"-1", b"1e308", b"[", b"]", b"{", b"}", b"*a",
          b"&a", b"\xef\xbb\xbf", b",", b"\n", b"\r\n", b'"', b"'", b":", b"- ", b"\x00", b"\xff", b"=", b"#",
          b"/", b"..", b"    -1\n", b"58b", b"99999999999", b"\t", b" "]


# --------------------------------------------------------------------------------------------
# seeds


def make_seeds(folder: Path) -> dict[str, list[Path]]:
    """Seed files of every reader in ``folder`` (built from the bundled samples)."""
    import numpy as np

    from rotorcheck.baseline import Baseline, HealthyData, ModelBound, NoiseFit, Provenance, write_baseline
    from rotorcheck.resources import configs_dir, samples_dir
    from rotorcheck.sweep import read_sweep
    from rotorcheck.sweep.convert import ConvertOptions, read_any, write_any

    folder.mkdir(parents=True, exist_ok=True)
    h5 = samples_dir() / "crack_rig" / "healthy_0rpm.h5"
    shutil.copy(h5, folder / "sweep.h5")
    sw = read_sweep(h5)
    write_any(sw, folder / "own.uff", "uff", ConvertOptions(force=True))
    write_any(sw, folder / "ascii.uff", "uff", ConvertOptions(force=True, ascii=True))
    write_any(sw, folder / "tidy.csv", "csv", ConvertOptions(force=True))
    write_any(sw, folder / "wide.csv", "wide", ConvertOptions(force=True))
    assert read_any(folder / "tidy.csv", "csv", ConvertOptions()) is not None
    (run,) = sw.runs.values()
    f = np.asarray(run.frequency)
    frf = np.asarray(run.frf[:, :, 0])
    base = Baseline(
        Provenance(sw.rig_id, "0" * 64, ["1" * 64], run.run_id, float(run.speed_rpm), "2026-01-01T00:00:00Z"),
        NoiseFit(1e-7, "pooled", 0.99, None, "additive", ""),
        ModelBound("measured", "additive", "", f, np.full(f.size, 1e-8), frf[:, :, None], np.zeros(f.size),
                   np.array(["ok"] * f.size)),
        HealthyData(frf, np.full(frf.shape, 1e-16), np.full(frf.shape, 10.0)))
    write_baseline(base, folder / "baseline.h5")
    shutil.copy(configs_dir() / "crack_rig.yaml", folder / "rig.yaml")
    ross = sorted((REPO / "tests" / "data" / "ross").glob("*.toml"))
    for p in ross[:3]:
        shutil.copy(p, folder / p.name)
    row = "m1,rig.yaml,baseline.h5,sweep.h5,2026-01-01T00:00:00Z\n"
    (folder / "fleet.csv").write_text("machine,rig,baseline,sweep,time\n" + row + row.replace("01T", "02T"))
    (folder / "fleet.yaml").write_text("sweeps:\n- {machine: m1, rig: rig.yaml, baseline: baseline.h5, sweep: "
                                       "sweep.h5, time: '2026-01-01T00:00:00Z'}\n- machine: m2\n  rig: rig.yaml\n"
                                       "  baseline: baseline.h5\n  sweep: sweep.h5\n")
    return {
        "sweep_hdf5": [folder / "sweep.h5"],
        "baseline": [folder / "baseline.h5"],
        "rig_yaml": [folder / "rig.yaml"],
        "uff58": [folder / "own.uff", folder / "ascii.uff"],
        "tidy_csv": [folder / "tidy.csv"],
        "wide_csv": [folder / "wide.csv"],
        "ross_toml": [folder / p.name for p in ross[:3]],
        "manifest_csv": [folder / "fleet.csv"],
        "manifest_yaml": [folder / "fleet.yaml"],
    }


# --------------------------------------------------------------------------------------------
# readers and their output checks


def _check_sweep(sw: Any) -> None:
    import numpy as np

    from rotorcheck.sweep.validation import validate_sweep

    validate_sweep(sw, "<fuzz>")
    for run in sw.runs.values():
        assert np.all(np.isfinite(run.frequency)) and np.all(np.diff(run.frequency) > 0)


def _read_sweep(p: Path) -> Any:
    from rotorcheck.sweep import read_sweep

    return read_sweep(p)


def _read_baseline(p: Path) -> Any:
    from rotorcheck.baseline import read_baselines

    return read_baselines(p)


def _check_baselines(bs: Any) -> None:
    import math

    for b in bs:
        assert isinstance(b.rig_id, str) and isinstance(b.stage, str) and isinstance(b.run_id, str)
        for v in (b.speed_rpm, b.noise_bound_m, b.noise_confidence):
            assert isinstance(v, float)
        assert math.isfinite(b.noise_bound_m) and b.noise_bound_m >= 0


def _read_rig(p: Path) -> Any:
    from rotorcheck.config import load_config

    return load_config(p)


def _check_rig(cfg: Any) -> None:
    from rotorcheck.config import RigConfig

    assert isinstance(cfg, RigConfig)


def _convert_reader(fmt: str) -> Callable[[Path], Any]:
    def read(p: Path) -> Any:
        from rotorcheck.sweep.convert import ConvertOptions, read_any

        return read_any(p, fmt, ConvertOptions())

    return read


def _read_ross(p: Path) -> Any:
    from rotorcheck.ross_import import import_ross

    return import_ross(p)


def _check_ross(res: Any) -> None:
    assert isinstance(res.rig, dict) and isinstance(res.rig["rig_id"], str) and isinstance(res.to_yaml(), str)


def _read_manifest(p: Path) -> Any:
    from rotorcheck.fleet.layout import discover_manifest

    return discover_manifest(p)


def _check_manifest(fleet: Any) -> None:
    assert fleet.machines and all(m.sweeps for m in fleet.machines)


@dataclass
class Reader:
    read: Callable[[Path], Any]
    check: Callable[[Any], None]
    binary: bool  # HDF5: binary mutations (and attribute edits)
    hdf5: bool = False
    companions: tuple[str, ...] = field(default=())  # files beside the input, copied with it (suffixes)


READERS: dict[str, Reader] = {
    "sweep_hdf5": Reader(_read_sweep, _check_sweep, True, hdf5=True),
    "baseline": Reader(_read_baseline, _check_baselines, True, hdf5=True),
    "rig_yaml": Reader(_read_rig, _check_rig, False),
    "uff58": Reader(_convert_reader("uff"), _check_sweep, True),
    "tidy_csv": Reader(_convert_reader("csv"), _check_sweep, False, companions=(".columns.yaml",)),
    "wide_csv": Reader(_convert_reader("wide"), _check_sweep, False, companions=(".columns.yaml",)),
    "ross_toml": Reader(_read_ross, _check_ross, False),
    "manifest_csv": Reader(_read_manifest, _check_manifest, False),
    "manifest_yaml": Reader(_read_manifest, _check_manifest, False),
}


# --------------------------------------------------------------------------------------------
# mutations


def mutate_bytes(data: bytes, rng: random.Random, binary: bool) -> bytes:
    """One to four random edits of ``data``."""
    b = bytearray(data)
    for _ in range(rng.choice([1, 1, 2, 4])):
        op = rng.choice(["flip", "flip", "trunc", "delete", "dup", "overwrite", "token", "token", "repeat"]
                        if not binary else ["flip", "flip", "flip", "trunc", "zero", "overwrite", "dup", "token"])
        n = len(b)
        if n == 0:
            b += rng.choice(TOKENS)
            continue
        i = rng.randrange(n)
        span = rng.choice([1, 2, 8, 64, 512])
        if op == "flip":
            for _ in range(rng.choice([1, 2, 8, 32])):
                k = rng.randrange(n)
                b[k] ^= 1 << rng.randrange(8)
        elif op == "trunc":
            del b[rng.randrange(n):]
        elif op == "delete":
            del b[i:i + span]
        elif op == "dup":
            b[i:i] = b[i:i + span] * rng.choice([1, 2, 50])
        elif op == "zero":
            b[i:i + span] = bytes(len(b[i:i + span]))
        elif op == "overwrite":
            b[i:i + span] = bytes(rng.randrange(256) for _ in range(len(b[i:i + span])))
        elif op == "token":
            if not binary and rng.random() < 0.5:  # replace a number-like word
                j = b.find(b",", i) if rng.random() < 0.5 else b.find(b" ", i)
                j = n if j < 0 else j
                b[i:j] = rng.choice(TOKENS)
            else:
                b[i:i] = rng.choice(TOKENS)
        elif op == "repeat":
            start = b.rfind(b"\n", 0, i) + 1
            end = b.find(b"\n", i)
            end = n if end < 0 else end + 1
            b[end:end] = b[start:end] * rng.choice([2, 20, 1000])
    return bytes(b)


def mutate_hdf5(path: Path, rng: random.Random) -> None:
    """Replace, delete or retype attributes and datasets of an HDF5 file in place."""
    import h5py
    import numpy as np

    values: list[Any] = [np.nan, np.inf, -1, 0, 2**40, "text", b"\xff\xfe", np.arange(3), np.zeros((2, 2)),
                         np.array([b"a", b"b"]), True, 1.5, np.array([1 + 2j]), np.zeros(0), np.ones(10**5)]
    with h5py.File(path, "r+") as h5:
        items: list[tuple[Any, str, bool]] = []
        h5.visititems(lambda name, obj: items.append((obj, name, isinstance(obj, h5py.Dataset))))
        groups = [h5] + [o for o, _, ds in items if not ds]
        for _ in range(rng.choice([1, 2, 3])):
            if rng.random() < 0.5:
                g = rng.choice(groups)
                names = list(g.attrs)
                if not names:
                    continue
                name = rng.choice(names)
                if rng.random() < 0.2:
                    del g.attrs[name]
                else:
                    g.attrs[name] = rng.choice(values)
            else:
                dsets = [(o, n) for o, n, ds in items if ds]
                if not dsets:
                    continue
                _, name = rng.choice(dsets)
                if name not in h5:
                    continue
                del h5[name]
                if rng.random() < 0.8:
                    v = rng.choice(values)
                    h5.create_group(name) if isinstance(v, str) and v == "text" and rng.random() < 0.3 else \
                        h5.create_dataset(name, data=v)


def make_input(reader: str, seeds: list[Path], index: int, seed: int, work: Path) -> Path:
    """The ``index``-th input of ``reader``: a copy of a seed (with its companions) mutated deterministically."""
    rng = random.Random(f"{seed}:{reader}:{index}")
    src = rng.choice(seeds)
    r = READERS[reader]
    dst = work / f"{reader}_{index}{src.suffix}"
    for suffix in r.companions:
        comp = src.with_name(src.stem + suffix)
        if comp.exists():
            shutil.copy(comp, dst.with_name(dst.stem + suffix))
    for name in ("rig.yaml", "baseline.h5", "sweep.h5"):  # what a manifest names
        if reader.startswith("manifest") and not (work / name).exists():
            shutil.copy(src.parent / name, work / name)
    data = src.read_bytes()
    if r.hdf5 and rng.random() < 0.4:
        dst.write_bytes(data)
        try:
            mutate_hdf5(dst, rng)
        except Exception:  # h5py refused the edit: fall back to byte mutations
            dst.write_bytes(mutate_bytes(data, rng, True))
    else:
        dst.write_bytes(mutate_bytes(data, rng, r.binary))
    return dst


# --------------------------------------------------------------------------------------------
# running (forked children, a time bound per input)


def classify(reader: str, path: Path) -> tuple[str, str]:
    """``(outcome, detail)`` of reading ``path`` with ``reader`` in this process."""
    from rotorcheck.errors import UserInputError

    r = READERS[reader]
    try:
        out = r.read(path)
    except UserInputError as exc:
        text = str(exc)
        named = str(path) in text or path.name in text or str(path.with_name(path.stem + ".columns.yaml")) in text
        return ("refused", text[:300]) if named else ("other", f"refusal not naming the file: {text[:300]}")
    except BaseException as exc:
        if isinstance(exc, KeyboardInterrupt):
            raise
        frame = traceback.extract_tb(exc.__traceback__)[-1]
        return "other", f"{type(exc).__name__} at {Path(frame.filename).name}:{frame.lineno} {frame.name}: " \
                        f"{str(exc)[:200]}"
    try:
        r.check(out)
    except BaseException as exc:
        return "other", f"accepted, but the output check failed: {type(exc).__name__}: {str(exc)[:200]}"
    return "accepted", ""


def _child(reader: str, seeds: list[Path], start: int, stop: int, seed: int, work: Path, fd: int) -> None:
    import warnings

    warnings.simplefilter("ignore")
    for i in range(start, stop):
        os.write(fd, json.dumps({"i": i, "start": True}).encode() + b"\n")
        path = make_input(reader, seeds, i, seed, work)
        outcome, detail = classify(reader, path)
        os.write(fd, json.dumps({"i": i, "outcome": outcome, "detail": detail}).encode() + b"\n")
        with_companions = [path] + [path.with_name(path.stem + s) for s in READERS[reader].companions]
        for p in with_companions:
            p.unlink(missing_ok=True)


@dataclass
class Result:
    counts: Counter[str] = field(default_factory=Counter)
    others: list[tuple[str, int, str]] = field(default_factory=list)
    per_reader: dict[str, Counter[str]] = field(default_factory=dict)

    @property
    def inputs(self) -> int:
        return sum(self.counts.values())

    def add(self, reader: str, i: int, outcome: str, detail: str) -> None:
        self.counts[outcome] += 1
        self.per_reader.setdefault(reader, Counter())[outcome] += 1
        if outcome == "other":
            self.others.append((reader, i, detail))


def run_reader(reader: str, seeds: list[Path], start: int, stop: int, seed: int, work: Path, timeout: float,
               result: Result, keep: Path | None = None) -> None:
    """Inputs ``start..stop-1`` of ``reader`` in forked children; a child past ``timeout`` on one input is
    killed, that input counted as a hang, and a new child goes on with the next."""
    i = start
    while i < stop:
        rfd, wfd = os.pipe()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            os.close(rfd)
            code = 0
            try:
                _child(reader, seeds, i, stop, seed, work, wfd)
            except BaseException:
                code = 3
            os._exit(code)
        os.close(wfd)
        buf = b""
        current: int | None = None
        began = time.monotonic()
        done_upto = i
        with os.fdopen(rfd, "rb", buffering=0) as pipe:
            while True:
                left = timeout - (time.monotonic() - began)
                ready, _, _ = select.select([pipe], [], [], max(left, 0.0))
                if not ready:  # the current input ran past the bound
                    os.kill(pid, signal.SIGKILL)
                    os.waitpid(pid, 0)
                    assert current is not None
                    result.add(reader, current, "other", f"hang: more than {timeout:g} s")
                    if keep is not None:
                        keep.mkdir(parents=True, exist_ok=True)
                        make_input(reader, seeds, current, seed, keep)
                    done_upto = current + 1
                    break
                chunk = pipe.read(65536)
                if not chunk:  # the child ended
                    _, status = os.waitpid(pid, 0)
                    if current is not None and done_upto <= current:  # died inside an input
                        result.add(reader, current, "other", f"crash: child exit status {status}")
                        done_upto = current + 1
                    break
                buf += chunk
                while b"\n" in buf:
                    line, buf = buf.split(b"\n", 1)
                    msg = json.loads(line)
                    if msg.get("start"):
                        current, began = msg["i"], time.monotonic()
                    else:
                        result.add(reader, msg["i"], msg["outcome"], msg["detail"])
                        done_upto = msg["i"] + 1
                        if msg["outcome"] == "other" and keep is not None:
                            keep.mkdir(parents=True, exist_ok=True)
                            make_input(reader, seeds, msg["i"], seed, keep)
        if done_upto == i:  # the child died before its first input
            result.add(reader, i, "other", "crash: the child died before reading")
            done_upto = i + 1
        i = done_upto


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=300.0, help="run this long (rounds over every reader)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=5.0, help="bound per input, s")
    ap.add_argument("--batch", type=int, default=50, help="inputs per reader per round")
    ap.add_argument("--readers", default=",".join(READERS))
    ap.add_argument("--keep", type=Path, default=None, help="keep every 'other' input here")
    args = ap.parse_args(argv)
    readers = [r for r in args.readers.split(",") if r]
    result = Result()
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp:
        seeds = make_seeds(Path(tmp) / "seeds")
        work = Path(tmp) / "work"
        work.mkdir()
        start = 0
        while time.monotonic() - t0 < args.seconds:
            for reader in readers:
                run_reader(reader, seeds[reader], start, start + args.batch, args.seed, work, args.timeout, result,
                           args.keep)
            start += args.batch
    doc = {"seconds": round(time.monotonic() - t0, 1), "seed": args.seed, "inputs": result.inputs,
           "refused": result.counts["refused"], "accepted": result.counts["accepted"],
           "other": result.counts["other"], "per_reader": {k: dict(v) for k, v in result.per_reader.items()},
           "others": [f"{r} #{i}: {d}" for r, i, d in result.others[:50]]}
    print(json.dumps(doc, indent=1))
    return 0 if not result.others else 1


if __name__ == "__main__":
    sys.exit(main())
