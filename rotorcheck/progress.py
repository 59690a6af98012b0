"""Progress of a long library step, for whoever shows it (the CLI's bar on stderr, a notebook, nobody).

A step that loops over items (shaft elements, candidate elements, sweeps, frequency points) takes an
optional ``progress: Progress`` and calls it after each item as ``progress(done, total, label)``:
``done`` items of ``total`` finished, ``label`` naming the one just done (e.g. ``"element 4"``).
The library never prints; ``None`` means nobody listens.
"""

from __future__ import annotations

from collections.abc import Callable

#: ``progress(done, total, label)`` after each item of a long step
Progress = Callable[[int, int, str], None]


def report(progress: Progress | None, done: int, total: int, label: str) -> None:
    """Call ``progress`` when someone listens (one line at every call site instead of an ``if``)."""
    if progress is not None:
        progress(done, total, label)
