"""Writing figures: PNG and PDF side by side, each written atomically (temp file + os.replace)."""

from __future__ import annotations

import textwrap
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from rotorcheck.fileio import atomic_path


def save_figure(
    fig: Figure, path_stem: str | Path, formats: tuple[str, ...] = ("png", "pdf"), dpi: int = 150
) -> list[Path]:
    """Write ``fig`` to ``<path_stem>.png`` and ``.pdf`` (atomically); returns the written paths.

    ``path_stem`` may carry a suffix; it is replaced. Parent folders are created.
    """
    stem = Path(path_stem)
    if stem.suffix.lower().lstrip(".") in formats:
        stem = stem.with_suffix("")
    written: list[Path] = []
    for fmt in formats:
        target = stem.parent / f"{stem.name}.{fmt}"
        with atomic_path(target) as tmp, open(tmp, "wb") as fh:
            fig.savefig(fh, format=fmt, dpi=dpi)
        written.append(target)
    return written


def save_figures(figures: dict[str, Figure], out_dir: str | Path, formats: tuple[str, ...] = ("png",)) -> list[str]:
    """Every figure of ``figures`` (by file stem) into ``out_dir`` in ``formats``; the written paths."""
    return [str(p) for stem, fig in figures.items() for p in save_figure(fig, Path(out_dir) / stem, formats)]


def legend_outside(ax: Any, handles: Iterable[Any] | None = None, labels: Iterable[str] | None = None,
                   fontsize: float = 8, wrap: int = 50, **kw: Any) -> Any:
    """A legend right of ``ax``, outside its data (``handles``/``labels``: default the axes' labelled
    artists), each label wrapped at ``wrap`` characters (a wide legend would squeeze the axes); None when
    there is nothing to show."""
    h, lab = (list(handles), list(labels or [])) if handles is not None else ax.get_legend_handles_labels()
    if not h:
        return None
    lab = [textwrap.fill(str(x), wrap, subsequent_indent="  ") for x in lab]
    return ax.legend(h, lab, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=fontsize,
                     **kw)


#: average glyph width of the default sans-serif font, in em (a little above DejaVu Sans' mean: wrapping errs short)
GLYPH_EM = 0.62


def wrap_to_width(text: str, width_in: float, fontsize: float) -> str:
    """``text`` wrapped, line by line, to fit ``width_in`` inches at ``fontsize`` points (titles a constrained
    layout would otherwise leave cut at the figure's edge)."""
    chars = max(20, int(width_in * 72.0 / (GLYPH_EM * fontsize)))
    return "\n".join(textwrap.fill(line, chars) if line else line for line in text.split("\n"))


#: how the data are stated (sweep-format.md, method.md): x(t) = Re{X exp(j 2 pi f t)} with X the peak phasor
PHASOR_NOTE = "phasors x(t) = Re{X exp(j 2 pi f t)}, X the 0-peak amplitude; phase + = leads"
