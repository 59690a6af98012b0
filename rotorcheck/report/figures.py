"""Writing figures: PNG and PDF side by side, each written atomically (temp file + os.replace)."""

from __future__ import annotations

from pathlib import Path

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
