"""Checks on a rendered figure shared by the figure tests: the text artists actually drawn, pairs of them
whose boxes overlap, and texts reaching beyond the figure (display space, after ``canvas.draw()``); and the
figures several test files check, built once per worker (:func:`rotor_fig`, :func:`mode_shapes_fig`)."""

from __future__ import annotations

import itertools
import warnings
from functools import cache
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


def overlapping_texts(fig: Figure, boxes: list[tuple[Text, Any]] | None = None) -> list[tuple[str, str]]:
    """Pairs of drawn texts whose boxes overlap (by their text); ``boxes``: :func:`drawn_texts` of ``fig`` if
    already drawn."""
    boxes = drawn_texts(fig) if boxes is None else boxes
    return [(a.get_text(), b.get_text()) for (a, ba), (b, bb) in itertools.combinations(boxes, 2)
            if ba.x0 < bb.x1 and bb.x0 < ba.x1 and ba.y0 < bb.y1 and bb.y0 < ba.y1]


def texts_outside(fig: Figure, tol_px: float = 0.5, boxes: list[tuple[Text, Any]] | None = None) -> list[str]:
    """Drawn texts that reach beyond the figure's edges; ``boxes``: :func:`drawn_texts` of ``fig`` if already
    drawn."""
    w, h = fig.bbox.width, fig.bbox.height
    return [t.get_text() for t, b in (drawn_texts(fig) if boxes is None else boxes)
            if b.x0 < -tol_px or b.y0 < -tol_px or b.x1 > w + tol_px or b.y1 > h + tol_px]


# ---------------------------------------------------------------------------------------------------------------
# figures several tests check (test_model_figures.py, test_figure_layout.py): built once per worker, every warning
# an error while building (test_figure_layout's rule), whichever test asks first. Shared: the tests read their
# artists and may draw or save them (a figure's layout is frozen by then: drawing moves nothing), never change them.


def _built(make: Any, *args: Any, **kw: Any) -> Figure:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return make(*args, **kw)


@cache
def rotor_fig(name: str) -> Figure:
    """:func:`rotorcheck.report.rotor_drawing.rotor_figure` of the bundled config ``name``."""
    from rotorcheck.config import load_config
    from rotorcheck.report.rotor_drawing import rotor_figure
    from rotorcheck.resources import configs_dir

    return _built(rotor_figure, load_config(configs_dir() / f"{name}.yaml"))


@cache
def mode_shapes_fig(name: str, speed_rpm: float) -> Figure:
    """:func:`rotorcheck.report.campbell.mode_shape_figure` of the bundled config ``name`` at ``speed_rpm``, with
    the rotor drawing (``config``)."""
    from rotorcheck.config import load_config
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.report.campbell import mode_shape_figure
    from rotorcheck.resources import configs_dir

    cfg = load_config(configs_dir() / f"{name}.yaml")
    return _built(mode_shape_figure, build_system(cfg), speed_rpm, config=cfg)
