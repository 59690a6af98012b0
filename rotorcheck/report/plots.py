"""Validation, detection and identification plots (matplotlib Figure API, no global state).

The uncertainty band at each frequency is a disk in the complex plane (centre ``c``, radius ``rho``,
receptance units m/N): magnitude from ``max(0, |c| - rho)`` to ``|c| + rho``; phase
``arg(c) +/- asin(rho/|c|)``, or the full 360 degrees where the disk holds the origin (dissertation
Fig. 43/47).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure


def disk_band(centre: np.ndarray, radius: np.ndarray) -> dict[str, np.ndarray]:
    """Magnitude and phase (deg) bands of disks; ``full_phase`` where a disk holds the origin."""
    c = np.asarray(centre, dtype=complex)
    r = np.asarray(radius, dtype=float)
    mag = np.abs(c)
    full = r >= mag
    with np.errstate(divide="ignore", invalid="ignore"):
        half = np.degrees(np.arcsin(np.clip(np.where(full, 1.0, r / mag), 0.0, 1.0)))
    ph = np.degrees(np.angle(c))
    half = np.where(full, 180.0, half)
    return {
        "phase_half_width": half,
        "mag_lo": np.maximum(mag - r, 0.0),
        "mag_hi": mag + r,
        "phase_lo": np.where(full, -180.0, ph - half),
        "phase_hi": np.where(full, 180.0, ph + half),
        "full_phase": full,
    }


def _wrap_near(phase_deg: np.ndarray, ref_deg: np.ndarray) -> np.ndarray:
    """Shift ``phase_deg`` by multiples of 360 to lie within 180 deg of ``ref_deg``."""
    return ref_deg + (phase_deg - ref_deg + 180.0) % 360.0 - 180.0


def bode_band_figure(
    freq_hz: np.ndarray,
    model_frf: np.ndarray,
    centre: np.ndarray,
    radius: np.ndarray,
    healthy_frf: np.ndarray | None = None,
    damaged_frf: np.ndarray | None = None,
    fault: np.ndarray | None = None,
    title: str = "",
) -> Figure:
    """Bode magnitude (m/N, log) and phase (deg) of model, band, healthy and damaged data."""
    fig = Figure(figsize=(9, 7), layout="constrained")
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    band = disk_band(centre, radius)
    ref = np.unwrap(np.angle(model_frf))
    ref_deg = np.degrees(ref)
    floor = np.min(np.abs(model_frf)) * 1e-3
    ax_m.fill_between(freq_hz, np.maximum(band["mag_lo"], floor), band["mag_hi"], color="tab:blue",
                      alpha=0.25, lw=0, label="uncertainty band")
    ax_m.semilogy(freq_hz, np.abs(model_frf), color="tab:blue", lw=1.2, label="nominal model")
    ax_p.plot(freq_hz, ref_deg, color="tab:blue", lw=1.2)
    centre_deg = _wrap_near(np.degrees(np.angle(centre)), ref_deg)
    half = band["phase_half_width"]
    ax_p.fill_between(freq_hz, centre_deg - half, centre_deg + half, color="tab:blue", alpha=0.25, lw=0)
    for data, colour, label in ((healthy_frf, "k", "healthy data"), (damaged_frf, "tab:red", "new data")):
        if data is None:
            continue
        ax_m.semilogy(freq_hz, np.abs(data), ".", ms=3, color=colour, label=label)
        ax_p.plot(freq_hz, _wrap_near(np.degrees(np.angle(data)), ref_deg), ".", ms=3, color=colour)
    if fault is not None and damaged_frf is not None and np.any(fault):
        ax_m.semilogy(freq_hz[fault], np.abs(damaged_frf[fault]), "o", mfc="none", ms=7, color="tab:red",
                      label=f"fault points ({int(np.sum(fault))})")
        ax_p.plot(freq_hz[fault], _wrap_near(np.degrees(np.angle(damaged_frf[fault])), ref_deg[fault]), "o",
                  mfc="none", ms=7, color="tab:red")
    ax_m.set_ylabel("|receptance| (m/N)")
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("frequency (Hz)")
    ax_m.legend(loc="best", fontsize=8)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, alpha=0.3)
    if title:
        ax_m.set_title(title)
    return fig


def complex_plane_figure(
    freq_hz: float,
    model: complex,
    centre: complex,
    radius: float,
    healthy: complex | None = None,
    damaged: complex | None = None,
) -> Figure:
    """The uncertainty disk at one frequency in the complex plane (dissertation Fig. 48)."""
    fig = Figure(figsize=(5.5, 5.5), layout="constrained")
    ax = fig.subplots()
    t = np.linspace(0, 2 * np.pi, 361)
    ax.fill(centre.real + radius * np.cos(t), centre.imag + radius * np.sin(t), color="tab:blue", alpha=0.2,
            label="uncertainty set")
    ax.plot(model.real, model.imag, "s", color="tab:blue", label="nominal model")
    if healthy is not None:
        ax.plot(healthy.real, healthy.imag, "o", color="k", label="healthy data")
    if damaged is not None:
        ax.plot(damaged.real, damaged.imag, "o", color="tab:red", label="new data")
    ax.plot(0, 0, "+", color="grey")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("Re (m/N)")
    ax.set_ylabel("Im (m/N)")
    ax.set_title(f"{freq_hz:.2f} Hz")
    ax.legend(loc="best", fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def damage_dynamics_figure(
    freq_hz: np.ndarray,
    damage: np.ndarray,
    bound_min_abs: np.ndarray,
    bound_max_abs: np.ndarray,
    phase_lo_deg: np.ndarray | None = None,
    phase_hi_deg: np.ndarray | None = None,
    fault: np.ndarray | None = None,
    title: str = "",
    anchored: np.ndarray | None = None,
    label: str = "identified D_u (eq. 3.11)",
    bound_label: str = "exact bound",
    anchored_label: str = "D_u anchored at the healthy data",
) -> Figure:
    """Identified damage dynamics D_u (N/m) with its bound: magnitude and phase.

    ``damage`` is drawn solid with its bound; ``anchored``: an optional second estimate (dashed).
    """
    fig = Figure(figsize=(9, 6.5), layout="constrained")
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    hi = np.where(np.isfinite(bound_max_abs), bound_max_abs, np.nan)
    floor = np.nanmax(np.abs(damage)) * 1e-4 if np.any(np.isfinite(damage)) else 1.0
    ax_m.fill_between(freq_hz, np.maximum(bound_min_abs, floor), hi, color="tab:orange", alpha=0.3, lw=0,
                      label=bound_label)
    ax_m.semilogy(freq_hz, np.abs(damage), color="tab:red", lw=1.2, label=label)
    if anchored is not None:
        ax_m.semilogy(freq_hz, np.abs(anchored), "--", color="tab:purple", lw=1.0, label=anchored_label)
    if fault is not None and np.any(fault):
        ax_m.semilogy(freq_hz[fault], np.abs(damage[fault]), "o", mfc="none", ms=6, color="k",
                      label="fault points")
    ph = np.degrees(np.angle(damage))
    ax_p.plot(freq_hz, ph, color="tab:red", lw=1.2)
    if anchored is not None:
        ax_p.plot(freq_hz, np.degrees(np.angle(anchored)), "--", color="tab:purple", lw=1.0)
    if phase_lo_deg is not None and phase_hi_deg is not None:
        ax_p.fill_between(freq_hz, phase_lo_deg, phase_hi_deg, color="tab:orange", alpha=0.3, lw=0)
    ax_m.set_ylabel("|D_u| (N/m)")
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("frequency (Hz)")
    ax_p.set_ylim(-200, 200)
    ax_m.legend(loc="best", fontsize=8)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, alpha=0.3)
    if title:
        ax_m.set_title(title)
    return fig


def shaft_drawing(ax: Any, config: Any, colour_of: Any = None, actuators: Any = (), sensors: Any = ()) -> None:
    """The rotor along its axis (m) on ``ax``: shaft elements (numbered, filled by ``colour_of(element)``),
    discs, bearings on the shaft, actuator (v) and sensor (o) ports."""
    from matplotlib.patches import Rectangle

    z = np.asarray(config.stations, dtype=float)
    for el in config.shaft:
        col = colour_of(el.start) if colour_of is not None else "white"
        r0, r1 = 0.5 * el.outer_diameter, 0.5 * el.outer_right
        x0, x1 = z[el.start - 1], z[el.end - 1]
        ax.fill([x0, x1, x1, x0], [-r0, -r1, r1, r0], facecolor=col, edgecolor="k", lw=0.6)
        ax.text(0.5 * (x0 + x1), 1.6 * max(r0, r1), str(el.start), ha="center", va="bottom", fontsize=7)
    dmax = max(el.outer_diameter for el in config.shaft)
    for d in config.discs:
        ax.add_patch(Rectangle((z[d.station - 1] - 0.004, -1.5 * dmax), 0.008, 3.0 * dmax, facecolor="0.4"))
    for b in config.bearings:
        if b.station <= z.size:  # support nodes (pedestals) are not on the shaft
            ax.plot(z[b.station - 1], -1.3 * dmax, "^", color="k", ms=9)
    for ports, mark, name in ((actuators, "v", "actuator"), (sensors, "o", "sensor")):
        for port in ports:
            if getattr(port, "station", None) is not None:
                ax.plot(z[port.station - 1], 1.3 * dmax, mark, color="tab:green", ms=8,
                        label=f"{name} s{port.station}{port.direction}")
    ax.plot([], [], "^", color="k", label="bearing")
    ax.set_ylim(-2.2 * dmax, 2.2 * dmax)
    ax.set_yticks([])


def detectability_figure(config: Any, det: Any) -> Figure:
    """The rotor drawing (elements shaded by their detectable breathing depth with benign ranges) over the
    smallest detectable breathing-crack depth (% of diameter) per element: with the benign ranges, noise
    only, and the likelihood-ratio limit."""
    import textwrap

    from matplotlib import colormaps

    from rotorcheck.config import Port

    def parse_port(label: str) -> Port:  # "s6.x"
        station, direction = label[1:].split(".")
        return Port(station=int(station), direction=direction)  # type: ignore[arg-type]

    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax, bx = fig.subplots(2, 1, sharex=True, height_ratios=(1.0, 1.4))
    depth = {e.element: e.breathing_depth_min for e in det.elements}
    cmap = colormaps["RdYlGn_r"]

    def colour_of(element: int) -> Any:
        d = depth.get(element)
        return "0.6" if d is None else cmap(min(float(d) / 0.5, 1.0))

    shaft_drawing(ax, config, colour_of, [parse_port(a) for a in det.actuators], [parse_port(s) for s in det.sensors])
    ax.legend(loc="upper right", fontsize=7)
    ax.set_title("\n".join(textwrap.wrap(
        f"{det.rig_id} at {det.speed_rpm:g} rpm: smallest breathing crack found with 90 % power at "
        f"{det.false_alarm:g} false alarms; {det.noise_source}", 110)), fontsize=8)
    mids = np.array([0.5 * (e.z_start_m + e.z_end_m) for e in det.elements])
    for key, style, label in (("breathing_depth_min", "o-", "with the benign ranges"),
                              ("breathing_depth_min_noise_only", "s--", "noise only"),
                              ("limit_breathing_depth_noise_only", ":", "likelihood-ratio limit (noise only)")):
        vals = np.array([np.nan if getattr(e, key) is None else 100 * getattr(e, key) for e in det.elements])
        bx.plot(mids, vals, style, label=label)
    bx.set_yscale("log")
    bx.set_ylabel("breathing crack depth (% of diameter)")
    bx.set_xlabel("axial position (m); grey: not seen by these channels, or no detectable depth up to 50 %")
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=7)
    z = np.asarray(config.stations, dtype=float)
    bx.set_xlim(z[0] - 0.01, z[-1] + 0.01)
    return fig


def location_figure(config: Any, location: Any, title: str = "") -> Figure:
    """The shaft along its axis (m): each candidate element coloured by its status (excluded: grey,
    consistent: blue, the best ranked: red), stations, discs, bearings, actuator and sensor marked; below,
    the certified stiffness-loss interval of every candidate not excluded (and its estimate), with the
    depth interval (% of the diameter) of the three best ranked."""

    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax, bx = fig.subplots(2, 1, sharex=True, height_ratios=(1.0, 1.4))
    z = np.asarray(config.stations, dtype=float)
    status = {c.element: c for c in location.candidates}
    best = location.best.element if location.best is not None else None
    colour = {"excluded": "0.8", "consistent": "tab:blue"}

    def colour_of(element: int) -> str:
        c = status.get(element)
        return "tab:red" if element == best else colour.get(c.status if c is not None else "", "white")

    ports = getattr(config, "ports", None)
    shaft_drawing(ax, config, colour_of, [p for p in (getattr(ports, "actuator", None),) if p is not None],
                  [p for p in (getattr(ports, "sensor", None),) if p is not None])
    import textwrap

    ax.set_title("\n".join(textwrap.wrap(title or location.summary(), 110)), fontsize=8)
    ax.legend(loc="upper right", fontsize=7)
    for c in location.candidates:
        if c.status != "consistent":
            continue
        mid = 0.5 * (c.z_start_m + c.z_end_m)
        lo, hi = 100 * c.loss_interval[0], 100 * c.loss_interval[1]
        col = "tab:red" if c.element == best else "tab:blue"
        bx.plot([mid, mid], [lo, hi], color=col, lw=5, alpha=0.6, solid_capstyle="butt")
        if c.loss_estimate is not None:
            bx.plot(mid, 100 * c.loss_estimate, "k_", ms=12)
        d0, d1 = c.depth_interval
        if c.rank is not None and c.rank <= 3 and d0 is not None:
            depth = f"{100 * d0:.0f}-" + ("50+" if d1 is None else f"{100 * d1:.0f}")
            bx.annotate(f"#{c.rank}\ndepth {depth} %", (mid, hi), textcoords="offset points", xytext=(0, 4),
                        ha="center", fontsize=7)
    bx.set_ylabel("element stiffness loss (%)\ncertified interval, fit (-)")
    bx.set_xlabel("axial position (m); grey: excluded, blue: consistent, red: most likely")
    bx.grid(True, alpha=0.3)
    bx.set_xlim(z[0] - 0.01, z[-1] + 0.01)
    return fig
