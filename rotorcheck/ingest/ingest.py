"""Time records in, a sweep file out: read the files, join them in time order, analyse, write.

Nothing is written unless the whole analysis succeeds (the sweep writer is atomic); an existing
output is refused unless ``force``.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Sequence

from rotorcheck.errors import InputError
from rotorcheck.fileio import check_writable, file_sha256
from rotorcheck.ingest.analysis import IngestResult, analyse
from rotorcheck.ingest.channel_map import ChannelMap, load_channel_map
from rotorcheck.ingest.readers import open_record
from rotorcheck.ingest.record import TimeRecord, concatenate
from rotorcheck.sweep.hdf5io import write_sweep

__all__ = ["ingest_files", "read_records"]


def read_records(paths: Sequence[str | os.PathLike[str]], cmap: ChannelMap) -> list[TimeRecord]:
    """Open every file (the map's format, group and sample rate) and join them in time order."""
    if not paths:
        raise InputError(None, "RECORD", "no time-record files given")
    recs: list[TimeRecord] = []
    try:
        for p in paths:
            recs.extend(open_record(p, cmap.format, cmap.sample_rate_hz, cmap.group))
        return concatenate(recs)
    except BaseException:
        for r in recs:
            r.close()
        raise


def ingest_files(paths: Sequence[str | os.PathLike[str]], channel_map: ChannelMap | str | os.PathLike[str],
                 out: str | os.PathLike[str] | None = None, force: bool = False) -> IngestResult:
    """Ingest ``paths`` (one sweep, possibly several files) with ``channel_map`` (a map or its YAML
    path) and write the sweep to ``out`` (when given) with its provenance attributes."""
    cmap = channel_map if isinstance(channel_map, ChannelMap) else load_channel_map(channel_map)
    if out is not None:
        check_writable([os.fspath(out)], force)
    sources = [(os.fspath(p), file_sha256(p)) for p in paths if os.path.isfile(p)]
    segments = read_records(paths, cmap)
    with contextlib.ExitStack() as stack:
        for s in segments:
            stack.callback(s.close)
        result = analyse(segments, cmap, sources)
    if out is not None:
        write_sweep(result.sweep, out, force=force, extra_attrs=result.attrs)
    return result
