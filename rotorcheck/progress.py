"""Progress of a long library step, for whoever shows it (the CLI's bar on stderr, a notebook, nobody).

A step that loops over items (shaft elements, candidate elements, sweeps, frequency points) takes an
optional ``progress: Progress`` and calls it after each item as ``progress(done, total, label)``:
``done`` items of ``total`` finished, ``label`` naming the one just done (e.g. ``"element 4"``); and with
``done`` 0 before the first item (the step starts: a display times the step's items from there, not from
whatever ran before it). The library never prints; ``None`` means nobody listens.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

#: ``progress(done, total, label)`` after each item of a long step
Progress = Callable[[int, int, str], None]


def report(progress: Progress | None, done: int, total: int, label: str) -> None:
    """Call ``progress`` when someone listens (one line at every call site instead of an ``if``)."""
    if progress is not None:
        progress(done, total, label)


def clock(seconds: float) -> str:
    """Seconds as h:mm:ss."""
    s = round(max(seconds, 0.0))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class ConsoleSteps:
    """A :data:`Progress` shown on a rich console (stderr): a bar with the items done, the label, the elapsed
    and the remaining time on a terminal; otherwise plain lines ``[k/n] text label: elapsed h:mm:ss, about
    h:mm:ss left`` (remaining = the step's time per item so far x items left; the step's time counts from its
    ``done`` 0 call, else from the start), the first after ``every_s`` seconds and then at most one per
    ``every_s`` (0: one per item); nothing when ``quiet``. The one progress display of the CLI and the fleet.

    ``with ConsoleSteps(console, "locating") as tick: library_call(..., progress=tick)``"""

    def __init__(self, console: Any, text: str, quiet: bool = False, every_s: float = 2.0) -> None:
        self.console, self.text, self.quiet, self.every_s = console, text, quiet, every_s
        self._bar: Any = None
        self._task: Any = None
        self._start = self._last = 0.0
        self._step: tuple[int, float] | None = None  # (total, when) of the last step that said it started

    def __enter__(self) -> ConsoleSteps:
        self._start = self._last = time.monotonic()
        if not self.quiet and self.console.is_terminal:
            from rich.progress import (  # lazy: rich.progress only for a bar on a terminal
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                 TextColumn("{task.fields[label]}"), TimeElapsedColumn(), TextColumn("left"),
                                 TimeRemainingColumn(), console=self.console, transient=True)
            self._bar.start()
            self._task = self._bar.add_task(self.text, total=None, label="")
        return self

    def __call__(self, done: int, total: int, label: str) -> None:
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.update(self._task, completed=done, total=total, label=label)
            return
        now = time.monotonic()
        if done <= 0:
            self._step = (total, now)  # a step starts: its items are timed from here
            return
        if now - self._last < self.every_s:
            return
        self._last = now
        elapsed = now - self._start
        since = self._step[1] if self._step is not None and self._step[0] == total else self._start
        self.console.print(f"[{done}/{total}] {self.text} {label}: elapsed {clock(elapsed)}, about "
                           f"{clock((now - since) * (total - done) / done)} left", markup=False, highlight=False)

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()
