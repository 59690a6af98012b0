"""The five steps as functions a notebook can call; the CLI is a thin layer over these."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rotorcheck.config import RigConfig, load_config


def load_rig(path: str | Path) -> RigConfig:
    """Load and validate a rig YAML file (raises ConfigError naming file and field)."""
    return load_config(path)


def model_report(
    rig_path: str | Path, speed_rpm: float = 0.0, out_dir: str | Path | None = None, force: bool = False
) -> dict[str, Any]:
    """Modal summary of a rig at ``speed_rpm`` and, with ``out_dir``, Campbell and mode-shape plots.

    Returns ``{"summary": <cli.md model keys>, "files": [written paths]}``.
    """
    config = load_config(rig_path)  # bad input fails here, before any work or output

    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.modal import model_summary

    summary = model_summary(config, speed_rpm)
    summary.setdefault("rig_id", config.rig_id)
    summary.setdefault("campbell_max_rpm", config.analysis.campbell_max_rpm)
    files: list[str] = []
    if out_dir is not None:
        files = _model_plots(config, build_system(config), speed_rpm, Path(out_dir), force)
    return {"summary": summary, "files": files}


def _model_plots(config: RigConfig, system: Any, speed_rpm: float, out: Path, force: bool) -> list[str]:
    import numpy as np

    from rotorcheck.fe.modal import campbell
    from rotorcheck.fileio import check_writable
    from rotorcheck.report.campbell import campbell_figure, mode_shape_figure
    from rotorcheck.report.figures import save_figure

    stems = [out / "campbell", out / "mode_shapes"]
    check_writable([s.with_suffix(ext) for s in stems for ext in (".png", ".pdf")], force)
    speeds = np.linspace(0.0, config.analysis.campbell_max_rpm, 41)
    camp = campbell(system, speeds, config.analysis.n_modes)
    files = save_figure(campbell_figure(camp), stems[0])
    files += save_figure(mode_shape_figure(system, speed_rpm, config.analysis.n_modes), stems[1])
    return [str(f) for f in files]
