"""Stepped-sine analysis of time records: steps, per-period phasors, shaft harmonics, the sweep.

For each step (a row of the map's step table, else found in the force: :mod:`.steps`):

1. skip the settling transient: ``max(settle_periods, ceil(settle_s f))`` periods from the step start;
2. keep the whole periods up to the step end (``n_periods``), each one analysed by a least-squares
   sine fit with DC and slope terms (:mod:`.periodfit`; the sample rate need not be a multiple of
   ``f``), every channel at once, phasors referenced to the step start ``t_ref`` (the table's
   ``start_s``, or the first rising zero crossing of a found step): ``x = Re{X exp(j 2 pi f (t - t_ref))}``;
3. drop periods with clipped samples (:func:`clipped_periods`), refuse a force that is not a sine;
4. average: with the shaft turning (keyphasor pulses, or the map's ``speed_rpm`` without a
   keyphasor), the shaft harmonics 1X..``shaft_orders``X are fitted out of the per-period phasors
   with the keyphasor's measured angle (:func:`rotorcheck.signal.lockin.shaft_harmonic_fit`), else
   the plain mean; ``output_var`` is the variance of that mean from the period scatter (m^2) and
   ``n_periods`` the periods used, as the sweep contract defines them;
5. scale: force (N) = recorded x 1 or x ``gain_n_per_a``; displacement (m) = recorded / sensitivity
   or x the length unit;
6. sidebands (``analysis.sideband_orders``, a rotating run with a keyphasor): on the samples of the
   same kept windows, the least-squares fit of known tones of :mod:`rotorcheck.signal.sidebands`
   (``tone_set(f, Omega, orders, f / N)``, ``fit_tones``) per probe with a quadratic drift fitted
   jointly, in local time ``t - t_ref`` (the main phasors' origin),
   referenced to the shaft with the keyphasor's angle at ``t_ref``
   (:func:`~rotorcheck.signal.sidebands.shaft_referenced`), scaled as the probes; NaN where a tone is
   not separable (the sweep contract's version 3).

Quirks are handled or refused with :class:`~rotorcheck.errors.InputError` naming the file, the
channel and the time (see ``docs/ingest.md``); what was handled is listed in the run's notes.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck import __version__
from rotorcheck.errors import InputError
from rotorcheck.ingest.channel_map import ChannelMap
from rotorcheck.ingest.keyphasor import Pulses, find_pulses, repair_pulses
from rotorcheck.ingest.periodfit import fit_windows, period_design, remove_drift, window_starts
from rotorcheck.ingest.record import TimeRecord
from rotorcheck.ingest.steps import find_steps, force_crossings
from rotorcheck.signal.lockin import average_periods, shaft_harmonic_fit
from rotorcheck.signal.sidebands import fit_tones, requested_orders, shaft_referenced, tone_set
from rotorcheck.sweep.format import Channel, Run, Sweep, utc_now_iso

__all__ = ["METHOD", "IngestResult", "StepPlan", "analyse", "clipped_periods", "plan_steps"]

#: the analysis as one line (stored with the settings in the sweep file)
METHOD = ("per-period least-squares sine fit with DC and slope terms over floor(fs/f) samples from each period "
          "start (one pseudo-inverse per step); shaft harmonics fitted out with the keyphasor angle; "
          "variance of the mean from the period scatter")
#: the sidebands' analysis as one line (stored with the settings when ``sideband_orders`` is set)
SIDEBAND_METHOD = ("least-squares fit of known tones (excitation, shaft harmonics, f + k Omega; rotorcheck.signal."
                   "sidebands) with a quadratic drift, on each step's analysed samples, local time from the step "
                   "start; times exp(-j k theta), theta the keyphasor's shaft angle at the step start")
#: samples read at once when a step is longer (memory bound per step; the sidebands hold a step's samples)
CHUNK_SAMPLES = 1 << 20


@dataclass(frozen=True)
class StepPlan:
    """One step to analyse: frequency (Hz), phase reference and first analysed period start (s),
    periods, the segment (record) index and the step's nominal end (s)."""

    frequency_hz: float
    t_ref_s: float
    t_first_s: float
    n_periods: int
    segment: int
    end_s: float


@dataclass
class IngestResult:
    """The sweep, the provenance attributes for its file and a summary (JSON-able)."""

    sweep: Sweep
    attrs: dict[str, str]
    summary: dict[str, Any]
    notes: list[str] = field(default_factory=list)


def _settle(cmap: ChannelMap, f: float) -> int:
    a = cmap.analysis
    return max(a.settle_periods, math.ceil(a.settle_s * f - 1e-9))


def _last_full(seg: TimeRecord, t_first: float, f: float, length: int) -> int:
    """Periods from ``t_first`` whose whole window lies inside the segment."""
    n = math.floor((seg.t_end_s - t_first) * f + 1e-6) + 1
    while n > 0 and int(window_starts(t_first, n, f, seg.t0_s, seg.fs_hz)[-1]) + length > seg.n_samples:
        n -= 1
    return max(n, 0)


def plan_steps(segments: Sequence[TimeRecord], cmap: ChannelMap, notes: list[str]) -> list[StepPlan]:
    """The steps to analyse, from the step table or found in the force (see the module docstring)."""
    plans: list[StepPlan] = []
    if cmap.steps:
        for row in cmap.steps:
            f = row.frequency_hz
            inside = [i for i, s in enumerate(segments) if s.t0_s <= row.start_s < s.t_end_s]
            later = [i for i, s in enumerate(segments) if row.start_s < s.t0_s < row.end_s]
            before = [s for s in segments if s.t_end_s <= row.start_s]
            if later and (inside or before):  # samples stop and resume within the step
                gap_at = segments[inside[0]].t_end_s if inside else before[-1].t_end_s
                nxt = segments[later[0]]
                raise InputError(nxt.path, f"t = {gap_at:.6f} s",
                                 f"the step at {f:g} Hz ({row.start_s:g}-{row.end_s:g} s) spans a gap in time "
                                 f"(next samples at {nxt.t0_s:.6f} s): refusing to analyse across it")
            if not inside and not later:  # the step lies outside the record
                plans.append(StepPlan(f, row.start_s, row.start_s, 0, -1, row.end_s))
                continue
            k = inside[0] if inside else later[0]  # the record may start inside the step
            seg = segments[k]
            t_first = row.start_s + _settle(cmap, f) / f
            if t_first < seg.t0_s:  # whole periods of the step's grid inside the record
                t_first += math.ceil((seg.t0_s - t_first) * f - 1e-9) / f
            n = math.floor((row.end_s - t_first) * f + 1e-6)
            length = math.floor(seg.fs_hz / f + 1e-9)
            n = min(n, _last_full(seg, t_first, f, length))
            plans.append(StepPlan(f, row.start_s, t_first, max(n, 0), k, row.end_s))
        return plans
    prev_last: tuple[float, float] | None = None
    for i, seg in enumerate(segments):
        ins = cmap.inputs
        # each input on its own: its steps are the patterns that drive it (one input at a time)
        found = sorted((st for c in ins for st in find_steps(force_crossings(seg, c.channel),
                                                              cmap.analysis.step_rtol)), key=lambda st: st.start_s)
        if not found:
            raise InputError(seg.path, f"channel {ins[0].channel!r}",
                             f"t = {seg.t0_s:.6f}-{seg.t_end_s:.6f} s: no steady sine found in the force "
                             "(not a sine, or give a step table)")
        if prev_last is not None and abs(found[0].frequency_hz / prev_last[0] - 1) < cmap.analysis.step_rtol:
            raise InputError(seg.path, f"t = {prev_last[1]:.6f} s",
                             f"the step at {found[0].frequency_hz:.6g} Hz continues across a gap in time "
                             f"(samples resume at {seg.t0_s:.6f} s): refusing to analyse across it")
        prev_last = (found[-1].frequency_hz, seg.t_end_s)
        for st in found:
            f = st.frequency_hz
            t_first = st.start_s + _settle(cmap, f) / f
            n = math.floor((st.end_s - t_first) * f + 0.01)
            length = math.floor(seg.fs_hz / f + 1e-9)
            n = min(n, _last_full(seg, t_first, f, length))
            plans.append(StepPlan(f, st.start_s, t_first, max(n, 0), i, st.end_s))
        notes.append(f"{len(found)} steps found in the force of {seg.path}")
    return plans


def clipped_periods(win: np.ndarray, rails: Sequence[tuple[float, float] | None], min_run: int) -> np.ndarray:
    """(channels, periods) True where a window has clipped samples: outside the channel's ``rails``
    when given, else a run of at least ``min_run`` samples exactly at the chunk's maximum or minimum
    (flat-topping)."""
    out = np.zeros(win.shape[:2], dtype=bool)
    for c in range(win.shape[0]):
        w = win[c]
        r = rails[c] if c < len(rails) else None
        if r is not None:
            out[c] = np.any((w <= r[0]) | (w >= r[1]), axis=1)
            continue
        for ext in (w.max(), w.min()):
            eq = w == ext
            if int(eq.sum()) < min_run:
                continue
            cs = np.cumsum(eq, axis=1, dtype=np.int32)
            cs = np.concatenate([np.zeros((w.shape[0], 1), np.int32), cs], axis=1)
            out[c] |= np.any(cs[:, min_run:] - cs[:, :-min_run] >= min_run, axis=1)
    return out


def _clipped(block: np.ndarray, off: np.ndarray, length: int, rails: Sequence[tuple[float, float] | None],
             min_run: int, n_inputs: int) -> np.ndarray:
    """:func:`clipped_periods` of the windows, gathered only for the channels that may clip (rails
    reached, or the chunk's extreme value repeated ``min_run`` times); a constant input channel (the
    first ``n_inputs`` rows) is an undriven actuator, a constant probe a saturated one."""
    out = np.zeros((block.shape[0], off.size), dtype=bool)
    idx = off[:, None] + np.arange(length)[None, :]
    for c in range(block.shape[0]):
        x, r = block[c], rails[c] if c < len(rails) else None
        if r is not None:
            suspect = bool(x.min() <= r[0] or x.max() >= r[1])
        else:
            hi, lo = x.max(), x.min()
            suspect = (c >= n_inputs if hi == lo else
                       int(np.count_nonzero(x == hi)) >= min_run or int(np.count_nonzero(x == lo)) >= min_run)
        if suspect:
            out[c] = clipped_periods(x[idx][None], [r], min_run)[0]
    return out


@dataclass
class _StepOut:
    frequency_hz: float
    t_ref_s: float
    per_period: np.ndarray  # (N, n_ch) scaled, t_ref frame
    mean: np.ndarray
    var: np.ndarray
    n: int
    dof: int
    sb_phasor: np.ndarray | None = None  # (K, n_out) m, shaft-referenced
    sb_var: np.ndarray | None = None  # (K, n_out) m^2


def _analyse_step(seg: TimeRecord, plan: StepPlan, cmap: ChannelMap, scales: np.ndarray,
                  pulses: Pulses | None, shaft_hz: float, notes: list[str]) -> _StepOut | None:
    ins = cmap.inputs
    names = [*(c.channel for c in ins), *(p.channel for p in cmap.probes)]
    rails = [*(c.rails for c in ins), *(p.rails for p in cmap.probes)]
    f, fs = plan.frequency_hz, seg.fs_hz
    des = period_design(f, fs)
    starts = window_starts(plan.t_first_s, plan.n_periods, f, seg.t0_s, fs)
    per_chunk = max(1, CHUNK_SAMPLES // des.length)
    phs, dcs, resid, clip, amp = [], [], [], [], []
    orders = cmap.analysis.sideband_orders
    wins: list[np.ndarray] = []  # the probes' window samples (n_out, P, L), for the sidebands
    min_run = max(3, math.ceil(0.02 * des.length))
    for a in range(0, plan.n_periods, per_chunk):
        s = starts[a : a + per_chunk]
        block = seg.read(names, int(s[0]), int(s[-1]) + des.length)
        off = s - s[0]
        ph, dc, res = fit_windows(block, off, des, residual_rows=len(ins))
        assert res is not None
        dcs.append(dc)
        clip.append(_clipped(block, off, des.length, rails, min_run, len(ins)))
        phs.append(ph)
        resid.append(res)
        amp.append(np.abs(ph[: len(ins)]))
        if orders:
            wins.append(block[len(ins):, off[:, None] + np.arange(des.length)[None, :]])
    ph = np.concatenate(phs, axis=1)  # (ch, N) local frames
    bad = np.concatenate(clip, axis=1)
    t_mid = seg.t0_s + (starts + 0.5 * (des.length - 1)) / fs
    good = ~bad.any(axis=0)
    if good.sum() >= 3:  # slow drift from the DC of the clean periods (see periodfit)
        ph = remove_drift(ph, np.concatenate(dcs, axis=1)[:, good], t_mid[good], des, t_all=t_mid)
    # the driven input (largest force): its residual says whether the force is a sine
    amp_cat = np.concatenate(amp, axis=1)
    amp_all = amp_cat * np.abs(scales[: len(ins)])[:, None]
    drv = int(np.argmax(np.median(amp_all, axis=1)))
    res_f = np.concatenate(resid, axis=1)[drv]
    amp_f = amp_cat[drv]
    t_win = seg.t0_s + starts / fs
    w = 2.0 * np.pi * f
    # a force that is not a sine: the fit residual against the fitted amplitude (RMS)
    chk = good & np.isfinite(res_f)
    dist = float(np.median(res_f[chk] / np.maximum(amp_f[chk] / np.sqrt(2.0), 1e-300))) if chk.any() else 0.0
    if dist > cmap.analysis.max_distortion:
        raise InputError(seg.path, f"channel {ins[drv].channel!r}",
                         f"t = {plan.t_first_s:.6f} s (step at {f:.6g} Hz): the force is not a sine (residual "
                         f"{100 * dist:.3g} % of its RMS, limit {100 * cmap.analysis.max_distortion:g} %)")
    if bad.any():
        chans = [names[c] for c in np.flatnonzero(bad.any(axis=1))]
        first = float(t_win[np.flatnonzero(bad.any(axis=0))[0]])
        n_bad = int((~good).sum())
        if cmap.analysis.clipping == "refuse" or n_bad > plan.n_periods // 2:
            raise InputError(seg.path, f"channel {chans[0]!r}",
                             f"t = {first:.6f} s (step at {f:.6g} Hz): clipped samples (flat at the rails) in "
                             f"{n_bad} of {plan.n_periods} periods: refusing")
        notes.append(f"{f:.6g} Hz: {n_bad} of {plan.n_periods} periods dropped for clipping "
                     f"({', '.join(chans)}, first at t = {first:.6f} s)")
    keep = np.flatnonzero(good)
    if keep.size < cmap.analysis.min_periods:
        _short(seg, plan, cmap, keep.size, notes)
        return None
    per = (ph[:, keep] * np.exp(-1j * w * (t_win[keep] - plan.t_ref_s))[None, :]).T * scales[None, :]
    if shaft_hz > 0 and cmap.analysis.shaft_orders > 0:
        theta = (pulses.angle(t_win[keep]) if pulses is not None else 2.0 * np.pi * shaft_hz * t_win[keep])
        grid = plan.t_first_s + keep / f
        phase = w * (t_win[keep] - grid)
        mean, var, dof = shaft_harmonic_fit(per, f, shaft_hz, cmap.analysis.shaft_orders,
                                            shaft_angle_rad=theta, window_phase_rad=phase)
    else:
        mean, var, _ = average_periods(per)
        dof = 2 * (keep.size - 1)
    out = _StepOut(f, plan.t_ref_s, per, mean, var, int(keep.size), int(dof))
    if orders:
        assert pulses is not None  # the map refuses sidebands without a keyphasor or at rest
        win = np.concatenate(wins, axis=1)[:, keep]  # (n_out, N, L)
        out.sb_phasor, out.sb_var = _sidebands(seg, plan, win, starts[keep], scales[len(ins):], pulses, shaft_hz,
                                               orders)
    return out


def _sidebands(seg: TimeRecord, plan: StepPlan, win: np.ndarray, starts: np.ndarray, scales: np.ndarray,
               pulses: Pulses, shaft_hz: float, orders: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """The shaft-referenced sidebands ``orders`` (K, n_out) m and their variances m^2 of one step from the
    probes' kept windows ``win`` (n_out, N, L; recorded units) starting at the record indices ``starts`` (N,):
    the tones of :func:`~rotorcheck.signal.sidebands.tone_set` (resolution ``f / N``) fitted in the local time
    ``t - t_ref`` with a slow drift fitted jointly, times ``exp(-j k theta)`` with the keyphasor
    angle ``theta`` at ``t_ref``, scaled; NaN where the tone is not separable."""
    f = plan.frequency_hz
    n_out, n_per, length = win.shape
    tau = (seg.t0_s - plan.t_ref_s) + (starts[:, None] + np.arange(length)[None, :]).reshape(-1) / seg.fs_hz
    tones = tone_set(f, shaft_hz, orders, f / n_per)
    if tones.freq_hz.max() >= 0.5 * seg.fs_hz:
        raise InputError(seg.path, "analysis.sideband_orders",
                         f"t = {plan.t_ref_s:.6f} s (step at {f:.6g} Hz): a fitted tone at "
                         f"{tones.freq_hz.max():.6g} Hz is above the Nyquist frequency {0.5 * seg.fs_hz:g} Hz")
    amp, var = fit_tones(win.reshape(n_out, -1).T, tau, tones, drift_degree=2 if n_per >= 6 else 1)
    ph, v = requested_orders(amp, tones, orders), requested_orders(var, tones, orders)
    theta = float(pulses.angle(np.array([plan.t_ref_s]))[0])
    return shaft_referenced(ph, orders, theta) * scales[None, :], v * (scales**2)[None, :]


def _short(seg: TimeRecord, plan: StepPlan, cmap: ChannelMap, n: int, notes: list[str]) -> None:
    msg = (f"step at {plan.frequency_hz:.6g} Hz ({plan.t_ref_s:.6f}-{plan.end_s:.6f} s) has {n} usable periods "
           f"after settling, fewer than min_periods {cmap.analysis.min_periods}")
    if cmap.analysis.short_step == "refuse":
        raise InputError(seg.path, f"t = {plan.t_ref_s:.6f} s", msg + ": refusing (analysis.short_step: refuse)")
    notes.append("warning: " + msg + ": step dropped")


def _speed(segments: Sequence[TimeRecord], cmap: ChannelMap, notes: list[str]) -> tuple[float, list[Pulses | None]]:
    """Shaft speed (Hz) and each segment's repaired pulses (None without a keyphasor)."""
    if cmap.speed_rpm == 0.0:
        return 0.0, [None] * len(segments)
    if cmap.keyphasor is None:
        assert cmap.speed_rpm is not None
        notes.append(f"no keyphasor: shaft at the map's {cmap.speed_rpm:g} rpm (angle unknown; harmonics fitted "
                     "with a constant speed)")
        return cmap.speed_rpm / 60.0, [None] * len(segments)
    kp = cmap.keyphasor
    out: list[Pulses | None] = []
    for seg in segments:
        t = find_pulses(seg, kp.channel, kp.threshold)
        if t.size == 0:
            raise InputError(seg.path, f"channel {kp.channel!r}",
                             f"t = {seg.t0_s:.6f}-{seg.t_end_s:.6f} s: no keyphasor pulses (the shaft turns: "
                             f"speed_rpm {cmap.speed_rpm if cmap.speed_rpm is not None else 'not given'}); set "
                             "speed_rpm: 0 for a shaft at rest")
        p = repair_pulses(t, seg.path, kp.channel)
        notes.extend(p.repairs)
        out.append(p)
    periods = np.concatenate([np.diff(p.times) for p in out if p is not None])
    return float(1.0 / np.median(periods)), out


def analyse(records: Sequence[TimeRecord], cmap: ChannelMap, sources: Sequence[tuple[str, str]] = ()) -> IngestResult:
    """Analyse time-ordered segments (:func:`~rotorcheck.ingest.record.concatenate`) into a one-run sweep."""
    notes: list[str] = []
    segments = list(records)
    for seg in segments:
        for name in cmap.channel_names():
            seg.column(name)
    shaft_hz, pulses = _speed(segments, cmap, notes)
    plans = plan_steps(segments, cmap, notes)
    scales = np.array([*(c.scale for c in cmap.inputs), *(p.scale for p in cmap.probes)])
    done: list[_StepOut] = []
    drift = 0.0
    for plan in plans:
        if plan.segment < 0 or plan.n_periods < cmap.analysis.min_periods:
            seg = segments[plan.segment] if plan.segment >= 0 else segments[-1]
            _short(seg, plan, cmap, plan.n_periods, notes)
            continue
        seg = segments[plan.segment]
        p = pulses[plan.segment]
        out = _analyse_step(seg, plan, cmap, scales, p, shaft_hz, notes)
        if out is not None:
            done.append(out)
            if p is not None:
                drift = max(drift, p.drift(plan.t_first_s, plan.t_first_s + out.n / out.frequency_hz))
    if not done:
        raise InputError(segments[0].path if segments else None, "steps", "no step with enough periods to analyse")
    groups = _patterns(done, cmap, segments[0].path)
    fitted = shaft_hz > 0 and cmap.analysis.shaft_orders > 0
    if fitted:
        dof = min(s.dof for s in done)
        notes.append(f"shaft harmonics 1X..{cmap.analysis.shaft_orders}X fitted out with the keyphasor angle: the "
                     f"stored phasors and output_var are that fit's (real dof >= {dof}); per-period phasors not "
                     "stored (a reader would fit the harmonics again)")
    if pulses[0] is not None:
        notes.append(f"speed {60 * shaft_hz:.6g} rpm from the keyphasor; largest drift within a step "
                     f"{100 * drift:.3g} % (max-min revolution over the median)")
    orders = cmap.analysis.sideband_orders
    if orders:
        n_nan = sum(int(np.isnan(s.sb_var[:, 0]).sum()) for s in done if s.sb_var is not None)
        notes.append(f"sidebands k = {', '.join(str(k) for k in orders)} read by the least-squares fit of known "
                     "tones on each step's analysed samples, referenced to the keyphasor's shaft angle at the step "
                     f"start; {n_nan} of {len(done) * len(orders)} not separable (NaN)")
    return _result(groups, cmap, 60.0 * shaft_hz, notes, segments, sources, keep=not fitted)


def _patterns(done: list[_StepOut], cmap: ChannelMap, path: str) -> list[list[_StepOut]]:
    """Steps grouped by frequency (relative 1e-4 or a quarter of ``step_rtol``), each group in time
    order: one step per frequency with one input; with several inputs the excitation patterns, the
    same number at every frequency."""
    done = sorted(done, key=lambda s: s.frequency_hz)
    tol = min(1e-4, 0.25 * cmap.analysis.step_rtol)
    groups: list[list[_StepOut]] = [[done[0]]]
    for s in done[1:]:
        if s.frequency_hz <= groups[-1][-1].frequency_hz * (1 + tol):
            groups[-1].append(s)
        else:
            groups.append([s])
    groups = [sorted(g, key=lambda s: s.t_ref_s) for g in groups]
    n_in = len(cmap.inputs)
    sizes = [len(g) for g in groups]
    if n_in == 1 and max(sizes) > 1:
        f = groups[sizes.index(max(sizes))][0].frequency_hz
        raise InputError(path, "steps", f"two steps at {f:.6g} Hz (one input: frequencies must differ)")
    if n_in > 1 and (min(sizes) != max(sizes) or min(sizes) < n_in):
        k = int(np.argmin(sizes)) if min(sizes) < n_in else next(i for i, z in enumerate(sizes) if z != sizes[0])
        raise InputError(path, "steps", f"{sizes[k]} excitation pattern(s) at {groups[k][0].frequency_hz:.6g} Hz, "
                                        f"{max(sizes)} elsewhere: every frequency needs the same number, at least "
                                        f"{n_in} (one per input)")
    return groups


def _result(groups: list[list[_StepOut]], cmap: ChannelMap, speed_rpm: float, notes: list[str],
            segments: Sequence[TimeRecord], sources: Sequence[tuple[str, str]], keep: bool) -> IngestResult:
    n_in = len(cmap.inputs)
    freqs = np.array([np.mean([s.frequency_hz for s in g]) for g in groups])
    n = np.array([[s.n for s in g] for g in groups], dtype=np.int32)  # (f, n_exc)
    mean = np.array([[s.mean for s in g] for g in groups])  # (f, n_exc, n_ch)
    var = np.array([[s.var for s in g] for g in groups])
    pp = None
    if cmap.analysis.keep_periods and keep:
        pp = np.full((*n.shape, int(n.max()), mean.shape[2]), np.nan + 1j * np.nan)
        for j, g in enumerate(groups):
            for e, s in enumerate(g):
                pp[j, e, : s.n] = s.per_period
    fs = sorted({seg.fs_hz for seg in segments})
    head = (f"ingested from {len(sources) or len(segments)} file(s), {len(segments)} segment(s), fs "
            f"{', '.join(f'{v:g}' for v in fs)} Hz; {n.size} steps")
    text = "; ".join([head, *notes])
    if n_in == 1:
        run = Run.from_phasors(cmap.run_id, speed_rpm, freqs, mean[:, 0, :1], mean[:, 0, 1:], var[:, 0, 1:],
                               n[:, 0], period_phasor=None if pp is None else pp[:, 0], notes=text)
    else:
        run = Run.from_patterns(cmap.run_id, speed_rpm, freqs, mean[..., :n_in], mean[..., n_in:], var[..., n_in:],
                                n, input_var=var[..., :n_in], period_phasor=pp, notes=text)
    orders = cmap.analysis.sideband_orders
    if orders:  # (f, n_exc, K, n_out), shaft-referenced
        run.with_sidebands(np.asarray(orders, dtype=np.int32),
                           np.array([[s.sb_phasor for s in g] for g in groups]),
                           np.array([[s.sb_var for s in g] for g in groups]))
    channels = [Channel(c.channel, "input", c.station, c.direction, "force", "N") for c in cmap.inputs]
    channels += [Channel(p.channel, "output", p.station, p.direction, "displacement", "m") for p in cmap.probes]
    sweep = Sweep(rig_id=cmap.resolved_rig_id(), source="measured",
                  generator=f"rotorcheck {__version__} ingest ({', '.join(os.path.basename(p) for p, _ in sources)})",
                  created_utc=utc_now_iso(), channels=channels, runs={run.run_id: run})
    attrs = {
        "ingest_sources": json.dumps([{"path": p, "sha256": h} for p, h in sources]),
        "ingest_channel_map": cmap.to_json(),
        "ingest_settings": json.dumps({**cmap.analysis.model_dump(mode="json"), "method": METHOD,
                                       **({"sideband_method": SIDEBAND_METHOD} if orders else {})}, sort_keys=True),
    }
    summary = {"run_id": run.run_id, "rig_id": sweep.rig_id, "speed_rpm": speed_rpm, "n_steps": int(n.size),
               "f_min_hz": float(freqs[0]), "f_max_hz": float(freqs[-1]), "n_periods_min": int(n.min()),
               "n_periods_max": int(n.max()), "notes": notes, "sources": [p for p, _ in sources]}
    return IngestResult(sweep, attrs, summary, notes)
