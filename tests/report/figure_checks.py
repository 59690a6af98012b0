"""Checks on a rendered figure shared by the figure tests: the text artists actually drawn, pairs of them
whose boxes overlap, and texts reaching beyond the figure (display space, after ``canvas.draw()``)."""

from __future__ import annotations

import itertools
from typing import Any
from unittest import mock

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text


def drawn_texts(fig: Figure) -> list[tuple[Text, Any]]:
    """Every text the Agg canvas draws (tick labels, axis labels, titles, legends, annotations, colour bars)
    with its glyph box in display pixels (an annotation's arrow left out)."""
    FigureCanvasAgg(fig)
    seen: list[Text] = []
    draw = Text.draw

    def record(self: Text, renderer: Any) -> None:
        if self.get_visible() and self.get_text().strip():
            seen.append(self)
        draw(self, renderer)

    with mock.patch.object(Text, "draw", record):
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    out, ids = [], set()
    for t in seen:
        if id(t) not in ids:
            ids.add(id(t))
            out.append((t, Text.get_window_extent(t, renderer)))
    return out


def overlapping_texts(fig: Figure) -> list[tuple[str, str]]:
    """Pairs of drawn texts whose boxes overlap (by their text)."""
    boxes = drawn_texts(fig)
    return [(a.get_text(), b.get_text()) for (a, ba), (b, bb) in itertools.combinations(boxes, 2)
            if ba.x0 < bb.x1 and bb.x0 < ba.x1 and ba.y0 < bb.y1 and bb.y0 < ba.y1]


def texts_outside(fig: Figure, tol_px: float = 0.5) -> list[str]:
    """Drawn texts that reach beyond the figure's edges."""
    w, h = fig.bbox.width, fig.bbox.height
    return [t.get_text() for t, b in drawn_texts(fig)
            if b.x0 < -tol_px or b.y0 < -tol_px or b.x1 > w + tol_px or b.y1 > h + tol_px]
