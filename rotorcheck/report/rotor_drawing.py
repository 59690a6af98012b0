"""The rotor drawn along its axis (matplotlib Figure API, no pyplot).

:func:`draw_rotor` draws a rig onto an axes: axial position (m) on x, radius (m) to scale on y (the
y scale is stretched against x: a shaft is long and thin). Shaft entries as patches (tapered ones as
trapezoids, hollow ones and concentric layers as their two wall bands), discs (to scale by their outer
diameter when the rig gives it, else a hatched marker of fixed size), bearings (a triangle under their
station on a hatched ground; a bearing to a support node draws the pedestal block between), point
masses, station springs, sensor and actuator ports (``s6x``, ``f8x``), the damage port and cracked
elements, candidate elements (outlined, hatched) and element numbers (top axis). The legend sits right
of the axes, outside the drawing. :func:`rotor_figure` is the drawing alone (``rotor.png``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any
from weakref import WeakKeyDictionary

import numpy as np
from matplotlib.figure import Figure
from matplotlib.layout_engine import PlaceHolderLayoutEngine
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, PathPatch, Polygon, Rectangle
from matplotlib.path import Path
from matplotlib.text import Annotation, Text

from rotorcheck.config import DamagePort, Port, RigConfig
from rotorcheck.faults.kinds import fault_elements
from rotorcheck.report.figures import legend_outside, wrap_to_width

__all__ = ["COLOURS", "draw_rig", "draw_rotor", "fit_rotor_labels", "fit_texts", "rig_cracks", "rig_elements",
           "rotor_figure", "settle_labels"]

#: colours of the drawing's parts (kept apart for the common colour-vision deficiencies)
COLOURS = {
    "shaft": "0.85",
    "layer": "0.65",
    "disc": "tab:purple",
    "bearing": "black",
    "sensor": "tab:blue",
    "actuator": "tab:orange",
    "damage": "tab:red",
    "candidate": "tab:cyan",
    "point_mass": "black",
    "spring": "tab:brown",
}
#: half height of a disc given without its diameter, as a multiple of the local shaft radius
DISC_MARKER = 2.5
#: gap (points) between the drawing's top and its lowest port label
LABEL_GAP_PT = 10.0


@dataclass
class _Labels:
    """A drawing's labels: port labels (with the port's radius, m) above its top ``top`` (m), names below."""

    top: float
    ports: list[tuple[Any, float]]
    names: list[tuple[Any, tuple[float, float]]]


#: the labels of each axes :func:`draw_rotor` drew on (for :func:`fit_rotor_labels`)
_LABELS: WeakKeyDictionary[Any, _Labels] = WeakKeyDictionary()


def rig_elements(config: RigConfig) -> list[tuple[int, float, float]]:
    """``(element, z_start, z_end)`` per shaft element (1-based, between stations e and e + 1), m."""
    z = np.asarray(config.stations, dtype=float)
    return [(k, float(z[k - 1]), float(z[k])) for k in range(1, len(z))]


def _shaft_radius(config: RigConfig, station: int) -> float:
    """Largest outer radius (m) of the shaft entries touching ``station``."""
    r = [0.5 * (e.outer_diameter if e.start == station else e.outer_right)
         for e in config.shaft if station in (e.start, e.end)]
    return max(r) if r else 0.0


def _wall(x0: float, x1: float, ro0: float, ro1: float, ri0: float, ri1: float) -> Path:
    """A section's outline: one trapezoid (solid) or its upper and lower wall bands (hollow)."""
    if ri0 <= 0.0 and ri1 <= 0.0:
        return Path([(x0, -ro0), (x1, -ro1), (x1, ro1), (x0, ro0), (x0, -ro0)], closed=True)
    upper = [(x0, ri0), (x1, ri1), (x1, ro1), (x0, ro0), (x0, ri0)]
    lower = [(x0, -ri0), (x1, -ri1), (x1, -ro1), (x0, -ro0), (x0, -ri0)]
    codes = [Path.MOVETO, Path.LINETO, Path.LINETO, Path.LINETO, Path.CLOSEPOLY] * 2
    return Path(upper + lower, codes)


def _disc_half_height(config: RigConfig, disc: Any) -> tuple[float, float, bool]:
    """(half height m, half width m, to scale) of a disc's drawing."""
    length = float(config.stations[-1] - config.stations[0])
    if disc.outer_diameter is not None:
        return 0.5 * float(disc.outer_diameter), 0.5 * float(disc.width or 0.01 * length), True
    return DISC_MARKER * _shaft_radius(config, disc.station), 0.006 * length, False


def drawing_extent(config: RigConfig) -> float:
    """Largest radius (m) the drawing reaches: shaft entries and discs (markers included)."""
    r = [0.5 * max(e.outer_diameter, e.outer_right) for e in config.shaft]
    r += [_disc_half_height(config, d)[0] for d in config.discs]
    return max(r)


def _port_label(prefix: str, port: Port) -> str:
    return f"{prefix}{port.station}{port.direction}"


def draw_rotor(
    ax: Any,
    config: RigConfig,
    *,
    element_colour: Callable[[int], Any] | None = None,
    sensors: Sequence[Port] = (),
    actuators: Sequence[Port] = (),
    damage_port: DamagePort | Port | None = None,
    candidates: Sequence[int] | None = None,
    label_elements: bool = True,
    crack_elements: Sequence[int] = (),
    fontsize: float = 7.0,
    legend: bool = True,
) -> None:
    """Draw ``config``'s rotor on ``ax`` (x: axial position m; y: radius m, to scale).

    ``element_colour(element)``: face colour of each shaft element (1-based; default light grey).
    ``sensors`` / ``actuators``: ports labelled ``s<station><dir>`` / ``f<station><dir>``.
    ``damage_port``: the rig's ``damage`` entry (its element hatched red) or a port.
    ``crack_elements``: elements with a crack (hatched red). ``candidates``: elements outlined and
    hatched. ``label_elements``: element numbers on a top axis. Every artist carries a ``gid``
    (``element <k>``, ``layer <k>``, ``disc <name>``, ``bearing <name>``, ``sensor s6x``, ...).
    """
    if config.kind != "rotor":
        raise ValueError("draw_rotor: a rotor rig is needed (lumped rigs have no shaft)")
    z = np.asarray(config.stations, dtype=float)
    n = z.size
    length = float(z[-1] - z[0])
    U = drawing_extent(config)
    handles: dict[str, Any] = {}
    names: list[Any] = []  # texts kept apart at the end (declutter)
    seen: set[int] = set()
    for e in config.shaft:
        x0, x1 = z[e.start - 1], z[e.end - 1]
        layer = e.start in seen
        seen.add(e.start)
        face = COLOURS["layer"] if layer else (element_colour(e.start) if element_colour is not None
                                               else COLOURS["shaft"])
        path = _wall(x0, x1, 0.5 * e.outer_diameter, 0.5 * e.outer_right, 0.5 * e.inner_diameter,
                     0.5 * e.inner_right)
        p = PathPatch(path, facecolor=face, edgecolor="black", lw=0.7, zorder=2 + layer,
                      gid=f"{'layer' if layer else 'element'} {e.start}")
        ax.add_patch(p)
        if layer:
            handles.setdefault("sleeve / concentric layer", Patch(facecolor=COLOURS["layer"], edgecolor="black"))
    ax.plot([z[0] - 0.02 * length, z[-1] + 0.02 * length], [0.0, 0.0], color="0.3", lw=0.5, ls="-.",
            zorder=1)
    handles.setdefault("shaft (radius to scale)", Patch(facecolor=COLOURS["shaft"], edgecolor="black"))
    marked = sorted(set(crack_elements) | ({damage_port.element} if isinstance(damage_port, DamagePort)
                                           and damage_port.element is not None else set()))
    for ks, colour, hatch, lw, gid, name in ((marked, "damage", "xxx", 1.2, "crack", "cracked / damage element"),
                                            (candidates or (), "candidate", "...", 1.8, "candidate",
                                             "candidate element")):
        for k in ks:  # the element outlined and hatched over its largest outer radius
            x0, x1 = z[k - 1], z[k]
            r = 0.5 * max(e.outer_diameter for e in config.shaft if e.start == k)
            ax.add_patch(Rectangle((x0, -r), x1 - x0, 2 * r, facecolor="none", edgecolor=COLOURS[colour],
                                   hatch=hatch, lw=lw, zorder=4, gid=f"{gid} {k}"))
            handles.setdefault(name, Patch(facecolor="none", edgecolor=COLOURS[colour], hatch=hatch,
                                           lw=lw if gid == "candidate" else None))
    for d in config.discs:
        h, w, to_scale = _disc_half_height(config, d)
        zs = z[d.station - 1]
        ax.add_patch(Rectangle((zs - w, -h), 2 * w, 2 * h, facecolor=COLOURS["disc"], alpha=0.55 if to_scale else 0.35,
                               edgecolor=COLOURS["disc"], hatch=None if to_scale else "////", lw=1.0, zorder=5,
                               gid=f"disc {d.name}"))
        names.append(ax.annotate(d.name, (zs, -h), xytext=(0, -1), textcoords="offset points", ha="center",
                                 va="top", fontsize=fontsize - 1, color=COLOURS["disc"], zorder=6,
                                 gid=f"disc label {d.name}"))
        key = "disc (to scale)" if to_scale else "disc (mass only: marker, not to scale)"
        handles.setdefault(key, Patch(facecolor=COLOURS["disc"], alpha=0.55 if to_scale else 0.35,
                                      hatch=None if to_scale else "////", edgecolor=COLOURS["disc"]))
    bearing_names = _draw_bearings(ax, config, z, U, fontsize, handles)
    for pm in config.point_masses:
        if pm.station <= n:
            ax.plot(z[pm.station - 1], 0.0, "o", color=COLOURS["point_mass"], ms=6, zorder=6,
                    gid=f"point_mass {pm.name}")
            handles.setdefault("point mass", Line2D([], [], marker="o", ls="", color=COLOURS["point_mass"]))
    for s in config.springs:
        zs, r = z[s.station - 1], _shaft_radius(config, s.station)
        yy = -r - np.linspace(0.0, 0.5 * U, 9)
        xx = zs + 0.004 * length * np.array([0, 1, -1, 1, -1, 1, -1, 1, 0])
        ax.plot(xx, yy, color=COLOURS["spring"], lw=1.0, zorder=5, gid=f"spring {s.name}")
        handles.setdefault("spring to ground", Line2D([], [], color=COLOURS["spring"]))
    ports: list[tuple[str, Port, str]] = [("sensor", p, _port_label("s", p)) for p in sensors]
    ports += [("actuator", p, _port_label("f", p)) for p in actuators]
    if damage_port is not None:
        dp = damage_port.port if isinstance(damage_port, DamagePort) else damage_port
        ports.append(("damage", dp, _port_label("d", dp)))
    ports_drawn: list[tuple[Any, float]] = []  # (label, port radius m): placed above the drawing by fit_rotor_labels
    for kind, port, label in ports:
        if port.station is None or not 1 <= port.station <= n:
            continue
        zs, r = z[port.station - 1], _shaft_radius(config, port.station)
        colour = COLOURS[kind]
        ports_drawn.append((ax.annotate(
            label, xy=(zs, r), xytext=(0.0, 0.0), textcoords="offset points", ha="center", va="bottom",
            fontsize=fontsize, color=colour, fontweight="bold", zorder=7, gid=f"{kind} {label}",
            arrowprops={"arrowstyle": "-|>" if kind != "sensor" else "-", "color": colour, "lw": 1.2,
                        "shrinkA": 0.0, "shrinkB": 0.0}), float(r)))
        marker = {"sensor": "s", "actuator": "v", "damage": "X"}[kind]
        if kind != "actuator":  # a probe's tip, the damage port; the force is the arrow
            ax.plot(zs, r, marker, color=colour, ms=5, zorder=7, gid=f"{kind} marker {label}")
        name = {"sensor": "sensor (s<station><dir>)", "actuator": "actuator force (f<station><dir>)",
                "damage": "damage port (d<station><dir>)"}[kind]
        handles.setdefault(name, Line2D([], [], marker=marker, ls="", color=colour))
    ax.set_xlim(z[0] - 0.04 * length, z[-1] + 0.04 * length)
    ax.set_ylim(-1.9 * U, 2.0 * U if ports_drawn else 1.5 * U)
    ax.set_xticks(z, minor=True)
    ax.tick_params(axis="x", which="minor", length=3)
    ax.set_ylabel("radius (m)", fontsize=fontsize + 1)
    ax.tick_params(labelsize=fontsize)
    ax.set_xlabel("axial position (m); minor ticks: stations", fontsize=fontsize + 1)
    ax.tick_params(axis="x", labelbottom=True)  # also when the axes shares x with a panel below
    if label_elements:
        top_ax = ax.secondary_xaxis("top")
        els = rig_elements(config)
        step = max(1, int(np.ceil(len(els) / 30)))
        shown = els[::step]
        top_ax.set_xticks([0.5 * (a + b) for _, a, b in shown], [str(k) for k, _, _ in shown])
        top_ax.tick_params(labelsize=fontsize - 1, length=2, pad=1)
        top_ax.set_xlabel("shaft element", fontsize=fontsize)
    if legend:
        legend_outside(ax, handles.values(), handles.keys(), fontsize=fontsize, frameon=False)
    _LABELS[ax] = _Labels(U, ports_drawn, [(t, tuple(t.xyann)) for t in names + bearing_names])
    fit_rotor_labels(ax)


def _draw_bearings(ax: Any, config: RigConfig, z: np.ndarray, U: float, fontsize: float,
                   handles: dict[str, Any]) -> list[Any]:
    """Bearings as triangles under their station; a bearing to a support node (pedestal) draws the
    pedestal block under its shaft station and the pedestal's own bearings under that."""
    n = z.size
    length = float(z[-1] - z[0])
    w = 0.012 * length
    h = 0.5 * U
    pedestal_at: dict[int, int] = {}  # support node -> shaft station it carries
    for b in config.bearings:
        if b.n_link is not None and b.station <= n < b.n_link:
            pedestal_at[b.n_link] = b.station
        elif b.n_link is not None and b.n_link <= n < b.station:
            pedestal_at[b.station] = b.n_link
    texts: list[Any] = []
    for b in config.bearings:
        if b.station <= n:
            station, depth = b.station, 0.0
        else:  # a pedestal's bearing: drawn under the pedestal block of the station it carries
            station, depth = pedestal_at.get(b.station, 0), 1.0
            if station == 0:
                continue
        zs = z[station - 1]
        y0 = -_shaft_radius(config, station) - depth * 1.1 * h
        ax.add_patch(Polygon([(zs, y0), (zs - w, y0 - h), (zs + w, y0 - h)], closed=True,
                             facecolor="white" if b.n_link is not None else "0.3", edgecolor=COLOURS["bearing"],
                             lw=1.0, zorder=6, gid=f"bearing {b.name}"))
        if b.n_link is not None and b.station <= n:  # the pedestal block under it
            ax.add_patch(Rectangle((zs - 1.3 * w, y0 - 1.1 * h), 2.6 * w, 0.1 * h, facecolor="0.5",
                                   edgecolor="black", lw=0.6, zorder=6, gid=f"pedestal {b.n_link}"))
            handles.setdefault("bearing to a pedestal (support node)",
                               Line2D([], [], marker="^", ls="", mfc="white", mec="black", ms=8))
            continue
        ax.plot([zs - 1.5 * w, zs + 1.5 * w], [y0 - h, y0 - h], color="black", lw=1.0, zorder=6)
        for k in range(5):
            xk = zs - 1.5 * w + 0.75 * w * k
            ax.plot([xk, xk - 0.5 * w], [y0 - h, y0 - 1.3 * h], color="black", lw=0.6, zorder=6)
        texts.append(ax.annotate(b.name, (zs, y0 - 1.3 * h), xytext=(0, -1), textcoords="offset points",
                                 ha="center", va="top", fontsize=fontsize - 1, zorder=6, gid=f"bearing label {b.name}"))
        handles.setdefault("bearing / seal to ground", Line2D([], [], marker="^", ls="", color="0.3", mec="black",
                                                              ms=8))
    return texts


def boxes_overlap(a: Any, b: Any, pad: float = 1.0) -> bool:
    """Whether two display-space boxes overlap (``pad`` pixels of clearance)."""
    return bool(a.x0 < b.x1 + pad and b.x0 < a.x1 + pad and a.y0 < b.y1 + pad and b.y0 < a.y1 + pad)


def text_extent(t: Text) -> Any:
    """Display-space box of a text's own glyphs (an annotation's arrow left out).

    An annotation's text position is updated first, as ``Annotation.get_window_extent`` does, but without
    the arrow's extent that call also computes (clipping the arrow's path: most of the labels' layout time,
    and not part of the box returned)."""
    if isinstance(t, Annotation):
        renderer = t._renderer  # type: ignore[attr-defined]
        if t.get_visible() and t._check_xy(renderer):  # type: ignore[attr-defined]
            if renderer is None:
                renderer = t._renderer = t.get_figure(root=True)._get_renderer()  # type: ignore[attr-defined, union-attr]
            t.update_positions(renderer)
    return Text.get_window_extent(t)


def _layout(fig: Any) -> None:
    """Lay the figure out (a draw without rendering) for the text boxes in display space. Not once
    :func:`settle_labels` froze the layout (``set_layout_engine("none")``): nothing then moves an axes, a
    draw changes no text box (the same figure, pixel for pixel) and costs a full pass over every artist."""
    if not isinstance(fig.get_layout_engine(), PlaceHolderLayoutEngine):
        fig.draw_without_rendering()


def declutter(fig: Any, texts: Sequence[Any], avoid: Sequence[Any] = (), max_moves: int = 12) -> None:
    """Move annotations apart until no two overlap: each text, in turn, steps away from the shaft axis
    (up when it sits above its anchor, down when below) by its own height until it overlaps none placed
    before it and none of ``avoid`` (boxes in display space). Texts in data or offset-point coordinates.
    """
    _layout(fig)  # positions in display space
    placed: list[Any] = list(avoid)
    for t in texts:
        box = text_extent(t)
        sign = -1.0 if t.get_va() == "top" else 1.0
        for _ in range(max_moves):
            if not any(boxes_overlap(box, p) for p in placed):
                break
            dy = sign * (box.height + 1.0)
            if t.anncoords == "offset points":
                x, y = t.xyann
                t.xyann = (x, y + dy * 72.0 / fig.dpi)
            else:
                ax = t.axes
                disp = ax.transData.transform(t.xyann)
                t.xyann = tuple(ax.transData.inverted().transform((disp[0], disp[1] + dy)))
            box = text_extent(t)
        placed.append(box)


def _inside_x(ax: Any, texts: Sequence[Any]) -> None:
    """Shift texts placed in offset points sideways until they lie within the axes' width."""
    box = ax.get_window_extent()
    for t in texts:
        b = text_extent(t)
        dx = max(box.x0 - b.x0, 0.0) - max(b.x1 - box.x1, 0.0)
        if dx and t.anncoords == "offset points":
            x, y = t.xyann
            t.xyann = (x + dx * 72.0 / t.figure.dpi, y)


def fit_texts(ax: Any, texts: Sequence[Any], reset: Callable[[], None], margin_px: float = 3.0,
              tries: int = 6) -> None:
    """Keep ``texts`` (annotations in offset points) apart and inside ``ax``: ``reset`` puts them at their
    wanted places for the current scale, they are shifted into the axes' width and moved apart
    (:func:`declutter`), then the (linear) y limits grow until every text lies inside the axes."""
    if not texts:
        return
    fig = ax.figure
    for _ in range(tries):
        _layout(fig)
        reset()
        _inside_x(ax, texts)
        declutter(fig, texts)
        box = ax.get_window_extent()
        boxes = [text_extent(t) for t in texts]
        over_top = max(b.y1 for b in boxes) - (box.y1 - margin_px)
        over_bottom = (box.y0 + margin_px) - min(b.y0 for b in boxes)
        if over_top <= 0.0 and over_bottom <= 0.0:
            return
        y0, y1 = ax.get_ylim()
        per_px = (y1 - y0) / max(box.height, 1.0)
        ax.set_ylim(y0 - 1.15 * max(over_bottom, 0.0) * per_px, y1 + 1.15 * max(over_top, 0.0) * per_px)


def fit_rotor_labels(ax: Any) -> None:
    """Place a drawing's labels for the axes' current size (:func:`draw_rotor` calls it; call it again when
    the figure's layout changes afterwards, e.g. a colour bar or another panel added): port labels above the
    drawing, stacked where they would overlap, disc and bearing names below it, all inside the axes (the
    y limits grow to hold them)."""
    lab = _LABELS.get(ax)
    if lab is None:
        return
    fig = ax.figure

    def reset() -> None:
        y0, y1 = ax.get_ylim()
        pt_per_m = ax.get_window_extent().height / (y1 - y0) * 72.0 / fig.dpi
        for t, r in lab.ports:
            t.xyann = (0.0, (lab.top - r) * pt_per_m + LABEL_GAP_PT)
        for t, xy in lab.names:
            t.xyann = xy

    fit_texts(ax, [t for t, _ in lab.ports] + [t for t, _ in lab.names], reset)


def settle_labels(fig: Any, *fits: Callable[[], None]) -> None:
    """A figure's last step: ``fits`` (label placements such as :func:`fit_rotor_labels`) for its layout,
    the layout frozen, then ``fits`` again, so that the labels stay where they were placed when the figure
    is drawn or saved (a layout engine would move the axes after the y limits grew)."""
    for fit in fits:
        fit()
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    for fit in fits:
        fit()


def rig_cracks(config: RigConfig) -> list[int]:
    """Elements of the rig's faults (1-based): :func:`rotorcheck.faults.kinds.fault_elements`."""
    return fault_elements(config)


def draw_rig(ax: Any, config: RigConfig, **kw: Any) -> None:
    """:func:`draw_rotor` with the rig's own sensor, actuator, damage port and crack faults marked."""
    ports = config.ports
    draw_rotor(ax, config, sensors=[ports.sensor] if ports is not None else [],
               actuators=[ports.actuator] if ports is not None else [], damage_port=config.damage,
               crack_elements=rig_cracks(config), **kw)


def rotor_figure(config: RigConfig, title: str | None = None) -> Figure:
    """The rig alone: shaft, discs, bearings, the rig's sensor, actuator, damage port and cracks."""
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    ax = fig.add_subplot()
    draw_rig(ax, config)
    ax.set_title(wrap_to_width(title or f"Rotor of {config.rig_id}: {len(config.stations)} stations, "
                               f"{len(rig_elements(config))} shaft elements", 0.7 * fig.get_figwidth(), 10),
                 fontsize=10)
    settle_labels(fig, lambda: fit_rotor_labels(ax))  # the layout is final: the drawing's labels placed for it
    return fig
