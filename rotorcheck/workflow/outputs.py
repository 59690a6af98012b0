"""Plot file formats (``--plot-format``) and the paths plots are written to."""

from __future__ import annotations

from pathlib import Path

from rotorcheck.errors import check_choice

#: plot file formats by the CLI's ``--plot-format``
PLOT_FORMATS = {"png": ("png",), "pdf": ("pdf",), "both": ("png", "pdf")}


def plot_formats(name: str) -> tuple[str, ...]:
    """``png`` (default) | ``pdf`` | ``both`` -> file formats; InputError naming ``--plot-format``."""
    check_choice(name, PLOT_FORMATS, "--plot-format")
    return PLOT_FORMATS[name]


def plot_paths(out_dir: str | Path, stems: tuple[str, ...] | list[str], formats: tuple[str, ...]) -> list[Path]:
    """The files the plots ``stems`` will be written to in ``out_dir``."""
    return [Path(out_dir) / f"{s}.{e}" for s in stems for e in formats]

