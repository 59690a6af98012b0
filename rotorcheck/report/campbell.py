"""Campbell diagram and mode-shape plots (matplotlib Figure API, no pyplot, no global style)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypedDict

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.typing import ColorType, LineStyleType

from rotorcheck.fe.elements import TimoshenkoBeam, beam_shape_functions
from rotorcheck.fe.modal import CampbellResult, modes
from rotorcheck.fe.system import MechanicalSystem


class WhirlStyle(TypedDict):
    """Line keyword arguments of one whirl direction."""

    color: ColorType
    linestyle: LineStyleType


WHIRL_STYLE: dict[str, WhirlStyle] = {
    "forward": {"color": "tab:red", "linestyle": "-"},
    "backward": {"color": "tab:green", "linestyle": "--"},
    "planar": {"color": "tab:gray", "linestyle": ":"},
    "none": {"color": "tab:blue", "linestyle": "-"},
}


def campbell_figure(
    result: CampbellResult,
    orders: Sequence[int] = (1, 2),
    max_frequency_hz: float | None = None,
    title: str = "Campbell diagram",
) -> Figure:
    """Tracked branches vs speed: forward red solid, backward green dashed; nX lines; criticals.

    Each branch is styled by its whirl at every speed step (a branch may change direction).
    """
    fig = Figure(figsize=(7.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    rpm = result.speeds_rpm
    f = result.frequency_hz
    labels = result.whirl
    for b in range(f.shape[1]):
        for k in range(rpm.size - 1):
            style = WHIRL_STYLE[str(labels[k + 1, b])]
            ax.plot(rpm[k : k + 2], f[k : k + 2, b], lw=1.6, **style)
        ax.annotate(
            f"{b + 1}",
            (rpm[-1], f[-1, b]),
            xytext=(3, 0),
            textcoords="offset points",
            fontsize=8,
            va="center",
        )
    top = max_frequency_hz if max_frequency_hz is not None else 1.05 * np.nanmax(f)
    for n in orders:
        ax.plot(rpm, n * rpm / 60.0, color="black", lw=0.8, ls="-." if n > 1 else "-")
        x_end = min(rpm[-1], top * 60.0 / n)
        ax.annotate(f"{n}X", (x_end, n * x_end / 60.0), fontsize=8, ha="right", va="bottom")
    if result.critical_speeds_rpm:
        cs = np.asarray(result.critical_speeds_rpm)
        ax.plot(cs, result.order * cs / 60.0, "o", mfc="none", mec="black", ms=8, zorder=5)
        for c in cs:
            ax.annotate(
                f"{c:.0f} rpm",
                (c, result.order * c / 60.0),
                xytext=(6, -12),
                textcoords="offset points",
                fontsize=8,
            )
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_ylim(0.0, top)
    ax.set_xlabel("spin speed (rpm)")
    ax.set_ylabel("damped natural frequency (Hz)")
    ax.set_title(title)
    ax.grid(True, lw=0.3)
    handles = [
        Line2D([], [], lw=1.6, label="forward", **WHIRL_STYLE["forward"]),
        Line2D([], [], lw=1.6, label="backward", **WHIRL_STYLE["backward"]),
        Line2D([], [], color="black", lw=0.8, label="running speed multiples"),
        Line2D([], [], marker="o", ls="", mfc="none", mec="black", label="critical speed"),
    ]
    ax.legend(handles=handles, loc="upper left", fontsize=8)
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
    """|w| signed by its phase relative to the largest entry (the plane's own deflected shape)."""
    ref = w[np.argmax(np.abs(w))] if w.size else 1.0
    if abs(ref) == 0:
        return np.zeros(w.shape)
    return np.abs(w) * np.sign(np.real(w * np.conj(ref)) + 0.0)


def mode_shape_figure(
    system: MechanicalSystem,
    speed_rpm: float = 0.0,
    n_modes: int = 3,
    title: str | None = None,
) -> Figure:
    """Mode shapes of the lowest distinct modes at ``speed_rpm`` (degenerate pairs shown once).

    Each panel shows the x and y deflection along the shaft (amplitude signed by phase relative to
    the plane's largest deflection; largest translation of the mode = 1), with bearings
    (triangles), discs (bars) and stations marked.
    """
    md = modes(system, speed_rpm, n_modes=2 * n_modes + 2)  # degenerate pairs count twice
    picked: list[int] = []
    for i in range(len(md)):
        f = md.frequency_hz[i]
        if picked and abs(f - md.frequency_hz[picked[-1]]) <= 1e-6 * f:
            continue
        picked.append(i)
        if len(picked) == n_modes:
            break
    fig = Figure(figsize=(7.0, 1.6 + 1.5 * len(picked)), layout="constrained")
    axes = fig.subplots(len(picked), 1, sharex=True, squeeze=False)[:, 0]
    if system.kind != "rotor":
        for ax, i in zip(axes, picked):
            names = list(system.mass_index)
            ax.bar(names, md.shapes[:, i].real, color="tab:blue")
            ax.set_ylabel(f"{md.frequency_hz[i]:.2f} Hz", fontsize=8)
            ax.axhline(0.0, color="black", lw=0.5)
        fig.suptitle(title or "Mode shapes")
        return fig
    stations = system.station_positions
    for ax, i in zip(axes, picked):
        top = 1.0
        for plane, style in (("x", "-"), ("y", "--")):
            z, w = interpolated_shape(system, md.shapes[:, i], plane)
            d = _signed_amplitude(w)
            ax.plot(1e3 * z, d, style, lw=1.4, label=plane)
            top = max(top, float(np.abs(d).max()))
        ax.axhline(0.0, color="black", lw=0.5)
        base = ax.get_xaxis_transform()  # x in data, y in axes fraction
        for kind, _, st in system.features:
            zs = 1e3 * stations[st - 1]
            if kind == "bearing":
                ax.plot(zs, 0.0, marker="^", color="black", ms=7, transform=base, clip_on=False)
            elif kind == "disc":
                ax.axvline(zs, color="tab:purple", lw=4, alpha=0.35)
            else:
                ax.plot(zs, 0.0, marker="s", color="tab:orange", ms=5, transform=base, clip_on=False)
        ax.set_ylim(-1.15 * top, 1.15 * top)
        ax.set_xticks(1e3 * stations, minor=True)
        ax.grid(True, which="minor", axis="x", lw=0.3)
        label = md.whirl[i] if speed_rpm else ""
        ax.set_ylabel(f"{md.frequency_hz[i]:.1f} Hz\n{label}", fontsize=8)
    axes[0].legend(loc="upper right", fontsize=8, ncol=2)
    axes[-1].set_xlabel("axial position (mm)")
    fig.suptitle(title or f"Mode shapes at {speed_rpm:g} rpm")
    return fig
