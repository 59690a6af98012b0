"""Validation, detection and identification plots (matplotlib Figure API, no global state).

The uncertainty set at each frequency is a disk in the complex plane (centre ``c``, radius ``rho``,
receptance units m/N). The Bode band shows the range of magnitude (``max(0, |c| - rho)`` to ``|c| + rho``)
and of phase (``arg(c) +/- asin(rho/|c|)``) over the disk; where the disk holds the origin the magnitude
reaches 0 and the phase is any (hatched; dissertation Fig. 43/47). A point inside both ranges can still lie
outside the disk: the decision figure (:func:`decision_figure`) shows the ratio that decided.

Every figure names the rig, the speed (or that the rig does not rotate), the channel pair, the sweep and
the baseline (:class:`FigureContext`), and keeps its legend outside the data.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import MultipleLocator

from rotorcheck.location import depth_text
from rotorcheck.nominal import parse_port
from rotorcheck.report.figures import PHASOR_NOTE, legend_outside
from rotorcheck.report.rotor_drawing import draw_rotor, fit_rotor_labels, fit_texts, settle_labels
from rotorcheck.units import PLOT_FRF_UNITS, UNITS

#: receptance units a plot may use: factor from m/N (rotorcheck.units' receptance table, inverted)
FRF_UNITS: dict[str, float] = {u: 1.0 / UNITS["receptance"][u] for u in PLOT_FRF_UNITS}
#: colours that stay apart for readers with the common colour-vision deficiencies
COLOURS = {"model": "0.35", "band": "tab:blue", "healthy": "k", "new": "tab:orange", "fault": "tab:red",
           "ok": "0.55", "reference": "tab:green"}


def disk_band(centre: np.ndarray, radius: np.ndarray) -> dict[str, np.ndarray]:
    """Magnitude and phase (deg) bands of disks; ``full_phase`` where a disk holds the origin (or is not
    finite): there the magnitude reaches 0 and the phase is any (half width 180 deg, never more)."""
    c = np.asarray(centre, dtype=complex)
    r = np.asarray(radius, dtype=float)
    mag = np.abs(c)
    full = ~np.isfinite(r) | (r >= mag)
    with np.errstate(divide="ignore", invalid="ignore"):
        half = np.degrees(np.arcsin(np.clip(np.where(full, 1.0, r / mag), 0.0, 1.0)))
    ph = np.degrees(np.angle(c))
    half = np.where(full, 180.0, half)
    return {
        "phase_half_width": half,
        "mag_lo": np.where(full, 0.0, np.maximum(mag - r, 0.0)),
        "mag_hi": mag + r,
        "phase_lo": np.where(full, -180.0, ph - half),
        "phase_hi": np.where(full, 180.0, ph + half),
        "full_phase": full,
    }


@dataclass(frozen=True)
class FigureContext:
    """What a figure shows: the rig, speed, channel pair, sweep and baseline, and the receptance unit.

    ``speed_rpm`` None: a rig that does not rotate (a lumped rig), said so instead of "0 rpm".
    """

    rig_id: str
    speed_rpm: float | None = None
    channels: str = ""  # e.g. "s6x <- f8x" (output <- input)
    sweep: str = ""
    baseline: str = ""
    frf_unit: str = "m/N"
    n_pairs: int = 1  # channel pairs of the sweep (the figures draw the first; fault points are any pair's)

    @property
    def frf_scale(self) -> float:
        """Factor from m/N to :attr:`frf_unit`."""
        return FRF_UNITS[self.frf_unit]

    def speed_text(self) -> str:
        """"at 1000 rpm", "at standstill (0 rpm)", or "" for a rig that does not rotate."""
        if self.speed_rpm is None:
            return ""
        return "at standstill (0 rpm)" if self.speed_rpm == 0 else f"at {self.speed_rpm:g} rpm"

    def title(self, what: str, width: int = 90) -> str:
        """``what`` with the rig, speed and channels; the sweep and baseline on a second line. Lines of at
        most ``width`` characters, broken between these parts (a channel pair "s6.x <- s8.x" stays whole)
        unless one part alone is longer."""
        head = [x for x in (f"{what}: {self.rig_id}", self.speed_text()) if x]
        if self.channels:
            head[-1] += ","
            head.append(self.channels)
        tail = [x for x in (f"sweep {self.sweep}" if self.sweep else "",
                            f"baseline {self.baseline}" if self.baseline else "") if x]
        tail = [x + ";" for x in tail[:-1]] + tail[-1:]
        return "\n".join(line for parts in (head, tail) for line in _pack(parts, width))


def _pack(parts: list[str], width: int) -> list[str]:
    """``parts`` joined by spaces into lines of at most ``width`` characters, broken between parts (a part
    longer than ``width`` wrapped on its own)."""
    lines: list[str] = []
    for part in parts:
        if lines and len(lines[-1]) + 1 + len(part) <= width:
            lines[-1] += " " + part
        else:
            lines += textwrap.wrap(part, width) or [part]
    return lines


def _wrap_near(phase_deg: np.ndarray, ref_deg: np.ndarray) -> np.ndarray:
    """Shift ``phase_deg`` by multiples of 360 to lie within 180 deg of ``ref_deg``."""
    return ref_deg + (phase_deg - ref_deg + 180.0) % 360.0 - 180.0


def _runs(f: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """Contiguous runs of ``mask`` as frequency spans reaching half a grid step beyond their end points."""
    out: list[tuple[float, float]] = []
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        return out
    step = float(np.median(np.diff(f))) if f.size > 1 else 1.0
    start = prev = int(idx[0])
    for i in map(int, idx[1:]):
        if i != prev + 1:
            out.append((f[start] - 0.5 * step, f[prev] + 0.5 * step))
            start = i
        prev = i
    out.append((f[start] - 0.5 * step, f[prev] + 0.5 * step))
    return out


def phase_limits(ax: Any, *arrays: Any, margin_deg: float = 10.0) -> tuple[float, float]:
    """Fit a phase axis (deg) to the finite values of ``arrays``: a margin of ``margin_deg`` (or 8 % of
    the span) each side, ticks every 45 or 90 deg for spans over 90 deg; returns the limits."""
    vals = np.concatenate([np.ravel(np.asarray(a, dtype=float)) for a in arrays if a is not None] or [np.zeros(0)])
    vals = vals[np.isfinite(vals)]
    if vals.size == 0:
        lo, hi = -180.0, 180.0
    else:
        lo, hi = float(vals.min()), float(vals.max())
        pad = max(margin_deg, 0.08 * (hi - lo))
        lo, hi = lo - pad, hi + pad
    ax.set_ylim(lo, hi)
    if hi - lo > 90.0:
        ax.yaxis.set_major_locator(MultipleLocator(45.0 if hi - lo <= 400.0 else 90.0))
    return lo, hi


def _log_limits(*arrays: Any) -> tuple[float, float]:
    """Log-axis limits around the positive finite values of ``arrays`` (a decade-fraction margin)."""
    vals = np.concatenate([np.abs(np.ravel(np.asarray(a, dtype=complex))) for a in arrays if a is not None])
    vals = vals[np.isfinite(vals) & (vals > 0)]
    if vals.size == 0:
        return 1e-12, 1.0
    return float(vals.min()) / 2.0, float(vals.max()) * 2.0


def bode_band_figure(
    freq_hz: np.ndarray,
    model_frf: np.ndarray,
    centre: np.ndarray,
    radius: np.ndarray,
    healthy_frf: np.ndarray | None = None,
    damaged_frf: np.ndarray | None = None,
    fault: np.ndarray | None = None,
    title: str = "",
    context: FigureContext | None = None,
    band_label: str = "uncertainty set (range over the disk)",
) -> Figure:
    """Bode magnitude (log, ``context.frf_unit``) and phase (deg) of the model, the uncertainty set, the
    healthy and new data, and the fault points (open red circles over the data, which stays visible).

    Phase: each quantity within 180 deg of the set's centre (the nominal model's unwrapped phase where there
    is no set), so a band is never wider than 360 deg.
    """
    ctx = context or FigureContext(rig_id="")
    s = ctx.frf_scale
    f = np.asarray(freq_hz, dtype=float)
    fig = Figure(figsize=(10, 7), layout="constrained")
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    band = disk_band(centre, radius)
    full = band["full_phase"]
    lo_lim, hi_lim = _log_limits(s * np.asarray(model_frf), None if healthy_frf is None else s * healthy_frf,
                                 None if damaged_frf is None else s * damaged_frf,
                                 s * band["mag_lo"][band["mag_lo"] > 0], s * band["mag_hi"])
    ax_m.set_ylim(lo_lim, hi_lim)
    lo = np.clip(s * band["mag_lo"], lo_lim, hi_lim)  # 0 (disk over the origin): down to the axis
    hi = np.clip(s * band["mag_hi"], lo_lim, hi_lim)
    ax_m.fill_between(f, lo, hi, color=COLOURS["band"], alpha=0.22, lw=0, label=band_label)
    if np.any(full):
        ax_m.fill_between(f, lo_lim, hi, where=full, facecolor="none", edgecolor=COLOURS["band"], hatch="///",
                          lw=0, label=f"set holds 0: any phase, |.| down to 0 ({int(np.sum(full))} points)")
    ax_m.semilogy(f, s * np.abs(model_frf), color=COLOURS["model"], lw=1.2, label="nominal model")
    ref_deg = np.degrees(np.unwrap(np.angle(model_frf)))
    centre_deg = _wrap_near(np.degrees(np.angle(centre)), ref_deg)
    half = np.minimum(band["phase_half_width"], 180.0)
    ax_p.plot(f, _wrap_near(np.degrees(np.angle(model_frf)), centre_deg), color=COLOURS["model"], lw=1.2)
    ax_p.fill_between(f, centre_deg - half, centre_deg + half, where=~full, color=COLOURS["band"], alpha=0.22,
                      lw=0)
    if np.any(full):
        ax_p.fill_between(f, centre_deg - 180.0, centre_deg + 180.0, where=full, facecolor="none",
                          edgecolor=COLOURS["band"], hatch="///", lw=0)
    for data, key, label in ((healthy_frf, "healthy", "healthy data"), (damaged_frf, "new", "new data")):
        if data is None:
            continue
        z = 3 if key == "healthy" else 2  # the healthy dots above the new ones
        ax_m.semilogy(f, s * np.abs(data), ".", ms=3.5, color=COLOURS[key], label=label, zorder=z)
        ax_p.plot(f, _wrap_near(np.degrees(np.angle(data)), centre_deg), ".", ms=3.5, color=COLOURS[key], zorder=z)
    n_fault = 0
    if fault is not None and damaged_frf is not None and np.any(fault):
        fault = np.asarray(fault, dtype=bool)
        n_fault = int(np.sum(fault))
        which = f"; in any of the {ctx.n_pairs} pairs" if ctx.n_pairs > 1 else ""
        ax_m.semilogy(f[fault], s * np.abs(damaged_frf[fault]), "o", mfc="none", mew=1.3, ms=8,
                      color=COLOURS["fault"], label=f"fault points ({n_fault}{which})", zorder=4, gid="fault_points")
        ax_p.plot(f[fault], _wrap_near(np.degrees(np.angle(damaged_frf[fault])), centre_deg[fault]), "o",
                  mfc="none", mew=1.3, ms=8, color=COLOURS["fault"], zorder=4, gid="fault_points")
    ax_m.set_ylabel(f"|receptance| ({ctx.frf_unit})\n0-peak displacement / 0-peak force", fontsize=9)
    ax_p.set_ylabel("phase of displacement re force\n(deg; + = displacement leads)", fontsize=9)
    ax_p.set_xlabel("frequency (Hz)")
    drawn = [np.concatenate([l_.get_ydata() for l_ in ax_p.get_lines()]) if ax_p.get_lines() else None,
             np.where(full, np.nan, centre_deg - half), np.where(full, np.nan, centre_deg + half)]
    phase_limits(ax_p, *drawn)  # the data and the finite band; an any-phase (hatched) band fills what is shown
    legend_outside(ax_m)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, alpha=0.3)
    note = ("Band: the range of magnitude and of phase over the uncertainty disk at each frequency. A point inside "
            "both ranges can still lie outside the disk" + (": the decision figure shows the ratio that decided."
                                                           if damaged_frf is not None else ".")
            + f" {PHASOR_NOTE[0].upper()}{PHASOR_NOTE[1:]}.")
    ax_p.text(0.0, -0.16, "\n".join(textwrap.wrap(note, 120)), transform=ax_p.transAxes, fontsize=7, va="top")
    ax_m.set_title(title or ctx.title("Bode"), fontsize=9)
    return fig


def decision_figure(
    freq_hz: np.ndarray,
    ratio: np.ndarray,
    fault: np.ndarray,
    status: np.ndarray,
    context: FigureContext,
    verdict: str,
    rule: str,
    ratio_meaning: str = "gamma_required / gamma_healthy",
    joint: dict[str, Any] | None = None,
    beyond_benign: np.ndarray | None = None,
) -> Figure:
    """The decision actually made: per frequency the ``ratio`` that decides a point (e.g. ``gamma_required /
    gamma_healthy``; log axis), the threshold 1 and the fault points (ratio above 1, red); points not
    evaluated marked at the bottom. With
    the joint test (``joint``: ``statistic``, ``threshold``, ``p_value``, ``false_alarm``), a second panel:
    the sweep's statistic against its threshold, the rule that made the verdict.
    """
    f = np.asarray(freq_hz, dtype=float)
    fault = np.asarray(fault, dtype=bool)
    status = np.asarray(status).astype(str)
    ratio = np.asarray(ratio, dtype=float)
    evaluated = np.isfinite(ratio) & (ratio > 0)
    if joint is not None:
        fig = Figure(figsize=(10, 6.2), layout="constrained")
        ax, bx = fig.subplots(2, 1, height_ratios=(3.0, 1.0))
    else:
        fig = Figure(figsize=(10, 4.8), layout="constrained")
        ax, bx = fig.subplots(), None
    lo, hi = _log_limits(ratio[evaluated], np.array([1.0]))
    ax.set_ylim(lo, hi)
    ok = evaluated & ~fault
    ax.semilogy(f[ok], ratio[ok], ".", ms=4, color=COLOURS["ok"], label=f"explained ({int(np.sum(ok))})")
    ax.semilogy(f[fault & evaluated], ratio[fault & evaluated], "o", ms=5, color=COLOURS["fault"],
                label=f"fault points ({int(np.sum(fault))})", gid="fault_points")
    ax.axhline(1.0, color="k", lw=1.0, ls="--", label="threshold 1 (fault above)")
    if beyond_benign is not None and np.any(beyond_benign):
        bb = np.asarray(beyond_benign, dtype=bool) & evaluated
        ax.semilogy(f[bb], ratio[bb], "D", mfc="none", ms=8, color="tab:purple",
                    label=f"beyond every benign change ({int(np.sum(np.asarray(beyond_benign, dtype=bool)))})")
    other = ~evaluated | ~np.isin(status, ("ok", "fault"))
    for s_ in np.unique(status[other]):
        sel = other & (status == s_)
        ax.plot(f[sel], np.full(int(np.sum(sel)), lo * 1.15), "x", color="tab:brown",
                label=f"not decided: {s_} ({int(np.sum(sel))})")
    ax.set_ylabel(f"ratio {ratio_meaning}")
    ax.set_xlabel("frequency (Hz)")
    ax.grid(True, which="both", alpha=0.3)
    legend_outside(ax)
    head = context.title(f"Detection ({verdict.upper()})")
    ax.set_title(head + "\n" + "\n".join(textwrap.wrap("Rule: " + rule, 100)), fontsize=8)
    if bx is not None and joint is not None:
        joint_panel(bx, float(joint["statistic"]), float(joint["threshold"]), float(joint["p_value"]),
                    float(joint["false_alarm"]))
    return fig


def engineering_unit(largest_m_per_n: float) -> tuple[str, float]:
    """The receptance unit (rotorcheck.units' table: m/N, mm/N, um/N, nm/N) in which ``largest_m_per_n``
    reads 1 or more (nm/N below that) and its factor from m/N."""
    units = sorted(((u, f) for u, f in UNITS["receptance"].items() if u.isascii()), key=lambda uf: -uf[1])
    for unit, factor in units:
        if abs(largest_m_per_n) >= factor:
            return unit, 1.0 / factor
    return units[-1][0], 1.0 / units[-1][1]


def joint_panel(bx: Any, t: float, thr: float, p_value: float, false_alarm: float) -> None:
    """The sweep's joint statistic ``t`` as a dot against its threshold ``thr`` (dashed line; the damage side
    shaded) on a linear axis from 0, or a symlog one (linear up to the threshold) when ``t`` exceeds 20
    thresholds: a statistic of 0 sits on the axis, never off a log scale."""
    damage = t > thr
    top = max(t, thr, 1e-300)
    if top > 20.0 * thr > 0.0:
        bx.set_xscale("symlog", linthresh=thr)
        right = 2.0 * top
    else:
        right = 1.15 * top
    left = min(0.0, 1.15 * t)
    bx.axvspan(thr, right, color=COLOURS["fault"], alpha=0.08, lw=0, label="damage side (T above the threshold)")
    bx.axvline(thr, color="k", ls="--", lw=1.0, gid="joint_threshold",
               label=f"threshold {thr:.4g} (false alarm {false_alarm:g} per sweep)")
    bx.plot([t], [0.0], "o", ms=9, color=COLOURS["fault"] if damage else COLOURS["ok"], mec="k", zorder=3,
            gid="joint_statistic", label=f"joint statistic T = {t:.4g} (p = {p_value:.3g})", clip_on=False)
    bx.set_xlim(left, right)
    bx.set_ylim(-1.0, 1.0)
    bx.set_yticks([])
    bx.set_ylabel("this sweep", fontsize=9)
    bx.set_xlabel("joint statistic T (the verdict: damage when T is above the threshold)")
    bx.grid(True, which="both", axis="x", alpha=0.3)
    legend_outside(bx)


def complex_plane_figure(
    freq_hz: float,
    model: complex,
    centre: complex,
    radius: float,
    healthy: complex | None = None,
    damaged: complex | None = None,
    context: FigureContext | None = None,
    damaged_noise: float | None = None,
    healthy_noise: float | None = None,
    set_label: str = "uncertainty set",
) -> Figure:
    """The uncertainty disk at one frequency in the complex plane (dissertation Fig. 48), with the noise
    disks of the data (their own noise bound, m/N) and the distance of the new data from the set.

    A square frame on the set and the data, equal scales; the unit an engineering one chosen from the frame
    (:func:`engineering_unit`, named in the axis labels: no offset or power in a corner)."""
    ctx = context or FigureContext(rig_id="")
    fig = Figure(figsize=(9.0, 5.6), layout="constrained")
    ax = fig.subplots()
    t = np.linspace(0, 2 * np.pi, 361)
    # frame the set and the data (the decision is read there); the model and the origin only when near
    c0 = complex(centre)
    near = [complex(z) for z in (healthy, damaged) if z is not None]
    r_fin = float(radius) if np.isfinite(radius) else 0.0
    half = max([1.3 * abs(z - c0) for z in near] + [1.6 * r_fin, 1e-300])
    model_far = abs(complex(model) - c0) > 2.5 * half
    if not model_far:
        half = max(half, 1.3 * abs(complex(model) - c0))
    unit, s = engineering_unit(max(abs(c0.real) + half, abs(c0.imag) + half))
    c = c0 * s
    if np.isfinite(radius):
        ax.fill(c.real + s * radius * np.cos(t), c.imag + s * radius * np.sin(t), color=COLOURS["band"], alpha=0.2,
                label=f"{set_label} (radius {s * radius:.3g} {unit})")
    if not model_far:
        ax.plot(s * model.real, s * model.imag, "s", color=COLOURS["model"], label="nominal model")
    for z, noise, key, label in ((healthy, healthy_noise, "healthy", "healthy data"),
                                 (damaged, damaged_noise, "new", "new data")):
        if z is None:
            continue
        ax.plot(s * z.real, s * z.imag, "o", color=COLOURS[key], label=label, zorder=3)
        if noise is not None and np.isfinite(noise):
            ax.plot(s * z.real + s * noise * np.cos(t), s * z.imag + s * noise * np.sin(t), ":", color=COLOURS[key],
                    lw=1.0, label=f"{label}: its noise bound ({s * noise:.3g} {unit})")
    if abs(c0) <= half:
        ax.plot(0, 0, "+", color="grey", ms=10, label="origin")
    ax.set_xlim(s * (c0.real - half), s * (c0.real + half))
    ax.set_ylim(s * (c0.imag - half), s * (c0.imag + half))
    ax.set_aspect("equal", adjustable="box")  # a square frame: the limits stay as set
    ax.ticklabel_format(axis="both", style="plain", useOffset=False)
    if model_far:
        d = complex(model) - c0
        u = d / abs(d)
        ax.annotate(f"nominal model: {abs(d) / half:.3g} frame\nhalf-widths away", xycoords="axes fraction",
                    xy=(0.5 + 0.49 * u.real, 0.5 + 0.49 * u.imag), xytext=(0.5 + 0.36 * u.real, 0.5 + 0.36 * u.imag),
                    textcoords="axes fraction", fontsize=7, color=COLOURS["model"],
                    ha="center", arrowprops={"arrowstyle": "->", "color": COLOURS["model"]}, gid="model_off_frame")
    ax.set_xlabel(f"Re receptance ({unit})")
    ax.set_ylabel(f"Im receptance ({unit})")
    extra = ""
    if damaged is not None and np.isfinite(radius) and radius > 0:
        d = abs(complex(damaged) - complex(centre)) / radius
        extra = f"; new data at {d:.3g} radii from the centre ({'outside: a fault point' if d > 1 else 'inside'})"
    ax.set_title(ctx.title(f"Complex plane at {freq_hz:.2f} Hz") + "\n" + "\n".join(textwrap.wrap(extra[2:], 90))
                 if extra else ctx.title(f"Complex plane at {freq_hz:.2f} Hz"), fontsize=8)
    legend_outside(ax)
    ax.text(1.02, 0.0, "\n".join(textwrap.wrap(f"receptance = displacement / force; {PHASOR_NOTE}", 45)),
            transform=ax.transAxes, fontsize=7, va="bottom", ha="left", color="0.3")
    ax.grid(True, alpha=0.3)
    return fig


def _significant_phase(f: np.ndarray, damage: np.ndarray, significant: np.ndarray) -> np.ndarray:
    """Phase (deg) of ``damage`` where ``significant``, NaN elsewhere: unwrapped along each contiguous run,
    the run shifted by whole turns to centre within +-180 deg."""
    out = np.full(f.size, np.nan)
    idx = np.flatnonzero(significant)
    for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []:
        ph = np.degrees(np.unwrap(np.angle(damage[run])))
        out[run] = ph - 360.0 * np.round(np.mean(ph) / 360.0)
    return out


def damage_dynamics_figure(
    freq_hz: np.ndarray,
    damage: np.ndarray,
    bound_min_abs: np.ndarray,
    bound_max_abs: np.ndarray,
    phase_lo_deg: np.ndarray | None = None,
    phase_hi_deg: np.ndarray | None = None,
    fault: np.ndarray | None = None,
    title: str = "",
    nominal: np.ndarray | None = None,
    label: str = "identified D_u (eq. 3.11)",
    bound_label: str = "exact bound",
    nominal_label: str = "D_u with the nominal E22 (eq. 3.11; carries the model error)",
    context: FigureContext | None = None,
    reference_n_per_m: float | None = None,
    reference_label: dict[float, str] | None = None,
) -> Figure:
    """Identified damage dynamics D_u (N/m) with its bound: magnitude and phase.

    ``damage`` is drawn (solid) only where it is significant (its bound excludes 0): elsewhere its value
    means nothing and the bound alone is shown (down to the axis: 0 included); where the bound is unbounded
    the frequencies are hatched over the whole axis (D_u not identifiable there). The phase is drawn where
    significant, unwrapped along each run, the axis fitted to it. Fault points are ticks along the bottom.
    A reference level (``reference_n_per_m``, e.g. 1 % of the damage port's static stiffness) gives the scale.
    ``nominal``: an estimate not to be read (the nominal model's, with its error), drawn thin and grey.
    """
    ctx = context or FigureContext(rig_id="")
    reference_label = reference_label or {1.0: "reference", 0.1: "reference x 0.1"}
    f = np.asarray(freq_hz, dtype=float)
    damage = np.asarray(damage, dtype=complex)
    fig = Figure(figsize=(10, 7), layout="constrained")
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    lo_b = np.asarray(bound_min_abs, dtype=float)
    hi_b = np.asarray(bound_max_abs, dtype=float)
    unbounded = ~np.isfinite(hi_b)
    significant = np.isfinite(lo_b) & (lo_b > 0) & np.isfinite(damage)
    ref = [reference_n_per_m, 0.1 * reference_n_per_m] if reference_n_per_m else []
    lo_lim, hi_lim = _log_limits(damage[significant], None if nominal is None else nominal, lo_b[significant],
                                 hi_b[~unbounded], np.asarray(ref, dtype=float))
    ax_m.set_ylim(lo_lim, hi_lim)
    band_lo = np.clip(np.where(significant, lo_b, lo_lim), lo_lim, hi_lim)  # 0 in the bound: down to the axis
    band_hi = np.clip(np.where(unbounded, hi_lim, hi_b), lo_lim, hi_lim)
    ax_m.fill_between(f, band_lo, band_hi, where=~unbounded, color="tab:orange", alpha=0.3, lw=0,
                      label=bound_label + "; down to the axis: 0 in the bound")
    if np.any(unbounded):
        for a in (ax_m, ax_p):
            for k, (x0, x1) in enumerate(_runs(f, unbounded)):
                a.axvspan(x0, x1, facecolor="none", edgecolor="0.7", hatch="//", lw=0,
                          label=f"bound unbounded: D_u not identifiable ({int(np.sum(unbounded))} points)"
                          if a is ax_m and k == 0 else None)
    mag = np.abs(damage)
    ax_m.semilogy(f, np.where(significant, mag, np.nan), color="tab:red", lw=1.6,
                  label=label + " where its bound excludes 0" if np.any(significant) else None)
    if nominal is not None:
        ax_m.semilogy(f, np.abs(nominal), "--", color="0.55", lw=0.7, alpha=0.8, label=nominal_label + ": not to read")
    if fault is not None and np.any(fault):
        fault = np.asarray(fault, dtype=bool)
        ax_m.plot(f[fault], np.full(int(np.sum(fault)), 0.02), "|", ms=8, mew=0.8, color="k",
                  transform=ax_m.get_xaxis_transform(),
                  label=f"fault points ({int(np.sum(fault))}: ticks along the bottom)", gid="fault_points")
    if reference_n_per_m:
        for frac, ls in ((1.0, "-."), (0.1, ":")):
            ax_m.axhline(frac * reference_n_per_m, color=COLOURS["reference"], ls=ls, lw=1.0,
                         label=f"{reference_label[frac]}: {frac * reference_n_per_m:.3g} N/m")
    if not np.any(significant):
        ax_m.text(0.5, 0.93, "NOT SIGNIFICANT:\nthe bound holds D_u = 0 at every frequency", transform=ax_m.transAxes,
                  ha="center", va="top", fontsize=9, color="0.2", gid="not_significant",
                  bbox={"facecolor": "white", "edgecolor": "0.5", "alpha": 0.9})
    ph = _significant_phase(f, damage, significant)
    ax_p.plot(f, ph, color="tab:red", lw=1.4)
    shown = [ph]
    if phase_lo_deg is not None and phase_hi_deg is not None:
        plo, phi = np.asarray(phase_lo_deg, dtype=float), np.asarray(phase_hi_deg, dtype=float)
        ok = significant & np.isfinite(plo) & np.isfinite(phi) & ((phi - plo) < 360.0)
        mid = 0.5 * (plo + phi)
        shift = np.where(ok, _wrap_near(mid, np.where(ok, ph, 0.0)) - mid, 0.0)  # the band's turn: the estimate's
        ax_p.fill_between(f, plo + shift, phi + shift, where=ok, color="tab:orange", alpha=0.3, lw=0)
        shown += [np.where(ok, plo + shift, np.nan), np.where(ok, phi + shift, np.nan)]
    if nominal is not None and np.any(significant):
        ax_p.plot(f, np.where(significant, _wrap_near(np.degrees(np.angle(nominal)), np.where(significant, ph, 0.0)),
                              np.nan), "--", color="0.55", lw=0.7, alpha=0.8)
    if np.any(significant):
        phase_limits(ax_p, *shown)
    else:
        ax_p.set_ylim(-180.0, 180.0)
        ax_p.yaxis.set_major_locator(MultipleLocator(90.0))
        ax_p.text(0.5, 0.5, "phase not shown:\nD_u is not significant at any frequency (0 in its bound)",
                  transform=ax_p.transAxes, ha="center", va="center", fontsize=9, color="0.3")
    ax_m.set_ylabel("|D_u| (N/m): 0-peak force / 0-peak displacement", fontsize=9)
    ax_p.set_ylabel("phase of D_u: force re displacement\n(deg; + = force leads; where significant)", fontsize=9)
    ax_p.set_xlabel("frequency (Hz)")
    legend_outside(ax_m)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, alpha=0.3)
    ax_m.set_title(title or ctx.title("Damage dynamics D_u"), fontsize=9)
    return fig


def detectability_figure(config: Any, det: Any) -> Figure:
    """The rotor drawing (elements shaded by their detectable breathing depth with benign ranges) over the
    smallest detectable breathing-crack depth (% of diameter) per element: with the benign ranges, noise
    only, and the likelihood-ratio limit."""
    fig = Figure(figsize=(8.0, 6.0), layout="constrained")
    ax, bx = fig.subplots(2, 1, sharex=True, height_ratios=(1.0, 1.2))
    depth = {e.element: e.breathing_depth_min for e in det.elements}
    cmap = colormaps["RdYlGn_r"]

    def colour_of(element: int) -> Any:
        d = depth.get(element)
        return "0.6" if d is None else cmap(min(float(d) / 0.5, 1.0))

    draw_rotor(ax, config, element_colour=colour_of, actuators=[parse_port(a) for a in det.actuators],
               sensors=[parse_port(s) for s in det.sensors], damage_port=getattr(config, "damage", None))
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
    bx.set_ylabel("smallest detectable breathing\ncrack depth (% of diameter)", fontsize=8)
    bx.set_xlabel("axial position (m); grey elements: not seen by these channels, or no detectable depth up to 50 %",
                  fontsize=8)
    bx.tick_params(labelsize=7)
    bx.grid(True, which="both", alpha=0.3)
    legend_outside(bx, fontsize=7)
    bar = fig.colorbar(ScalarMappable(Normalize(0.0, 50.0), cmap), ax=ax, location="bottom", shrink=0.5,
                       aspect=40, pad=0.02)
    bar.set_label("element shading: breathing depth detectable with the benign ranges (% of diameter)", fontsize=7)
    bar.ax.tick_params(labelsize=7)
    z = np.asarray(config.stations, dtype=float)
    bx.set_xlim(z[0] - 0.01, z[-1] + 0.01)
    settle_labels(fig, lambda: fit_rotor_labels(ax))  # the layout is final: the drawing's labels placed for it
    return fig


def location_figure(config: Any, location: Any, title: str = "") -> Figure:
    """The shaft along its axis (m): each candidate element coloured by its status (excluded: grey,
    consistent: blue, the best ranked: red), stations, discs, bearings, actuator and sensor marked; below,
    the certified stiffness-loss interval of every candidate not excluded (and its estimate), with the
    depth interval (% of the diameter) of the three best ranked."""
    fig = Figure(figsize=(9.5, 5.5), layout="constrained")
    ax, bx = fig.subplots(2, 1, sharex=True, height_ratios=(1.0, 1.4))
    z = np.asarray(config.stations, dtype=float)
    status = {c.element: c for c in location.candidates}
    best = location.best.element if location.best is not None else None
    colour = {"excluded": "0.8", "consistent": "tab:blue"}

    def colour_of(element: int) -> str:
        c = status.get(element)
        return "tab:red" if element == best else colour.get(c.status if c is not None else "", "white")

    ports = getattr(config, "ports", None)
    draw_rotor(ax, config, element_colour=colour_of,
               actuators=[p for p in (getattr(ports, "actuator", None),) if p is not None],
               sensors=[p for p in (getattr(ports, "sensor", None),) if p is not None],
               candidates=([c.element for c in location.candidates]  # outlined only when not every element
                           if len(location.candidates) < len(config.shaft) else None))
    ax.set_title("\n".join(textwrap.wrap(title or location.summary(), 100)), fontsize=8, loc="left")
    ranks = []
    for c in location.candidates:
        if c.status != "consistent":
            continue
        mid = 0.5 * (c.z_start_m + c.z_end_m)
        lo, hi = 100 * c.loss_interval[0], 100 * c.loss_interval[1]
        col = "tab:red" if c.element == best else "tab:blue"
        bx.plot([mid, mid], [lo, hi], color=col, lw=5, alpha=0.6, solid_capstyle="butt")
        if c.loss_estimate is not None:
            bx.plot(mid, 100 * c.loss_estimate, "k_", ms=12)
        depth = depth_text(*c.depth_interval)
        if c.rank is not None and c.rank <= 3 and depth:
            ranks.append(bx.annotate(f"#{c.rank}\ndepth {depth}", (mid, hi), textcoords="offset points",
                                     xytext=(0, 4), ha="center", va="bottom", fontsize=7, gid=f"rank {c.rank}"))
    bx.set_ylabel("element stiffness loss (%)\ncertified interval, fit (-)", fontsize=8)
    bx.set_xlabel("axial position (m); grey: excluded, blue: consistent, red: most likely", fontsize=8)
    bx.tick_params(labelsize=7)
    bx.grid(True, alpha=0.3)
    bx.set_xlim(z[0] - 0.01, z[-1] + 0.01)

    def reset() -> None:
        for t in ranks:
            t.xyann = (0.0, 4.0)

    # the layout is final: the drawing's labels and the ranks (the best ranked nearest its bar) placed for it
    settle_labels(fig, lambda: fit_rotor_labels(ax),
                  lambda: fit_texts(bx, sorted(ranks, key=lambda t: t.get_gid()), reset))
    return fig
