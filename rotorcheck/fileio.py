"""Atomic writes and the no-silent-overwrite rule for every output rotorcheck produces.

One writer for the whole package: :func:`atomic_path` creates a temporary file in the target's
folder, hands it to the caller, then fsyncs it and moves it onto the target. The temporary file is
created with mode ``0o666`` through ``O_CREAT | O_EXCL``, so the kernel applies the umask (and any
default ACL of the folder) exactly as for a plain ``open(path, "w")``; the umask is never read by
flipping it, so no process-wide state changes.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import errno
import hashlib
import json
import os
import secrets
import shutil
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from rotorcheck.errors import InputError, OutputExistsError

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_text", "check_hdf5_global_heaps",
           "check_output_place", "check_replaceable", "check_writable", "claim_outputs", "file_sha256",
           "hdf5_attr_problem", "hdf5_vlen_problem", "output_error", "publish_dir", "read_bounded_text",
           "record_outputs", "release_claims", "remove_stale_outputs", "temp_dir_beside"]

_CREATE_ATTEMPTS = 100


def check_writable(paths: Iterable[str | Path], force: bool) -> None:
    """Refuse (before any work is done) when an output exists and ``force`` is false, or (even with
    ``force``) when an output is a folder or a file stands where its folder should be."""
    outs = [Path(p) for p in paths]
    for p in outs:
        check_output_place(p)
    existing = [str(p) for p in outs if p.exists()]
    if existing and not force:
        raise OutputExistsError(
            existing[0], "", "exists; refusing to overwrite (use --force)"
            + (f" [{len(existing) - 1} more outputs exist]" if len(existing) > 1 else "")
        )


_OUTPUT_REASONS = {
    errno.EACCES: "no permission to write here", errno.EPERM: "no permission to write here",
    errno.EROFS: "the file system is read-only", errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "the disk quota is exceeded", errno.EISDIR: "is a folder, not a file",
    errno.ENOTDIR: "a part of the path is a file, not a folder", errno.EEXIST: "a part of the path is a file, not a "
    "folder", errno.EFBIG: "the file is too large for this file system",
}


def output_error(path: str | Path, exc: OSError) -> InputError:
    """An output that cannot be written (``exc``) as an InputError naming ``path`` (exit 2, no traceback)."""
    target = Path(path)
    code = exc.errno
    if code is None and "errno = 28" in str(exc):  # HDF5 reports a full disk inside its message
        code = errno.ENOSPC
    try:
        check_output_place(target)
    except InputError as place:
        return place
    reason = _OUTPUT_REASONS.get(code) if code is not None else None
    return InputError(target, "output", f"cannot write: {reason or exc.strerror or exc}")


def check_output_place(path: str | Path) -> None:
    """An InputError naming ``path`` when it is a folder, or naming the file that stands where one of its
    folders should be (a file at ``--out``)."""
    target = Path(path)
    if target.is_dir():
        raise InputError(target, "output", _OUTPUT_REASONS[errno.EISDIR])
    blocking = next((p for p in target.parents if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise InputError(blocking, "output folder", "is a file, not a folder")


def _refusal(target: str) -> FileExistsError:
    return FileExistsError(f"{target}: exists; refusing to overwrite (pass force=True / --force)")


def _create_temp(target: Path) -> Path:
    """Create an empty, new temp file next to ``target`` with the mode ``open()`` would give."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    for _ in range(_CREATE_ATTEMPTS):
        tmp = target.parent / f".{target.name}.{secrets.token_hex(6)}.tmp"
        try:
            fd = os.open(tmp, flags, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(f"{target}: no free temporary file name in {target.parent}")


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(folder: Path) -> None:
    """Make a rename durable; silently skipped where folders cannot be opened or synced."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _publish(tmp: Path, target: Path, overwrite: bool) -> None:
    """Move the finished ``tmp`` onto ``target``; without ``overwrite`` never replace a file."""
    if overwrite:
        os.replace(tmp, target)
        return
    try:
        os.link(tmp, target)  # atomic create-if-absent
    except FileExistsError:
        raise _refusal(os.fspath(target)) from None
    except OSError:
        # file system without hard links: best-effort check, then rename
        if target.exists():
            raise _refusal(os.fspath(target)) from None
        os.replace(tmp, target)
    else:
        tmp.unlink()


def temp_dir_beside(final: str | os.PathLike[str]) -> Path:
    """A new empty folder ``.<name>.<token>.tmp`` beside ``final`` (its parents created), to build a
    folder's content in before :func:`publish_dir`."""
    final = Path(final)
    final.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(_CREATE_ATTEMPTS):
        tmp = final.parent / f".{final.name}.{secrets.token_hex(6)}.tmp"
        try:
            tmp.mkdir()
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(f"{final}: no free temporary folder name in {final.parent}")


def publish_dir(tmp: str | os.PathLike[str], final: str | os.PathLike[str], replace: bool = False) -> bool:
    """Rename the finished folder ``tmp`` onto ``final`` (atomic on one file system, made durable): a folder
    exists complete or not at all. ``replace``: an existing ``final`` is moved aside and removed first.
    Returns False, ``tmp`` removed, when a ``final`` another writer published is in the way."""
    tmp, final = Path(tmp), Path(final)
    if replace and final.exists():
        trash = final.parent / f".{final.name}.{secrets.token_hex(4)}.old"
        with contextlib.suppress(OSError):
            os.replace(final, trash)
            shutil.rmtree(trash, ignore_errors=True)
    try:
        os.replace(tmp, final)
    except OSError:
        if final.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
            return False
        raise
    _fsync_dir(final.parent)
    return True


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, overwrite: bool = True) -> Iterator[Path]:
    """Yield a new empty temp file in the target's folder; on success it becomes ``path``.

    The target's folder is created if missing. On success the temp file is fsynced and renamed
    onto ``path`` (then the folder is fsynced); on error it is removed and ``path`` is untouched.
    With ``overwrite=False`` an existing ``path`` raises ``FileExistsError`` before any work and
    the publish step never replaces a file that appeared meanwhile.
    """
    target = Path(path)
    if not overwrite and target.exists():
        raise _refusal(os.fspath(path))
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = _create_temp(target)
    except OSError as exc:
        raise output_error(target, exc) from exc
    try:
        yield tmp
        _fsync_file(tmp)
        _publish(tmp, target, overwrite)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError) and not isinstance(exc, FileExistsError):
            raise output_error(target, exc) from exc  # a full disk, a folder in the way, no permission
        raise
    _fsync_dir(target.parent)


def atomic_write_text(path: str | os.PathLike[str], text: str, *, overwrite: bool = True) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(text, encoding="utf-8")


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes, *, overwrite: bool = True) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_bytes(data)


# --------------------------------------------------------------------------------------------
# outputs the tool wrote itself (a manifest in the output folder)

MANIFEST_NAME = ".rotorcheck-manifest.json"


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 hex digest of a file's bytes (read in 1 MiB chunks)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _manifest(folder: Path, section: str = "files") -> dict[str, str]:
    """``{file name: sha256}`` of the outputs rotorcheck wrote in ``folder`` (``section="commands"``: ``{file
    name: the command that wrote it}``); empty when none or unreadable."""
    try:
        data = json.loads((folder / MANIFEST_NAME).read_text())
    except (OSError, ValueError):
        return {}
    files = data.get(section) if isinstance(data, dict) else None
    return {str(k): str(v) for k, v in files.items()} if isinstance(files, dict) else {}


def _write_manifest(folder: Path, files: dict[str, str], commands: dict[str, str]) -> None:
    doc = {"schema": "rotorcheck.outputs", "note": "files rotorcheck wrote here; it replaces them on a later run "
           "only while unchanged", "files": dict(sorted(files.items())),
           "commands": dict(sorted((k, v) for k, v in commands.items() if k in files))}
    atomic_write_text(folder / MANIFEST_NAME, json.dumps(doc, indent=1) + "\n")


def check_replaceable(paths: Iterable[str | Path], force: bool) -> None:
    """Like :func:`check_writable`, but an existing output that rotorcheck wrote itself (listed in
    its folder's manifest, unchanged since) may be replaced; any other existing file is refused
    without ``force``."""
    outs = [Path(p) for p in paths]
    for p in outs:
        check_output_place(p)
    if force:
        return
    blocked: list[str] = []
    for p in outs:
        if not p.exists():
            continue
        known = _manifest(p.parent).get(p.name)
        if known is None or not p.is_file() or file_sha256(p) != known:
            blocked.append(str(p))
    if blocked:
        raise OutputExistsError(
            blocked[0], "", "exists and is not an unchanged output of an earlier rotorcheck run here; refusing to "
            "overwrite (use --force)" + (f" [{len(blocked) - 1} more]" if len(blocked) > 1 else "")
        )


def record_outputs(paths: Iterable[str | Path], command: str | None = None) -> None:
    """Add written outputs (name and sha256; ``command``: the command that wrote them) to the manifest of
    their folder (atomic)."""
    by_folder: dict[Path, list[Path]] = {}
    for p in map(Path, paths):
        by_folder.setdefault(p.parent, []).append(p)
    for folder, files in by_folder.items():
        entries = _manifest(folder)
        entries.update({f.name: file_sha256(f) for f in files})
        commands = _manifest(folder, "commands")
        for f in files:
            if command is not None:
                commands[f.name] = command
            else:
                commands.pop(f.name, None)
        _write_manifest(folder, entries, commands)


def remove_stale_outputs(folders: Iterable[str | Path], command: str, kept: Iterable[str | Path]) -> list[Path]:
    """After a forced run of ``command``: remove the files an earlier run of the same command wrote in
    ``folders`` (per their manifests, unchanged since) that this run did not rewrite (``kept``); never a
    file rotorcheck did not write, one another command wrote, or one changed since. Returns what went."""
    keep = {Path(p).resolve() for p in kept}
    gone: list[Path] = []
    for folder in dict.fromkeys(map(Path, folders)):
        files, commands = _manifest(folder), _manifest(folder, "commands")
        for name, cmd in commands.items():
            p = folder / name
            if cmd != command or p.resolve() in keep or "/" in name or name.startswith("."):
                continue
            with contextlib.suppress(OSError):
                if p.is_file() and file_sha256(p) == files.get(name):
                    p.unlink()
                    gone.append(p)
        if gone:
            _write_manifest(folder, {k: v for k, v in files.items() if (folder / k) not in gone}, commands)
    return gone


# --------------------------------------------------------------------------------------------
# claims: one run at a time writes an output


CLAIM_SUFFIX = ".rotorcheck-claim"
_ACTIVE_CLAIMS: list[Path] = []
_MADE_DIRS: list[Path] = []


def _claim_path(target: Path) -> Path:
    return target.parent / f".{target.name}{CLAIM_SUFFIX}"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def claim_outputs(paths: Iterable[str | Path], force: bool, command: str, fresh: Iterable[str | Path] = ()) -> None:
    """Claim every output of this run before the work: a claim file beside each (``O_CREAT | O_EXCL``: one
    run wins), holding the run's command, pid and start. A path another live run holds is refused naming
    that run (a claim whose process is gone is taken over). Then ``fresh`` (the outputs that must not exist
    without ``force``) are checked again: one another run published after this run's first check is refused.
    :func:`release_claims` (the CLI calls it when the command ends) removes the claims."""
    outs = [Path(p) for p in paths]
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    doc = json.dumps({"command": command, "pid": os.getpid(), "started_utc": stamp}).encode()
    try:
        for target in outs:
            check_output_place(target)
            if not target.parent.exists():
                missing = [d for d in [target.parent, *target.parent.parents] if not d.exists()]
                target.parent.mkdir(parents=True, exist_ok=True)
                _MADE_DIRS.extend(missing)
            claim = _claim_path(target)
            for attempt in range(2):
                try:
                    fd = os.open(claim, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
                except FileExistsError:
                    holder = _claim_holder(claim)
                    if attempt == 0 and not _alive(int(holder.get("pid", -1))):
                        with contextlib.suppress(FileNotFoundError):
                            claim.unlink()  # a run that died without releasing
                        continue
                    who = (f"{holder.get('command', '?')}, pid {holder.get('pid', '?')}, started "
                           f"{holder.get('started_utc', '?')}")
                    raise InputError(target, "", f"being written by another rotorcheck run ({who}); refusing to "
                                     "write it too (wait for that run, or use another --out)") from None
                _ACTIVE_CLAIMS.append(claim)
                try:
                    os.write(fd, doc)
                finally:
                    os.close(fd)
                break
    except OSError as exc:
        release_claims()
        raise output_error(exc.filename or outs[0], exc) from exc
    except BaseException:
        release_claims()
        raise
    try:
        check_writable(fresh, force)
    except BaseException:
        release_claims()
        raise


def _claim_holder(claim: Path) -> dict[str, Any]:
    try:
        data = json.loads(claim.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def release_claims() -> None:
    """Remove this process's claims (and the folders a claim created that stayed empty)."""
    while _ACTIVE_CLAIMS:
        with contextlib.suppress(OSError):
            _ACTIVE_CLAIMS.pop().unlink()
    while _MADE_DIRS:
        with contextlib.suppress(OSError):
            _MADE_DIRS.pop(0).rmdir()  # only while empty; the deepest first


# --------------------------------------------------------------------------------------------
# reading a text input of bounded size


def read_bounded_text(
    path: str | Path, max_bytes: int, what: str,
    error: Callable[[str | Path, str, str], Exception] = InputError,
) -> str:
    """The UTF-8 text of ``path`` (a ``what``, e.g. "rig file"), refused before parsing when it is
    missing, unreadable, a folder, over ``max_bytes``, not UTF-8 or holding a NUL byte; ``error(file,
    field, message)`` builds the exception (an :class:`~rotorcheck.errors.InputError` by default)."""
    p = Path(path)
    try:
        if p.is_file() and p.stat().st_size > max_bytes:
            raise error(p, "", f"{p.stat().st_size} bytes: a {what} is at most {max_bytes} bytes")
        with open(p, "rb") as fh:
            raw = fh.read(max_bytes + 1)
    except FileNotFoundError:
        raise error(p, "", "file not found") from None
    except IsADirectoryError:
        raise error(p, "", f"is a folder, not a {what}") from None
    except OSError as exc:
        raise error(p, "", f"cannot read: {exc.strerror or exc}") from None
    if len(raw) > max_bytes:
        raise error(p, "", f"more than {max_bytes} bytes: a {what} is at most that")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(p, "", f"not UTF-8 text (byte {exc.start}): save the {what} as UTF-8") from None
    if "\x00" in text:
        raise error(p, "", "a NUL byte: this is no text file")
    return text


# --------------------------------------------------------------------------------------------
# HDF5 global heaps checked before the HDF5 library reads them


def check_hdf5_global_heaps(
    path: str | Path, error: Callable[[str | Path, str, str], Exception] = InputError,
) -> dict[int, dict[int, int]]:
    """Refuse an HDF5 file whose global heap collections (``GCOL``: where variable-length strings live) do
    not parse: the HDF5 library loops without end on some such files (a bit flip in an object's size), so
    they are walked here first, object by object, each within its collection and the free space filling
    the rest exactly. ``error(file, field, message)`` builds the exception. Returns the collections found:
    ``{file offset: {object index: size}}`` (for :func:`hdf5_vlen_problem`)."""
    import mmap  # lazy: mmap only to walk an HDF5 file's global heaps

    p = Path(path)
    heaps: dict[int, dict[int, int]] = {}
    try:
        with open(p, "rb") as fh:
            if os.fstat(fh.fileno()).st_size == 0:
                return heaps
            with mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
                n = len(mm)
                pos = mm.find(b"GCOL")
                while pos >= 0:
                    if pos + 16 <= n and mm[pos + 4] == 1 and mm[pos + 5:pos + 8] == b"\0\0\0":
                        objects: dict[int, int] = {}
                        problem = _heap_problem(mm, pos, n, objects)
                        if problem:
                            raise error(p, f"byte {pos}", f"corrupt HDF5 global heap: {problem}")
                        heaps[pos] = objects
                    pos = mm.find(b"GCOL", pos + 4)
    except OSError as exc:
        raise error(p, "", f"cannot read: {exc.strerror or exc}") from None
    return heaps


def _heap_problem(mm: Any, pos: int, n: int, objects: dict[int, int]) -> str:
    size = int.from_bytes(mm[pos + 8:pos + 16], "little")
    end = pos + size
    if size < 4096 or end > n:
        return f"collection size {size} (at least 4096, within the file of {n} bytes)"
    p = pos + 16
    while end - p >= 16:
        idx = int.from_bytes(mm[p:p + 2], "little")
        size = int.from_bytes(mm[p + 8:p + 16], "little")
        if idx == 0:  # the free space: the rest of the collection exactly
            return "" if size == end - p else f"free space of {size} bytes where {end - p} remain"
        if idx in objects:
            return f"object {idx} twice"
        objects[idx] = size
        p += 16 + (size + 7) // 8 * 8
        if p > end:
            return f"object {idx} of {size} bytes runs past the collection"
    return ""


def hdf5_vlen_problem(raw: bytes, heaps: dict[int, dict[int, int]], base: int = 0) -> str:
    """What is wrong with the variable-length descriptors ``raw`` of a dataset (16 bytes each: length,
    collection address, object index) given the file's global heaps, else "" (HDF5 spends seconds on a
    descriptor pointing past the file)."""
    for k in range(len(raw) // 16):
        length = int.from_bytes(raw[16 * k:16 * k + 4], "little")
        addr = int.from_bytes(raw[16 * k + 4:16 * k + 12], "little")
        idx = int.from_bytes(raw[16 * k + 12:16 * k + 16], "little")
        if length == 0 and addr == 0:
            continue
        objects = heaps.get(addr + base)
        if objects is None:
            return f"element {k} refers to no global heap (address {addr})"
        if idx not in objects or objects[idx] < length:
            return f"element {k} refers to no object {idx} of {length} bytes in the heap at {addr}"
    return ""


def hdf5_attr_problem(obj: Any, name: str) -> str:
    """What makes the attribute ``name`` of the h5py object ``obj`` unsafe to read, else "": only text and
    plain integers/floats with a sane layout are read (a corrupt datatype message, e.g. an integer whose
    offset and precision exceed its size, or a variable-length sequence, crashed libhdf5 with SIGSEGV)."""
    import h5py  # lazy: h5py only for HDF5 attributes (this base module loads without it)

    try:
        t = obj.attrs.get_id(name).get_type()
    except (KeyError, OSError, RuntimeError, ValueError) as exc:
        return f"unreadable attribute ({exc})"
    if isinstance(t, h5py.h5t.TypeStringID):
        return ""
    if isinstance(t, h5py.h5t.TypeEnumID):  # h5py's booleans: an enum over a plain integer
        t = t.get_super()
    if isinstance(t, h5py.h5t.TypeIntegerID | h5py.h5t.TypeFloatID):
        size, bits = t.get_size(), 8 * t.get_size()
        if size not in (1, 2, 4, 8) or t.get_offset() + t.get_precision() > bits:
            return f"corrupt number type (size {size}, offset {t.get_offset()}, precision {t.get_precision()})"
        if isinstance(t, h5py.h5t.TypeFloatID):
            spos, epos, esize, mpos, msize = t.get_fields()
            if max(spos + 1, epos + esize, mpos + msize) > bits or not 0 < esize < bits or not 0 < msize < bits:
                return f"corrupt float type (fields {spos, epos, esize, mpos, msize} in {bits} bits)"
        return ""
    return f"a {type(t).__name__.removeprefix('Type').removesuffix('ID')} attribute: only text or a number is read"
