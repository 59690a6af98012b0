"""``rotorcheck model`` (modal summary, Campbell, mode shapes, rotor drawing) and ``rotorcheck crack``
(the cracked rotor's stiffness, orbits and spectra, dissertation section 5.3)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rotorcheck.config import Crack, RigConfig, UnbalanceMass, load_config
from rotorcheck.errors import InputError, check_choice
from rotorcheck.faults.analysis import critical_speed_summary, unbalance_harmonics
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import campbell, mode_table, model_summary, modes
from rotorcheck.fileio import check_replaceable, check_writable, record_outputs


def model_report(
    rig_path: str | Path, speed_rpm: float | None = 0.0, out_dir: str | Path | None = None, force: bool = False,
    formats: tuple[str, ...] = ("png",), speed_unit: str = "rpm",
) -> dict[str, Any]:
    """Modal summary of a rig at ``speed_rpm`` and, with ``out_dir``, Campbell, mode-shape and rotor plots
    (``speed_unit`` ``rpm`` | ``Hz``: the Campbell diagram's speed axis; InputError naming ``--speed-unit``).

    ``speed_rpm=None``: every speed of the rig's ``analysis.speeds_rpm``; the summary's top-level
    keys are those of the first, ``at_speeds`` holds each speed's ``{speed_rpm, modes}``.
    Returns ``{"summary": <cli.md model keys>, "files": [written paths]}``.
    """
    config = load_config(rig_path)  # bad input fails here, before any work or output
    from rotorcheck.report.campbell import SPEED_UNITS  # lazy: matplotlib only when plotting

    check_choice(speed_unit, SPEED_UNITS, "--speed-unit")


    speeds = [float(speed_rpm)] if speed_rpm is not None else [float(x) for x in config.analysis.speeds_rpm]
    speed_rpm = speeds[0]
    system = build_system(config)
    summary = model_summary(config, speed_rpm, system)
    summary["speed_rpm"] = speed_rpm
    summary["at_speeds"] = [{"speed_rpm": speed_rpm, "modes": summary["modes"]}] + [
        {"speed_rpm": sp, "modes": mode_table(modes(system, sp, n_modes=config.analysis.n_modes))}
        for sp in speeds[1:]]
    summary.setdefault("rig_id", config.rig_id)
    summary.setdefault("campbell_max_rpm", config.analysis.campbell_max_rpm)
    files: list[str] = []
    if out_dir is not None:
        files = _model_plots(config, system, speed_rpm, Path(out_dir), force, formats, speed_unit)
    return {"summary": summary, "files": files}


def _model_plots(config: RigConfig, system: Any, speed_rpm: float, out: Path, force: bool,
                 formats: tuple[str, ...], speed_unit: str = "rpm") -> list[str]:
    """Campbell diagram (1X and 2X criticals, operating speed ``speed_rpm``, speed axis in ``speed_unit``),
    the table's mode shapes at ``speed_rpm`` and the rotor drawing (rotor rigs)."""

    from rotorcheck.report.campbell import (  # lazy: matplotlib only when plotting
        campbell_figure,
        mode_shape_figure,
        order_criticals,
    )
    from rotorcheck.report.figures import save_figure  # lazy: matplotlib only when plotting
    from rotorcheck.report.rotor_drawing import rotor_figure  # lazy: matplotlib only when plotting

    rotor = system.kind == "rotor"
    stems = [out / "campbell", out / "mode_shapes"] + ([out / "rotor"] if rotor else [])
    # a repeated run replaces the plots it wrote itself (manifest in the folder), never another file
    check_replaceable([s.with_suffix("." + ext) for s in stems for ext in formats], force)
    speeds = np.linspace(0.0, config.analysis.campbell_max_rpm, 41)
    camp = campbell(system, speeds, config.analysis.n_modes)
    crit = order_criticals(system, camp, (1, 2)) if rotor else None
    fig = campbell_figure(camp, (1, 2), rig_id=config.rig_id, operating_speed_rpm=speed_rpm if rotor else None,
                          speed_unit=speed_unit, criticals=crit)
    files = save_figure(fig, stems[0], formats)
    files += save_figure(mode_shape_figure(system, speed_rpm, config.analysis.n_modes, config=config), stems[1],
                         formats)
    if rotor:
        files += save_figure(rotor_figure(config), stems[2], formats)
    record_outputs(files)
    return [str(f) for f in files]


def crack_report(
    rig_path: str | Path, fault: str = "breathing_crack", unbalance_g_m: float = 0.2, station: int | None = None,
    speeds_rpm: tuple[float, float] = (1000.0, 750.0), out_dir: str | Path | None = None, force: bool = False,
    formats: tuple[str, ...] = ("png",),
) -> dict[str, Any]:
    """Stiffness over a revolution, orbits and spectra of the cracked rotor (Fig. 56-58).

    Unbalance ``unbalance_g_m`` (g m) at the first disc, facing down (-y) while the crack faces up
    and is closed at t = 0 (section 5.3); responses at ``station`` (default: the sensor). Returns
    the harmonic amplitudes (m) healthy and cracked at each speed, the critical speeds and, with
    ``out_dir``, the three figures (PNG and PDF).
    """

    config = load_config(rig_path)
    crack = config.faults.get(fault)
    if not isinstance(crack, Crack) or crack.model == "open":
        known = ", ".join(k for k, v in config.faults.items() if isinstance(v, Crack) and v.model != "open")
        raise InputError(rig_path, f"faults.{fault}", f"not a breathing crack (breathing cracks: {known or 'none'})")
    if not config.discs:
        raise InputError(rig_path, "discs", "the section 5.3 illustration puts the unbalance on the first disc")
    st = station if station is not None else config.io_ports("the illustration").sensor.station
    if st is None:
        raise InputError(rig_path, "ports.sensor.station", "the illustration needs a sensor station")
    stems = []
    if out_dir is not None:

        stems = [Path(out_dir) / n for n in ("crack_stiffness", "crack_orbit", "crack_spectrum")]
        check_writable([s.with_suffix("." + e) for s in stems for e in formats], force)


    system = build_system(config)
    unb = [UnbalanceMass(station=config.discs[0].station, amount=unbalance_g_m * 1e-3, phase=-np.pi / 2)]
    dofs = [system.dof(st, "x"), system.dof(st, "y")]
    harmonics = {}
    solved: dict[tuple[float, str], tuple[np.ndarray, np.ndarray]] = {}  # for the figures too
    for speed in speeds_rpm:
        for name, c in (("healthy", None), ("cracked", crack)):
            orders, X = solved[speed, name] = unbalance_harmonics(system, c, speed, unb, dofs)
            harmonics[f"{name}_{speed:g}rpm"] = {"order": orders.tolist(), "x_m": np.abs(X[:, 0]).tolist(),
                                                 "y_m": np.abs(X[:, 1]).tolist()}
    crit = critical_speed_summary(system, crack, speeds_rpm[0], config.analysis.campbell_max_rpm)
    files: list[str] = []
    if out_dir is not None:
        from rotorcheck.report.crack_plots import crack_figures  # lazy: matplotlib only when plotting
        from rotorcheck.report.figures import save_figure  # lazy: matplotlib only when plotting

        figs = crack_figures(system, crack, unb, station=st, speeds_rpm=speeds_rpm, rig_id=config.rig_id,
                             harmonics=solved)
        for key, stem in zip(("stiffness", "orbit", "spectrum"), stems):
            files += [str(p) for p in save_figure(figs[key], stem, formats)]
    return {"rig_id": config.rig_id, "fault": fault, "station": st, "unbalance_g_m": unbalance_g_m,
            "harmonics": harmonics, "critical_speeds": crit, "files": files}

