"""Reading the process umask without changing it, and refusing os.umask calls (shared test helpers)."""

from __future__ import annotations

import pytest


def proc_umask() -> int:
    """The process umask as the kernel reports it (Linux >= 4.7), read without changing it."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    pytest.skip("no 'Umask:' line in /proc/self/status")


def refuse_umask(mask: int) -> int:
    raise AssertionError(f"os.umask({mask:#o}) called: a process-wide side effect")
