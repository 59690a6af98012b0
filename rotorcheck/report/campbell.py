"""Campbell diagram and mode-shape plots (matplotlib Figure API, no pyplot, no global style)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypedDict

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.typing import ColorType, LineStyleType

from rotorcheck.config import RigConfig
from rotorcheck.fe.elements import TimoshenkoBeam, beam_shape_functions
from rotorcheck.fe.modal import CampbellResult, campbell, modes
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.report.figures import wrap_to_width
from rotorcheck.report.rotor_drawing import (
    boxes_overlap,
    draw_rig,
    fit_rotor_labels,
    rig_cracks,
    settle_labels,
    text_extent,
)
from rotorcheck.units import UNITS


class WhirlStyle(TypedDict):
    """Line keyword arguments of one whirl direction."""

    color: ColorType
    linestyle: LineStyleType
    zorder: float


#: forward and backward differ in colour and line style; backward is drawn above forward (a pair that
#: barely splits shows the forward line through the backward one's gaps)
WHIRL_STYLE: dict[str, WhirlStyle] = {
    "forward": {"color": "tab:red", "linestyle": "-", "zorder": 2.0},
    "backward": {"color": "tab:blue", "linestyle": "--", "zorder": 3.0},
    "planar": {"color": "tab:gray", "linestyle": ":", "zorder": 2.5},
    "none": {"color": "tab:gray", "linestyle": "-", "zorder": 2.0},
}
WHIRL_LETTER = {"forward": "F", "backward": "B", "planar": "P", "none": ""}
#: spin speed units of the x axis: factor from rpm
SPEED_UNITS: dict[str, float] = {u: 1.0 / UNITS["speed"][u] for u in ("rpm", "Hz")}
#: critical-speed markers per running-speed order
ORDER_MARKERS = {1: "o", 2: "s", 3: "D", 4: "^", 5: "v"}
OPERATING_COLOUR = "tab:green"


def speed_factor(speed_unit: str) -> float:
    """Factor from rpm to ``speed_unit`` (``rpm`` | ``Hz``); ValueError naming the choices."""
    if speed_unit not in SPEED_UNITS:
        raise ValueError(f"speed_unit must be one of {', '.join(SPEED_UNITS)}, got {speed_unit!r}")
    return SPEED_UNITS[speed_unit]


def speed_text(speed_rpm: float, speed_unit: str = "rpm") -> str:
    """``1000 rpm`` or ``16.67 Hz``."""
    return f"{speed_rpm:.0f} rpm" if speed_unit == "rpm" else f"{speed_rpm / 60.0:.4g} Hz"


Criticals = dict[int, tuple[tuple[float, ...], tuple[int, ...]]]


def order_criticals(system: MechanicalSystem, result: CampbellResult, orders: Sequence[int] = (1, 2)) -> Criticals:
    """Critical speeds (rpm) and their branches per running-speed order: forward branches of ``result``
    crossing ``order`` x speed, root-found by :func:`rotorcheck.fe.modal.campbell` (same speeds and
    branches as ``result``)."""
    out: Criticals = {}
    for n in orders:
        r = result if n == result.order else campbell(system, result.speeds_rpm, result.frequency_hz.shape[1],
                                                      order=n)
        out[n] = (r.critical_speeds_rpm, r.critical_branch)
    return out


def _whirl_runs(labels: np.ndarray) -> list[tuple[int, int, str]]:
    """(first, last, label) index runs of one branch; the segment k..k+1 takes the label at k + 1."""
    runs: list[tuple[int, int, str]] = []
    for k in range(labels.size - 1):
        lab = str(labels[k + 1])
        if runs and runs[-1][2] == lab:
            runs[-1] = (runs[-1][0], k + 1, lab)
        else:
            runs.append((k, k + 1, lab))
    return runs


def _spread(wanted: Sequence[float], gap: float, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    """Positions near ``wanted`` at least ``gap`` apart within [lo, hi] (when they fit), order kept."""
    y = np.asarray(wanted, dtype=float)
    order = np.argsort(y, kind="stable")
    v = np.clip(y[order], lo, hi)
    for i in range(1, v.size):
        v[i] = max(v[i], v[i - 1] + gap)
    if v.size and v[-1] > hi:
        v[-1] = hi
        for i in range(v.size - 2, -1, -1):
            v[i] = min(v[i], v[i + 1] - gap)
    out = np.empty_like(v)
    out[order] = v
    return out


def _end_labels(ax: Any, x: np.ndarray, ys: Sequence[np.ndarray], texts: Sequence[str],
                colours: Sequence[Any], fontsize: float = 8.0) -> list[Any]:
    """Labels right of ``ax`` at each curve's last finite point, spread apart, with leader lines."""
    fig = ax.figure
    fig.draw_without_rendering()
    height = ax.get_window_extent().height
    gap = (fontsize * 1.25 * fig.dpi / 72.0 + 1.0) / max(height, 1.0)
    lo, hi = ax.get_ylim()
    ends, frac = [], []
    for y in ys:
        ok = np.nonzero(np.isfinite(y) & (y <= hi) & (y >= lo))[0]
        k = int(ok[-1]) if ok.size else -1
        ends.append(k)
        frac.append((y[k] - lo) / (hi - lo) if k >= 0 else np.nan)
    shown = [i for i, k in enumerate(ends) if k >= 0]
    pos = _spread([frac[i] for i in shown], gap)
    out = []
    for i, yf in zip(shown, pos):
        k = ends[i]
        out.append(ax.annotate(texts[i], (x[k], ys[i][k]), xytext=(1.0 + 0.012, yf), textcoords="axes fraction",
                               va="center", ha="left", fontsize=fontsize, color=colours[i], annotation_clip=False,
                               fontweight="bold", gid=f"label {texts[i]}",
                               arrowprops={"arrowstyle": "-", "lw": 0.5, "color": "0.5", "shrinkA": 1,
                                           "shrinkB": 0}))
    return out


_CANDIDATES = ((6, -6, "left", "top"), (6, 6, "left", "bottom"), (-6, 6, "right", "bottom"),
               (-6, -6, "right", "top"), (6, -20, "left", "top"), (-6, 20, "right", "bottom"),
               (6, 20, "left", "bottom"), (-6, -20, "right", "top"))

Candidate = tuple[tuple[float, float], tuple[float, float], str, str]  # anchor (data), offset (pt), ha, va


def _place_apart(ax: Any, t: Any, candidates: Sequence[Candidate], placed: list[Any],
                 lines: Sequence[Line2D] = ()) -> None:
    """Put annotation ``t`` at the first candidate where it stays inside ``ax`` and overlaps no box in
    ``placed`` and crosses none of ``lines``; else at the first candidate that avoids the boxes, else
    the first. Appends its box to ``placed``."""
    inside = ax.get_window_extent()
    paths = [ln.get_transform().transform_path(ln.get_path()) for ln in lines]
    fallback: Candidate | None = None

    def put(c: Candidate) -> Any:
        t.xy, t.xyann = c[0], c[1]
        t.set_ha(c[2])
        t.set_va(c[3])
        return text_extent(t)

    for c in candidates:
        box = put(c)
        fits = box.x0 >= inside.x0 and box.x1 <= inside.x1 and box.y0 >= inside.y0 and box.y1 <= inside.y1
        if not fits or any(boxes_overlap(box, p, 2.0) for p in placed):
            continue
        if not any(path.intersects_bbox(box.padded(1.0), filled=False) for path in paths):
            placed.append(box)
            return
        fallback = fallback or c
    placed.append(put(fallback or candidates[0]))


def campbell_figure(
    result: CampbellResult,
    orders: Sequence[int] = (1, 2),
    max_frequency_hz: float | None = None,
    title: str | None = None,
    *,
    rig_id: str = "",
    operating_speed_rpm: float | None = None,
    speed_unit: str = "rpm",
    criticals: Criticals | None = None,
) -> Figure:
    """Campbell diagram: damped natural frequency (Hz) of each tracked branch vs spin speed (``speed_unit``
    ``rpm`` | ``Hz``) above its damping ratio (%).

    Forward whirl red solid, backward blue dashed (drawn above), planar grey dotted, styled per speed
    step (a branch may change direction). Each branch is labelled right of the axes (number and whirl at
    the highest speed, e.g. ``3B``); running-speed order lines ``nX`` labelled inside the axes; critical
    speeds (forward branches crossing ``nX``: ``criticals`` from :func:`order_criticals`, else the
    result's own order) marked and labelled; ``operating_speed_rpm`` a vertical line. Legend below the
    axes, outside the data.
    """
    unit = speed_factor(speed_unit)
    fig = Figure(figsize=(8.5, 7.2), layout="constrained")
    ax, dx = fig.subplots(2, 1, sharex=True, height_ratios=(3.0, 1.25))
    rpm = result.speeds_rpm
    x = unit * rpm
    f = result.frequency_hz
    zeta = 100.0 * result.damping_ratio
    labels = result.whirl
    n_branch = f.shape[1]
    top = max_frequency_hz if max_frequency_hz is not None else 1.08 * float(np.nanmax(f))
    names, colours = [], []
    for b in range(n_branch):
        for k0, k1, lab in _whirl_runs(labels[:, b]):
            style = WHIRL_STYLE[lab]
            seg = slice(k0, k1 + 1)
            ax.plot(x[seg], f[seg, b], lw=1.7, gid=f"branch {b + 1} {lab}", **style)
            dx.plot(x[seg], zeta[seg, b], lw=1.4, gid=f"damping {b + 1} {lab}", **style)
        whirl = result.branch_whirl[b]
        names.append(f"{b + 1}{WHIRL_LETTER.get(whirl, '')}")
        colours.append(WHIRL_STYLE[whirl]["color"])
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(0.0, top)
    styles = {1: "-", 2: "-."}
    for n in orders:
        ax.plot(x, n * rpm / 60.0, color="black", lw=0.9, ls=styles.get(n, ":"), zorder=1.5, gid=f"order {n}X")
    crit = criticals if criticals is not None else {result.order: (result.critical_speeds_rpm,
                                                                    result.critical_branch)}
    handles = [Line2D([], [], lw=1.7, label="forward whirl", **WHIRL_STYLE["forward"]),
               Line2D([], [], lw=1.7, label="backward whirl", **WHIRL_STYLE["backward"])]
    if any(str(v) == "planar" for v in labels[1:].ravel()):
        handles.append(Line2D([], [], lw=1.7, label="planar", **WHIRL_STYLE["planar"]))
    handles.append(Line2D([], [], color="black", lw=0.9, label="running speed x order (nX)"))
    for n, (speeds, _) in sorted(crit.items()):
        cs = np.asarray(speeds, dtype=float)
        mk = ORDER_MARKERS.get(n, "o")
        ax.plot(unit * cs, n * cs / 60.0, mk, ls="", mfc="white", mec="black", mew=1.3, ms=8, zorder=6,
                gid=f"critical {n}X")
        none = "" if cs.size else f" (none up to {speed_text(rpm[-1], speed_unit)})"
        handles.append(Line2D([], [], marker=mk, ls="", mfc="white", mec="black", mew=1.3,
                              label=f"critical speed: forward branch crosses {n}X{none}"))
    if operating_speed_rpm is not None:
        for a in (ax, dx):
            a.axvline(unit * operating_speed_rpm, color=OPERATING_COLOUR, lw=1.6, ls=(0, (6, 2)), zorder=1.6,
                      gid="operating speed")
        handles.append(Line2D([], [], color=OPERATING_COLOUR, lw=1.6, ls=(0, (6, 2)),
                              label=f"operating speed {speed_text(operating_speed_rpm, speed_unit)}"))
    dx.axhline(0.0, color="black", lw=0.6)
    ax.set_ylabel("damped natural frequency (Hz)")
    dx.set_ylabel("damping ratio (%)\n(< 0: unstable)", fontsize=9)
    dx.set_xlabel(f"spin speed ({speed_unit})")
    for a in (ax, dx):
        a.grid(True, lw=0.3)
    span = f"{speed_text(rpm[0], speed_unit)} to {speed_text(rpm[-1], speed_unit)}"
    op = "" if operating_speed_rpm is None else f"; operating speed {speed_text(operating_speed_rpm, speed_unit)}"
    fig.suptitle(wrap_to_width(title or f"Campbell diagram: {rig_id or 'rotor'}, {span}{op}",
                               0.95 * fig.get_figwidth(), 11), fontsize=11)
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=8, frameon=False)
    # labels: branch numbers right of both panels, then order, operating-speed and critical labels inside
    _end_labels(ax, x, [f[:, b] for b in range(n_branch)], names, colours)
    _end_labels(dx, x, [zeta[:, b] for b in range(n_branch)], names, colours, fontsize=7.0)
    fig.draw_without_rendering()
    fig.set_layout_engine("none")  # freeze the layout: the labels below are placed in display space
    placed: list[Any] = []
    branch_lines = [ln for ln in ax.get_lines() if str(ln.get_gid()).startswith("branch")]
    for n in orders:
        x_end = min(rpm[-1], 0.9 * top * 60.0 / n)
        t = ax.annotate(f"{n}X", (0.0, 0.0), xytext=(0.0, 0.0), textcoords="offset points", fontsize=9,
                        fontweight="bold", gid=f"order label {n}X")
        cands: list[Candidate] = []
        for frac in (0.93, 0.82, 0.7, 0.58, 0.46, 0.34):
            xy = (unit * frac * x_end, n * frac * x_end / 60.0)
            cands += [(xy, (-3.0, 3.0), "right", "bottom"), (xy, (3.0, -3.0), "left", "top")]
        _place_apart(ax, t, cands, placed, branch_lines)
    if operating_speed_rpm is not None:
        xo = unit * operating_speed_rpm
        right = xo > 0.5 * (x[0] + x[-1])
        t = ax.annotate(f"operating\n{speed_text(operating_speed_rpm, speed_unit)}", (xo, 1.0),
                        xycoords=("data", "axes fraction"), xytext=(-4 if right else 4, -4),
                        textcoords="offset points", ha="right" if right else "left", va="top", fontsize=8,
                        color=OPERATING_COLOUR, gid="operating speed label")
        placed.append(text_extent(t))
    for n, (speeds, branches) in sorted(crit.items()):
        for c, b in zip(speeds, branches):
            xy = (unit * c, n * c / 60.0)
            t = ax.annotate(f"{speed_text(c, speed_unit)} ({n}X, {names[b]})", xy, xytext=(6.0, -6.0),
                            textcoords="offset points", fontsize=7.5, gid=f"critical label {n}X")
            _place_apart(ax, t, [(xy, (dx_, dy_), ha, va) for dx_, dy_, ha, va in _CANDIDATES], placed,
                         branch_lines)
    return fig


def interpolated_shape(
    system: MechanicalSystem, shape: np.ndarray, plane: str = "x", points_per_element: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Deflection of one complex mode shape along the shaft, (z (m), w (complex)).

    Uses the Timoshenko displacement shape functions of each element (x plane: [u, psi];
    y plane: [v, -theta]).
    """
    xi = np.linspace(0.0, 1.0, points_per_element + 1)
    zs: list[np.ndarray] = []
    ws: list[np.ndarray] = []
    a, b = (0, 3) if plane == "x" else (1, 2)
    sgn = 1.0 if plane == "x" else -1.0
    pos = np.asarray(system.node_positions)
    for k, info in enumerate(system.elements):
        beam = TimoshenkoBeam.from_info(info)
        nw, _ = beam_shape_functions(xi, info.length, beam.phi)
        i, j = 4 * info.node_i, 4 * info.node_j
        q = np.array([shape[i + a], sgn * shape[i + b], shape[j + a], sgn * shape[j + b]])
        sl = slice(None) if k == 0 else slice(1, None)
        zs.append((pos[info.node_i] + xi * info.length)[sl])
        ws.append((nw @ q)[sl])
    return np.concatenate(zs), np.concatenate(ws)


def _signed_amplitude(w: np.ndarray) -> np.ndarray:
    """The plane's deflected shape at the instant of its largest deflection: ``Re(w e^{-j phi})`` with
    ``phi`` the phase of the largest entry (real, continuous, signed; = |w| signed by phase for a planar
    mode)."""
    ref = w[np.argmax(np.abs(w))] if w.size else 1.0
    if abs(ref) == 0:
        return np.zeros(w.shape)
    return np.real(w * np.conj(ref) / abs(ref))


def plane_pair(shapes: np.ndarray, n_shaft: int) -> np.ndarray:
    """The x-plane and the y-plane member of a degenerate pair's span (columns 0 and 1).

    ``shapes`` (n_dof, 2): any basis of the pair. x plane: the combination with no y-plane DOF
    (v, theta); y plane: none of the x-plane DOF (u, psi). Each scaled to a largest translation of 1.
    """
    idx = np.arange(0, n_shaft, 4)
    x_dofs = np.concatenate([idx, idx + 3])
    y_dofs = np.concatenate([idx + 1, idx + 2])
    out = np.empty_like(shapes)
    for col, kill in ((0, y_dofs), (1, x_dofs)):
        c = np.linalg.svd(shapes[kill], full_matrices=False)[2][-1].conj()
        v = shapes @ c
        trans = np.concatenate([v[idx], v[idx + 1]])
        out[:, col] = v / trans[np.argmax(np.abs(trans))]
    return out


def displayed_modes(system: MechanicalSystem, speed_rpm: float, n_modes: int) -> tuple[Any, np.ndarray, list[str]]:
    """The modes the table of ``rotorcheck model`` lists (:func:`rotorcheck.fe.modal.modes` with
    ``n_modes``, as :func:`rotorcheck.fe.modal.model_summary`), the shapes drawn (a degenerate pair as its
    x-plane and y-plane shapes: its basis is arbitrary) and a note per mode."""
    md = modes(system, speed_rpm, n_modes=n_modes)
    shapes = md.shapes.copy()
    notes = [""] * len(md)
    i = 0
    while i < len(md) - 1:
        f0, f1 = md.frequency_hz[i], md.frequency_hz[i + 1]
        if system.kind == "rotor" and abs(f1 - f0) <= 1e-6 * abs(f0):
            shapes[:, i : i + 2] = plane_pair(md.shapes[:, i : i + 2], system.n_shaft_dof)
            notes[i] = f"pair with {i + 2}: x plane"
            notes[i + 1] = f"pair with {i + 1}: y plane"
            i += 2
        else:
            i += 1
    return md, shapes, notes


def mode_shape_figure(
    system: MechanicalSystem,
    speed_rpm: float = 0.0,
    n_modes: int | None = None,
    title: str | None = None,
    *,
    config: RigConfig | None = None,
) -> Figure:
    """The modes of the model table at ``speed_rpm`` (``n_modes``, default the rig's ``analysis.n_modes``),
    numbered as in the table, one panel each with its frequency, damping and whirl.

    Each panel shows the x (solid) and y (dashed) deflection along the shaft, each plane at the instant
    of its largest deflection (largest x translation of the mode = 1, as in the table). A degenerate pair
    (an isotropic rotor at rest) is drawn as its pure x-plane and pure y-plane shapes. With ``config``: the
    rotor drawing on top and, in each panel, bearings (triangles), discs (bands), the sensor, actuator and
    the cracked / damage element at their axial positions.
    """
    n = n_modes if n_modes is not None else (config.analysis.n_modes if config is not None else 6)
    md, shapes, notes = displayed_modes(system, speed_rpm, n)
    rig = config.rig_id if config is not None else ""
    speed = "at standstill (0 rpm)" if speed_rpm == 0 else f"at {speed_rpm:g} rpm"
    head = title or f"Mode shapes: {rig + ' ' if rig else ''}{speed}, modes 1-{len(md)} of the model table"
    if system.kind != "rotor":
        fig = Figure(figsize=(7.0, 1.6 + 1.5 * len(md)), layout="constrained")
        lumped_axes = fig.subplots(len(md), 1, sharex=True, squeeze=False)[:, 0]
        for i, ax in enumerate(lumped_axes):
            names = list(system.mass_index)
            ax.bar(names, md.shapes[:, i].real, color="tab:blue")
            ax.set_title(f"mode {i + 1}: {md.frequency_hz[i]:.2f} Hz", fontsize=8, loc="left")
            ax.set_ylabel("normalised\ndisplacement", fontsize=8)
            ax.axhline(0.0, color="black", lw=0.5)
        fig.suptitle(wrap_to_width(head.replace(" at standstill (0 rpm)", ""), 0.95 * fig.get_figwidth(), 10),
                     fontsize=10)
        return fig
    ncol = 2 if len(md) > 1 else 1
    nrow = int(np.ceil(len(md) / ncol))
    fig = Figure(figsize=(10.0, 2.4 + 1.9 * nrow), layout="constrained")
    top = 1 if config is not None else 0
    gs = fig.add_gridspec(nrow + top, ncol, height_ratios=([1.5] if top else []) + [1.0] * nrow)
    axes: list[Any] = []
    for i in range(len(md)):
        share = axes[0] if axes else None
        axes.append(fig.add_subplot(gs[top + i // ncol, i % ncol], sharex=share))
    stations = system.station_positions
    marks = _feature_marks(system, config)
    for i, ax in enumerate(axes):
        peak = 1.0
        for plane, style, colour in (("x", "-", "tab:blue"), ("y", "--", "tab:orange")):
            z, w = interpolated_shape(system, shapes[:, i], plane)
            d = _signed_amplitude(w)
            peak = max(peak, float(np.abs(d).max()))
            ax.plot(z, d, style, color=colour, lw=1.5, gid=f"shape {i + 1} {plane}", label=f"{plane} deflection")
        ax.axhline(0.0, color="black", lw=0.5)
        _mark_features(ax, marks)
        ax.set_ylim(-1.25 * peak, 1.25 * peak)
        ax.set_xticks(stations, minor=True)
        ax.grid(True, which="minor", axis="x", lw=0.3)
        whirl = md.whirl[i] if np.isfinite(md.whirl_ratio[i]) else ""
        extra = notes[i] or whirl
        ax.set_title(f"mode {i + 1}: {md.frequency_hz[i]:.2f} Hz, zeta {100 * md.damping_ratio[i]:.2f} %"
                     + (f", {extra}" if extra else ""), fontsize=8.5, loc="left")
        if i % ncol == 0:
            ax.set_ylabel("normalised deflection\n(at its largest, -)", fontsize=8)
        if i >= len(md) - ncol:
            ax.set_xlabel("axial position (m)", fontsize=8)
        ax.tick_params(labelsize=7)
    if config is not None:
        rax = fig.add_subplot(gs[0, :], sharex=axes[0])
        draw_rig(rax, config, fontsize=6.5)
    handles, labels = axes[0].get_legend_handles_labels()
    handles += [h for _, h in marks["legend"]]
    labels += [k for k, _ in marks["legend"]]
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(wrap_to_width(head, 0.95 * fig.get_figwidth(), 10), fontsize=10)
    if config is not None:
        settle_labels(fig, lambda: fit_rotor_labels(rax))  # the layout is final: the drawing's labels placed for it
    return fig


def _feature_marks(system: MechanicalSystem, config: RigConfig | None) -> dict[str, Any]:
    """Axial positions (m) of bearings, discs, sensor, actuator and cracked elements to mark."""
    z = system.station_positions
    n = z.size
    out: dict[str, Any] = {"bearing": [], "disc": [], "sensor": [], "actuator": [], "crack": [], "legend": []}
    for kind, _, st in system.features:
        if kind in ("bearing", "disc") and st <= n:
            out[kind].append(float(z[st - 1]))
    if config is not None:
        if config.ports is not None:
            for kind in ("sensor", "actuator"):
                p = getattr(config.ports, kind)
                if p.station is not None:
                    out[kind].append(float(z[p.station - 1]))
        els = set(rig_cracks(config))
        if config.damage is not None and config.damage.element is not None:
            els.add(config.damage.element)
        out["crack"] = [(float(z[k - 1]), float(z[k])) for k in sorted(els)]
    leg = out["legend"]
    if out["bearing"]:
        leg.append(("bearing", Line2D([], [], marker="^", ls="", color="black", ms=7)))
    if out["disc"]:
        leg.append(("disc", Patch(facecolor="tab:purple", alpha=0.3)))
    if out["sensor"]:
        leg.append(("sensor", Line2D([], [], marker="s", ls=":", color="tab:blue", ms=5)))
    if out["actuator"]:
        leg.append(("actuator", Line2D([], [], marker="v", ls=":", color="tab:orange", ms=5)))
    if out["crack"]:
        leg.append(("cracked / damage element", Patch(facecolor="none", edgecolor="tab:red", hatch="xx")))
    return out


def _mark_features(ax: Any, marks: dict[str, Any]) -> None:
    """Bearings, discs, sensor, actuator and cracked elements on a mode-shape panel (``gid`` = kind)."""
    base = ax.get_xaxis_transform()  # x in data, y in axes fraction
    for zb in marks["bearing"]:
        ax.plot(zb, 0.0, marker="^", color="black", ms=7, transform=base, clip_on=False, gid="bearing")
    for zd in marks["disc"]:
        ax.axvline(zd, color="tab:purple", lw=5, alpha=0.3, gid="disc")
    for zs in marks["sensor"]:
        ax.axvline(zs, color="tab:blue", lw=0.9, ls=":", gid="sensor")
        ax.plot(zs, 1.0, marker="s", color="tab:blue", ms=5, transform=base, clip_on=False, gid="sensor")
    for za in marks["actuator"]:
        ax.axvline(za, color="tab:orange", lw=0.9, ls=":", gid="actuator")
        ax.plot(za, 1.0, marker="v", color="tab:orange", ms=5, transform=base, clip_on=False, gid="actuator")
    for z0, z1 in marks["crack"]:
        ax.axvspan(z0, z1, facecolor="none", edgecolor="tab:red", hatch="xx", lw=0.0, alpha=0.6, gid="crack")
