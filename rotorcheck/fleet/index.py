"""The results index: each input file's sha256 cached by (path, size, mtime_ns), so that a nightly run
with nothing new reads no sweep (``<results>/index.json``; a file that changed is hashed again)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from rotorcheck.fileio import atomic_write_text, file_sha256

INDEX_FILE = "index.json"
INDEX_VERSION = 1


class HashIndex:
    """sha256 (and time, where a sweep's name carries none) of input files by (path, size, mtime_ns)."""

    def __init__(self, results: Path) -> None:
        self.path = results / INDEX_FILE
        self.entries: dict[str, dict[str, Any]] = {}
        self.changed = False
        try:
            doc = json.loads(self.path.read_text(encoding="utf-8"))
            if doc.get("version") == INDEX_VERSION and isinstance(doc.get("files"), dict):
                self.entries = doc["files"]
        except (OSError, ValueError, AttributeError):
            self.entries = {}  # absent or unreadable: rebuilt (it is only a cache)

    @staticmethod
    def _key(st: os.stat_result) -> list[int]:
        return [st.st_size, st.st_mtime_ns]

    def times(self) -> dict[str, str]:
        """Cached times by path (for files whose name carries none)."""
        return {p: e["time"] for p, e in self.entries.items() if e.get("time")}

    def sha256(self, path: Path, time: str | None = None) -> str:
        """The file's sha256, from the cache when its size and mtime are unchanged."""
        key = str(path)
        st = os.stat(path)
        e = self.entries.get(key)
        if e is not None and e.get("stat") == self._key(st):
            if time and e.get("time") != time:
                e["time"] = time
                self.changed = True
            return str(e["sha256"])
        digest = file_sha256(path)
        self.entries[key] = {"stat": self._key(st), "sha256": digest, **({"time": time} if time else {})}
        self.changed = True
        return digest

    def save(self) -> None:
        """Write the index atomically when it changed."""
        if self.changed:
            atomic_write_text(self.path, json.dumps({"version": INDEX_VERSION, "files": self.entries},
                                                    sort_keys=True) + "\n")
            self.changed = False
