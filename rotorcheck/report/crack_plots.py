"""Breathing-crack figures (dissertation Fig. 56-58), matplotlib Figure API only (no pyplot).

- :func:`stiffness_change_figure`: normalized rotating-frame stiffness ``k_xi/k0``, ``k_eta/k0`` over
  one revolution of the crack opening angle (Fig. 56; closed at 0 deg, fully open at 180 deg).
- :func:`orbit_figure`: healthy vs cracked steady-state orbits at a station (Fig. 57), in um, one panel
  per speed, with the start (t = 0) marked and arrows in the direction of travel.
- :func:`spectrum_figure`: harmonic amplitudes nX of the unbalance response (Fig. 58), in um on a log
  scale (stated on the axis), order ticks ``1X``, ``2X``, ... with the frequency (Hz) on the top axis.
- :func:`crack_figures`: computes the data by harmonic balance and returns all three figures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from rotorcheck.config import Crack, UnbalanceMass
from rotorcheck.faults.analysis import orbit_from_harmonics, unbalance_harmonics
from rotorcheck.faults.crack import rotating_reduction
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.report.figures import legend_outside, wrap_to_width

__all__ = ["crack_figures", "orbit_figure", "spectrum_figure", "stiffness_change_figure"]

UM = 1e6
#: healthy and cracked series: colour and line style
SERIES = {"healthy": ("black", "-"), "cracked": ("tab:red", "--")}
#: a log-scale spectrum shows this many decades below its largest amplitude
LOG_DECADES = 5.0


def stiffness_change_figure(crack: Crack, poisson: float = 0.3, radius: float = 0.008, n_points: int = 721,
                            title: str | None = None) -> Figure:
    """Fig. 56: ``k/k0`` in the xi and eta directions vs the opening angle (deg).

    ``poisson`` and ``radius`` (m) are used when the crack does not set them (eq. 5.25).
    """
    theta = np.linspace(0.0, 2.0 * np.pi, n_points)
    red = rotating_reduction(crack, theta, poisson, radius)
    fig = Figure(figsize=(6.4, 4.0), layout="constrained")
    ax = fig.add_subplot()
    deg = np.degrees(theta)
    ax.plot(deg, 1.0 - red[:, 0, 0], label=r"$k_\xi / k_0$")
    ax.plot(deg, 1.0 - red[:, 1, 1], "--", label=r"$k_\eta / k_0$")
    ax.set_xlim(0.0, 360.0)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("crack opening angle theta (deg; 0 = closed, facing up)")
    ax.set_ylabel("normalized stiffness")
    ax.set_title(wrap_to_width(title or f"Breathing crack stiffness over one revolution: element {crack.element} "
                               f"({crack.model})", 0.95 * fig.get_figwidth(), 10), fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend()
    return fig


def _travel_arrow(ax: Any, x: np.ndarray, y: np.ndarray, colour: Any, at: float = 0.2) -> None:
    """An arrow along the orbit (x, y) at fraction ``at`` of the period, in the direction of travel."""
    n = x.size
    i = int(at * n) % n
    j = (i + max(1, n // 40)) % n
    ax.annotate("", xy=(x[j], y[j]), xytext=(x[i], y[i]), gid="travel arrow",
                arrowprops={"arrowstyle": "-|>,head_length=0.8,head_width=0.4", "color": colour, "lw": 1.5})


def orbit_figure(orbits: Mapping[str, Any], title: str = "Orbit") -> Figure:
    """Fig. 57: orbits in um with equal axes, one panel per speed.

    ``orbits``: ``{label: xy (N, 2) in m}`` (one panel), or ``{panel title: {label: xy}}`` (one panel each,
    e.g. per speed). The start (t = 0: crack closed, facing up) is a dot; arrows show the direction of
    travel (spin from +x towards +y: counter-clockwise).
    """
    panels = orbits if all(isinstance(v, Mapping) for v in orbits.values()) else {"": orbits}
    fig = Figure(figsize=(4.6 * len(panels) + 1.2, 5.0), layout="constrained")
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (name, series) in zip(axes, panels.items()):
        for i, (label, xy) in enumerate(series.items()):
            xy = UM * np.asarray(xy)
            colour, style = SERIES.get(label, (f"C{i}", ["-", "--", ":", "-."][i % 4]))
            ax.plot(xy[:, 0], xy[:, 1], style, color=colour, lw=1.5, label=label, gid=f"orbit {label}")
            ax.plot(xy[0, 0], xy[0, 1], "o", color=colour, ms=6, gid=f"start {label}")
            _travel_arrow(ax, xy[:, 0], xy[:, 1], colour)
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.axvline(0.0, color="0.6", lw=0.5)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x (horizontal) displacement (um)")
        ax.set_ylabel("y (vertical) displacement (um)")
        ax.set_title(name, fontsize=10)
        ax.grid(True, alpha=0.3)
    handles = [Line2D([], [], color=c, ls=st, lw=1.5, label=k) for k, (c, st) in SERIES.items()
               if any(k in series for series in panels.values())]
    handles += [Line2D([], [], marker="o", ls="", color="0.3", ms=6, label="start of the period (t = 0, crack closed)"),
                Line2D([], [], marker=">", ls="-", color="0.3", label="direction of travel")]
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle(wrap_to_width(title + "\nshaft spin counter-clockwise (+x towards +y)", 0.95 * fig.get_figwidth(), 10),
                 fontsize=10)
    return fig


def spectrum_figure(panels: Sequence[Mapping[str, Any]], title: str = "") -> Figure:
    """Fig. 58: one axes per panel, harmonic amplitudes as stems in um.

    Each panel: ``{"title", "speed_rpm", "orders" (q,), "amp" (q, k) in m (or (q,)), "labels" (series
    names), "scale": "log" (default) | "linear"}``. The x axis reads orders ``1X``, ``2X``, ...; the top
    axis the frequency (Hz) at the panel's speed; the y label names the scale. A log panel shows
    :data:`LOG_DECADES` decades below its largest amplitude (smaller ones sit at the bottom edge).
    """
    n = len(panels)
    fig = Figure(figsize=(7.0, 2.6 * n + 0.9), layout="constrained")
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    for ax, p in zip(axes, panels):
        orders = np.asarray(p["orders"], dtype=float)
        a = np.abs(np.asarray(p["amp"]))
        a = UM * (a[:, None] if a.ndim == 1 else a)
        labels = p.get("labels") or [f"series {i + 1}" for i in range(a.shape[1])]
        log = p.get("scale", "log") == "log"
        width = 0.12
        floor = max(float(a.max()), 1e-30) * 10.0 ** (-LOG_DECADES) if log else 0.0
        for j in range(a.shape[1]):
            x = orders + (j - (a.shape[1] - 1) / 2.0) * width
            colour, _ = SERIES.get(str(labels[j]).split(",")[0], (f"C{j}", "-"))
            if "y" in str(labels[j]).split(",")[-1]:
                colour = {"black": "0.55", "tab:red": "tab:orange"}.get(str(colour), colour)
            shown = np.maximum(a[:, j], floor) if log else a[:, j]
            ax.vlines(x, floor, shown, lw=2.0, color=colour)
            ax.plot(x, shown, "o" if j % 2 == 0 else "s", ms=4, color=colour, label=labels[j], gid=f"stem {labels[j]}")
        ax.set_xticks(orders, [f"{int(o)}X" for o in orders])
        ax.set_xlim(orders[0] - 0.5, orders[-1] + 0.5)
        speed = p.get("speed_rpm")
        if speed:
            top = ax.secondary_xaxis("top", functions=(lambda o, s=speed: o * s / 60.0,
                                                       lambda f, s=speed: f * 60.0 / s))
            top.set_xticks(orders * speed / 60.0, [f"{o * speed / 60.0:.4g}" for o in orders])
            top.tick_params(labelsize=7)
            top.set_xlabel("frequency (Hz)", fontsize=8)
        if log:
            ax.set_yscale("log")
            ax.set_ylim(floor, float(a.max()) * 3.0)
            ax.set_ylabel("amplitude (um, 0-peak)\nlog scale", fontsize=9)
        else:
            ax.set_ylim(0.0, None)
            ax.set_ylabel("amplitude (um, 0-peak)\nlinear scale", fontsize=9)
        ax.set_title(wrap_to_width(str(p.get("title", "")), 0.8 * fig.get_figwidth(), 9), fontsize=9, loc="left")
        ax.grid(True, which="major", alpha=0.3)
        legend_outside(ax, fontsize=7, frameon=False)
    axes[-1].set_xlabel("order of the running speed (nX)")
    if any(p.get("scale", "log") == "log" for p in panels):
        title = (title + "\n" if title else "") + (f"log scale: amplitudes below 1e-{LOG_DECADES:g} of a panel's "
                                                   "largest sit on its bottom edge")
    if title:
        fig.suptitle(wrap_to_width(title, 0.95 * fig.get_figwidth(), 10), fontsize=10)
    return fig


def crack_figures(
    system: MechanicalSystem,
    crack: Crack,
    unbalance: Sequence[UnbalanceMass],
    station: int = 6,
    speeds_rpm: tuple[float, float] = (1000.0, 750.0),
    max_order: int = 5,
    n_harmonics: int = 10,
    rig_id: str = "",
    harmonics: Mapping[tuple[float, str], tuple[np.ndarray, np.ndarray]] | None = None,
) -> dict[str, Any]:
    """Fig. 56-58 for a rig by harmonic balance; returns ``{"stiffness", "orbit", "spectrum"}``
    figures and the plotted ``data`` (harmonic amplitudes in m, orbits in m) at every speed of
    ``speeds_rpm``. ``harmonics``: :func:`unbalance_harmonics` at ``station`` (x, y) by ``(rpm, "healthy" |
    "cracked")`` when the caller has them (else solved here, once each)."""
    e = next(el for el in system.elements if el.segment == crack.element)
    outs = [system.dof(station, "x"), system.dof(station, "y")]
    data: dict[str, Any] = {}
    rig = f"{rig_id} " if rig_id else ""
    orbits: dict[str, dict[str, np.ndarray]] = {}
    panels = []
    for rpm in speeds_rpm:
        hb = {name: (harmonics[rpm, name] if harmonics is not None and (rpm, name) in harmonics
                     else unbalance_harmonics(system, ck, rpm, unbalance, outs, n_harmonics))
              for name, ck in (("healthy", None), ("cracked", crack))}
        xy_h, xy_c = (orbit_from_harmonics(*hb[name], rpm)[1] for name in ("healthy", "cracked"))
        orbits[f"{rpm:g} rpm"] = {"healthy": xy_h, "cracked": xy_c}
        data[f"orbits_{rpm:g}rpm"] = {"healthy": xy_h, "cracked": xy_c}
        amps, orders_kept = [], None
        for name in ("healthy", "cracked"):
            orders, ph = hb[name]
            keep = (orders >= 1) & (orders <= max_order)
            data[f"{name}, {rpm:g} rpm"] = {"orders": orders[keep], "amp": np.abs(ph[keep])}
            amps.append(ph[keep])
            orders_kept = orders[keep]
        panels.append({"title": f"{rig}station {station} at {rpm:g} rpm: healthy vs cracked (x and y)",
                       "speed_rpm": rpm, "orders": orders_kept, "amp": np.hstack(amps), "scale": "log",
                       "labels": ["healthy, x", "healthy, y", "cracked, x", "cracked, y"]})
    s1 = speeds_rpm[0]
    data["orbit_healthy"], data["orbit_cracked"] = (data[f"orbits_{s1:g}rpm"][k] for k in ("healthy", "cracked"))
    what = f"{crack.model} crack in element {crack.element}"
    return {
        "stiffness": stiffness_change_figure(
            crack, e.poisson, 0.5 * e.outer_diameter,
            title=f"{rig}breathing crack stiffness over one revolution: {what}"),
        "orbit": orbit_figure(orbits, f"{rig}orbits at station {station}, healthy vs {what}"),
        "spectrum": spectrum_figure(panels, f"{rig}unbalance response harmonics at station {station}: {what}"),
        "data": data,
    }
