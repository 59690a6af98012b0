"""Breathing-crack figures (dissertation Fig. 56-58), matplotlib Figure API only (no pyplot).

- :func:`stiffness_change_figure`: normalized rotating-frame stiffness ``k_xi/k0``, ``k_eta/k0`` over
  one revolution of the crack opening angle (Fig. 56; closed at 0 deg, fully open at 180 deg).
- :func:`orbit_figure`: healthy vs cracked steady-state orbits at a station (Fig. 57), in um.
- :func:`spectrum_figure`: harmonic amplitudes nX of the unbalance response (Fig. 58), in um.
- :func:`crack_figures`: computes the data by harmonic balance and returns all three figures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from rotorcheck.config import Crack, UnbalanceMass
from rotorcheck.faults.analysis import unbalance_harmonics, unbalance_orbit
from rotorcheck.faults.crack import rotating_reduction
from rotorcheck.fe.system import MechanicalSystem

__all__ = ["crack_figures", "orbit_figure", "spectrum_figure", "stiffness_change_figure"]

UM = 1e6


def stiffness_change_figure(crack: Crack, poisson: float = 0.3, radius: float = 0.008, n_points: int = 721) -> Figure:
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
    ax.set_title(f"Breathing crack stiffness ({crack.model})")
    ax.grid(True, alpha=0.3)
    ax.legend()
    return fig


def orbit_figure(orbits: Mapping[str, np.ndarray], title: str = "Orbit") -> Figure:
    """Fig. 57: orbits ``{label: xy (N, 2) in m}`` plotted in um with equal axes."""
    fig = Figure(figsize=(5.2, 5.0), layout="constrained")
    ax = fig.add_subplot()
    styles = ["-", "--", ":", "-."]
    for i, (label, xy) in enumerate(orbits.items()):
        xy = np.asarray(xy)
        ax.plot(UM * xy[:, 0], UM * xy[:, 1], styles[i % len(styles)], label=label)
        ax.plot(UM * xy[0, 0], UM * xy[0, 1], "o", color=ax.lines[-1].get_color(), ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (horizontal) displacement (um)")
    ax.set_ylabel("y (vertical) displacement (um)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    return fig


def spectrum_figure(panels: Sequence[Mapping[str, Any]]) -> Figure:
    """Fig. 58: one axes per panel.

    Each panel: ``{"title", "freq_hz" (q,), "amp" (q,) or (q, 2) in m, "scale": "log"|"linear",
    "labels": (optional series names)}``; amplitudes are drawn as stems in um.
    """
    n = len(panels)
    fig = Figure(figsize=(6.4, 2.4 * n), layout="constrained")
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    for ax, p in zip(axes, panels):
        f = np.asarray(p["freq_hz"], dtype=float)
        a = np.abs(np.asarray(p["amp"]))
        a = a[:, None] if a.ndim == 1 else a
        labels = p.get("labels") or [f"series {i + 1}" for i in range(a.shape[1])]
        width = 0.12 * (np.min(np.diff(f)) if f.size > 1 else 1.0)
        base = 0.0 if p.get("scale") != "log" else 1e-6
        for j in range(a.shape[1]):
            x = f + (j - (a.shape[1] - 1) / 2.0) * width
            color = f"C{j}"
            ax.vlines(x, base, UM * a[:, j], lw=2.0, color=color)
            ax.plot(x, UM * a[:, j], "o" if j == 0 else "s", ms=4, color=color, label=labels[j])
        ax.set_xticks(f)
        if p.get("scale") == "log":
            ax.set_yscale("log")
            pos = UM * a[a > 0]
            if pos.size:
                ax.set_ylim(max(pos.min() * 0.3, pos.max() * 1e-6), pos.max() * 3.0)
        else:
            ax.set_ylim(0.0, None)
        ax.set_title(str(p.get("title", "")))
        ax.set_ylabel("amplitude (um)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
    axes[-1].set_xlabel("frequency (Hz)")
    return fig


def crack_figures(
    system: MechanicalSystem,
    crack: Crack,
    unbalance: Sequence[UnbalanceMass],
    station: int = 6,
    speeds_rpm: tuple[float, float] = (1000.0, 750.0),
    max_order: int = 5,
    n_harmonics: int = 10,
) -> dict[str, Any]:
    """Fig. 56-58 for a rig by harmonic balance; returns ``{"stiffness", "orbit", "spectrum"}``
    figures and the plotted ``data`` (harmonic amplitudes in m, orbits in m)."""
    e = next(el for el in system.elements if el.segment == crack.element)
    outs = [system.dof(station, "x"), system.dof(station, "y")]
    data: dict[str, Any] = {}
    s1, s2 = speeds_rpm
    _, xy_h = unbalance_orbit(system, None, s1, unbalance, station, n_harmonics=n_harmonics)
    _, xy_c = unbalance_orbit(system, crack, s1, unbalance, station, n_harmonics=n_harmonics)
    data["orbit_healthy"], data["orbit_cracked"] = xy_h, xy_c
    panels = []
    for label, ck, rpm, scale in (
        (f"healthy, {s1:g} rpm", None, s1, "log"),
        (f"cracked, {s1:g} rpm (log)", crack, s1, "log"),
        (f"cracked, {s1:g} rpm (linear)", crack, s1, "linear"),
        (f"cracked, {s2:g} rpm (linear)", crack, s2, "linear"),
    ):
        orders, ph = unbalance_harmonics(system, ck, rpm, unbalance, outs, n_harmonics)
        keep = (orders >= 1) & (orders <= max_order)
        data[label] = {"orders": orders[keep], "amp": np.abs(ph[keep])}
        panels.append(
            {
                "title": label,
                "freq_hz": orders[keep] * rpm / 60.0,
                "amp": ph[keep],
                "scale": scale,
                "labels": ["x", "y"],
            }
        )
    return {
        "stiffness": stiffness_change_figure(crack, e.poisson, 0.5 * e.outer_diameter),
        "orbit": orbit_figure({"healthy": xy_h, "cracked": xy_c}, f"Station {station} orbit, {s1:g} rpm"),
        "spectrum": spectrum_figure(panels),
        "data": data,
    }
