"""A sweep's runs read against the rig: :class:`MeasuredRun` (band, channel pairs, shaft harmonics removed),
frequency grids, resampling, and the FRF estimates (m/N) with their variances (m^2/N^2)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import chdtri

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig, load_config
from rotorcheck.errors import InputError
from rotorcheck.fe.assembly import build_system
from rotorcheck.nominal import ChannelPair, channel_port, pair_receptance, port_label
from rotorcheck.robust.lft import additive_me
from rotorcheck.robust.measured import FrfEstimate, combine_sweeps, welch_dof
from rotorcheck.robust.measured import frf_estimate as _est
from rotorcheck.robust.noise import point_miss
from rotorcheck.signal.harmonics import ShaftHarmonics, lockin_resolution_hz, shaft_harmonic_points
from rotorcheck.signal.lockin import SHAFT_ORDERS, fit_shaft_harmonics, remove_shaft_harmonics
from rotorcheck.signal.sidebands import sideband_points, sideband_statistic
from rotorcheck.sweep.format import Sweep, ls_frf, ls_frf_var
from rotorcheck.sweep.hdf5io import read_sweep, sweep_sha256
from rotorcheck.workflow.frf import MeasuredFRF
from rotorcheck.workflow.rigs import rig_for


@dataclass(frozen=True)
class SidebandFRF:
    """A run's sideband receptances (sweep contract version 3), in band, per channel pair: ``frequency_hz`` (f,)
    the excitation frequencies (the run's own grid, kept when the run is resampled); ``order`` (K,) the orders k of
    the tones at ``f + k speed / 60``; ``frf`` (f, K, P) m/N, shaft-referenced, NaN where the record could not
    separate the tone; ``var`` (f, K, P) (m/N)^2 its variance."""

    frequency_hz: np.ndarray
    order: np.ndarray
    frf: np.ndarray
    var: np.ndarray
    speed_hz: float = 0.0
    n_periods: np.ndarray | None = None  # (f,) periods each point averaged (the fewest over the patterns)

    def statistic(self) -> tuple[np.ndarray, np.ndarray]:
        """Per point (f,) ``sum 2|S|^2/var`` over its separable tones, divided by the tones' correlation scale (a
        conservative chi-square; :func:`rotorcheck.signal.sidebands.sideband_points`), and the tones' count."""
        if self.n_periods is None:
            return sideband_points(self.frf, self.var)
        return sideband_statistic(self.frf, self.var, self.frequency_hz, self.speed_hz, [int(k) for k in self.order],
                                  self.n_periods)


def _sidebands(run: Any, cols: list[tuple[int, int]], keep: np.ndarray) -> SidebandFRF | None:
    """The run's sideband receptances for the pairs ``cols`` at the points ``keep`` (None without sidebands)."""
    sb = run.sideband_frf()
    if sb is None:
        return None
    frf, var = sb  # (f, K, n_out, n_in)
    return SidebandFRF(np.asarray(run.frequency)[keep], np.asarray(run.sideband_order),
                       np.stack([frf[:, :, o, i] for o, i in cols], axis=2)[keep],
                       np.stack([var[:, :, o, i] for o, i in cols], axis=2)[keep], abs(float(run.speed_rpm)) / 60.0,
                       np.min(np.asarray(run.n_periods_exc), axis=1)[keep])


@dataclass
class MeasuredRun:
    """One run of a sweep file restricted to the rig's analysis band (SISO: actuator -> sensor)."""

    path: Path
    sha256: str
    rig_id: str
    run_id: str
    speed_rpm: float
    frequency_hz: np.ndarray  # (f,) Hz, in band
    W: np.ndarray  # (f,) input force phasor, N
    Zt: np.ndarray  # (f,) output displacement phasor, m
    output_var: np.ndarray  # (f,) variance of the mean output phasor, m^2
    n_periods: np.ndarray  # (f,)
    band_hz: tuple[float, float]
    n_dropped: int = 0  # points of the run outside the band
    dof: np.ndarray | None = None  # (f,) real degrees of freedom of output_var (2 (N - q))
    harmonics_removed: int = 0  # shaft-speed orders removed from the per-period phasors (0: none)
    # every measured channel pair (output <- input), the rig's own actuator -> sensor first; W, Zt and
    # output_var above are that first pair's phasors. Several pairs: their FRFs (f, P) m/N, the
    # variances of those FRFs (f, P) m^2/N^2 and the variances' real degrees of freedom (f, P)
    pairs: tuple[ChannelPair, ...] = ()
    frf_pairs: np.ndarray | None = None
    var_pairs: np.ndarray | None = None
    dof_pairs: np.ndarray | None = None
    noise_source: str = ""  # an FRF-only run: where its variance came from ("measured" | "assumed: ...")
    resampled_from: int = 0  # points of the file's grid when interpolated onto another grid (0: not)
    sidebands: SidebandFRF | None = None  # the sideband receptances where the sweep holds them (version 3)

    @property
    def n_pairs(self) -> int:
        """Measured channel pairs (1 for a one-actuator, one-sensor sweep)."""
        return max(len(self.pairs), 1)

    @property
    def frf(self) -> np.ndarray:
        """Measured receptance Zt / W (f,), m/N."""
        return self.Zt / self.W

    def measured_frf(self) -> MeasuredFRF:
        """The run as a :class:`~rotorcheck.workflow.frf.MeasuredFRF`: (f, P) with variances, dof and labels."""
        est = frf_estimate(self)
        labels = [f"{o}<-{i}" for o, i in pair_keys(self)] or ["sensor<-actuator"]
        return MeasuredFRF(self.frequency_hz, est.frf, est.var, est.dof, labels, self.path, self.sha256,
                           self.rig_id, self.run_id, self.speed_rpm, self.band_hz, self.harmonics_removed,
                           self.noise_source)


def load_rig_and_runs(sweep_path: str | Path, rig_path: str | Path | None = None,
                      baseline_path: str | Path | None = None, run_id: str | None = None, every_run: bool = False,
                      sha256: str | None = None) -> tuple[RigConfig, Path, list[MeasuredRun]]:
    """Read a sweep file once: its rig (:func:`rig_for`), that rig's file, and its runs checked against the
    rig: ``run_id``; else every run with ``every_run``; else the file's one run (several: an error asking
    for ``--run``); ``sha256``: the file's digest when the caller has it (else computed)."""

    p = Path(sweep_path)
    sweep = read_sweep(p)
    rig_file = rig_for(rig_path, sweep.rig_id, baseline_path)
    config = load_config(rig_file)
    sha = sha256 if sha256 is not None else sweep_sha256(p)
    ids: list[str | None] = list(sweep.runs) if every_run and run_id is None else [run_id]
    return config, rig_file, [measured_run(sweep, config, rid, p, sha) for rid in ids]


def load_rig_and_run(sweep_path: str | Path, rig_path: str | Path | None = None, run_id: str | None = None
                     ) -> tuple[RigConfig, MeasuredRun]:
    """Read a sweep file once: its rig (``rig_path``, or the bundled rig named by its ``rig_id``) and
    the run, checked against that rig (:func:`load_run`)."""
    config, _, runs = load_rig_and_runs(sweep_path, rig_path, None, run_id)
    return config, runs[0]


def read_runs(path: str | Path, config: RigConfig, run_ids: list[str] | None = None,
              sha256: str | None = None) -> list[MeasuredRun]:
    """Every run of a sweep file (or those of ``run_ids``), read once, checked against ``config``;
    ``sha256``: the file's digest when the caller has it already (else it is computed)."""

    p = Path(path)
    sweep = read_sweep(p)
    sha = sha256 if sha256 is not None else sweep_sha256(p)
    return [measured_run(sweep, config, rid, p, sha) for rid in (run_ids if run_ids is not None else sweep.runs)]


def load_run(path: str | Path, config: RigConfig, run_id: str | None = None,
             shaft_orders: int = SHAFT_ORDERS) -> MeasuredRun:
    """Read a sweep file, check it belongs to ``config`` (rig id, channels) and cut the band.

    A rotating run that stores per-period phasors gets its shaft-speed harmonics (1X ..
    ``shaft_orders`` X) fitted out before the phasor and its variance are formed (0: keep the
    file's averaged phasors).
    """

    p = Path(path)
    return measured_run(read_sweep(p), config, run_id, p, sweep_sha256(p), shaft_orders)


def measured_run(sweep: Sweep, config: RigConfig, run_id: str | None = None, path: str | Path = "<memory>",
                 sha256: str = "", shaft_orders: int = SHAFT_ORDERS) -> MeasuredRun:
    """:func:`load_run` on a :class:`rotorcheck.sweep.format.Sweep` already in memory."""
    p = Path(path)
    if sweep.rig_id != config.rig_id:
        raise InputError(p, "/@rig_id", f"sweep is of rig {sweep.rig_id!r}, the rig file is {config.rig_id!r}")
    if run_id is None:
        if len(sweep.runs) != 1:
            raise InputError(p, "/runs", f"{len(sweep.runs)} runs ({', '.join(sweep.runs)}); choose one with --run")
        run_id = next(iter(sweep.runs))
    if run_id not in sweep.runs:
        raise InputError(p, f"/runs/{run_id}", f"no such run (runs: {', '.join(sweep.runs)})")
    run = sweep.runs[run_id]
    pairs, cols = _channel_pairs(sweep, config, p)
    lo, hi = config.analysis.band_hz
    f = run.frequency
    keep = (f >= lo - 1e-9) & (f <= hi + 1e-9)
    if not np.any(keep):
        raise InputError(p, f"/runs/{run_id}/frequency", f"no point inside the analysis band {lo:g}-{hi:g} Hz")
    if run.is_frf_only:
        return _frf_only_run(run, pairs, cols, p, sha256, sweep.rig_id, keep, (lo, hi))
    if len(pairs) > 1 or run.n_exc > 1:
        return _multi_pair_run(sweep, run, pairs, cols, p, sha256, keep, (lo, hi), shaft_orders)
    W, Z, var = run.input_phasor[:, 0], run.output_phasor[:, 0], run.output_var[:, 0]
    dof = 2.0 * (run.n_periods.astype(float) - 1.0)
    removed = 0
    if run.period_phasor is not None and run.speed_rpm != 0.0 and shaft_orders > 0:
        in_col = next(i for i, c in enumerate(sweep.channels) if c.role == "input")
        out_col = next(i for i, c in enumerate(sweep.channels) if c.role == "output")

        W, Z, var, dof = remove_shaft_harmonics(run.period_phasor, run.n_periods, f, abs(run.speed_rpm) / 60.0,
                                                in_col, out_col, shaft_orders)
        removed = shaft_orders
    return MeasuredRun(
        path=p, sha256=sha256, rig_id=sweep.rig_id, run_id=run_id, speed_rpm=float(run.speed_rpm),
        frequency_hz=f[keep], W=W[keep], Zt=Z[keep],
        output_var=var[keep], n_periods=run.n_periods[keep], band_hz=(lo, hi),
        n_dropped=int(np.count_nonzero(~keep)), dof=dof[keep], harmonics_removed=removed, pairs=tuple(pairs),
        sidebands=_sidebands(run, cols, keep),
    )


def _channel_pairs(sweep: Any, config: RigConfig, p: Path) -> tuple[list[Any], list[tuple[int, int]]]:
    """Every (output, input) channel pair of ``sweep`` as model ports, the rig's actuator -> sensor first,
    and each pair's (output, input) column. A channel off the model, or a sweep without the rig's own
    actuator and sensor, is refused naming the channel."""

    system = build_system(config) if config.kind == "rotor" else None  # to check each channel's station

    def port(ch: Any) -> Any:
        try:
            prt = channel_port(config, int(ch.node), ch.direction)
            if system is not None:
                system.port_dof(prt)
        except (KeyError, InputError) as exc:
            raise InputError(p, "/channels", f"channel {ch.name!r} (node {ch.node} {ch.direction}) is not on rig "
                             f"{config.rig_id!r}: {exc}") from None
        return prt

    ins = [port(c) for c in sweep.inputs]
    outs = [port(c) for c in sweep.outputs]
    if not ins or not outs:
        raise InputError(p, "/channels", "a sweep needs at least one input and one output channel")
    rig_ports = config.io_ports("reading a sweep against the rig")
    act, sen = rig_ports.actuator, rig_ports.sensor
    same = [port_label(x) for x in ins].count(port_label(act)), [port_label(x) for x in outs].count(port_label(sen))
    if same[0] != 1 or same[1] != 1:
        what = "actuator" if same[0] != 1 else "sensor"
        prt = act if what == "actuator" else sen
        chans, ports = (sweep.inputs, ins) if what == "actuator" else (sweep.outputs, outs)
        raise InputError(p, "/channels", f"the rig's {what} port ({port_label(prt)}) must be exactly one of the "
                         f"sweep's {'inputs' if what == 'actuator' else 'outputs'} ("
                         + ", ".join(f"{c.name} {port_label(x)}" for c, x in zip(chans, ports)) + ")")
    i0 = [port_label(x) for x in ins].index(port_label(act))
    o0 = [port_label(x) for x in outs].index(port_label(sen))
    order = [(o0, i0)] + [(o, i) for o in range(len(outs)) for i in range(len(ins)) if (o, i) != (o0, i0)]
    pairs = [ChannelPair(outs[o], ins[i], f"{sweep.outputs[o].name}/{sweep.inputs[i].name}") for o, i in order]
    return pairs, order


def _frf_only_run(run: Any, pairs: list[Any], cols: list[tuple[int, int]], p: Path, sha256: str, rig_id: str,
                  keep: np.ndarray, band: tuple[float, float]) -> MeasuredRun:
    """An FRF-only run (UFF58, a spreadsheet): its FRFs and stated variances (dof inf: treated as known);
    the first pair as a unit force so the one-channel steps run."""
    if run.frf_var is None:
        raise InputError(p, f"/runs/{run.run_id}/frf_var", "an FRF-only run needs frf_var (the FRF's variance) to "
                         "detect against; convert the file with --noise-var or --noise-source 'assumed: ...'")
    frf = np.stack([run.frf[:, o, i] for o, i in cols], axis=1)[keep]
    var = np.stack([run.frf_var[:, o, i] for o, i in cols], axis=1)[keep]
    nf = int(np.count_nonzero(keep))
    return MeasuredRun(
        path=p, sha256=sha256, rig_id=rig_id, run_id=run.run_id, speed_rpm=float(run.speed_rpm),
        frequency_hz=run.frequency[keep], W=np.ones(nf, complex), Zt=frf[:, 0], output_var=var[:, 0],
        n_periods=np.zeros(nf, dtype=np.int32), band_hz=band, n_dropped=int(np.count_nonzero(~keep)),
        dof=np.full(nf, np.inf), pairs=tuple(pairs), frf_pairs=frf, var_pairs=var, dof_pairs=np.full(var.shape, np.inf),
        noise_source=str(run.noise_source or ""),
    )


def _multi_pair_run(sweep: Any, run: Any, pairs: list[Any], cols: list[tuple[int, int]], p: Path, sha256: str,
                    keep: np.ndarray, band: tuple[float, float], shaft_orders: int) -> MeasuredRun:
    """Several channel pairs: per excitation pattern and channel the phasors (shaft harmonics fitted out of
    the per-period phasors where stored), the FRF matrix ``Y X^+`` per frequency and each entry's
    variance ``sum_e var(Y_eo) |X^+_ei|^2``, dof the smallest of the patterns that enter."""

    f = run.frequency
    X = np.array(run.input_phasor_exc, dtype=complex)  # (f, n_exc, n_in)
    Y = np.array(run.output_phasor_exc, dtype=complex)  # (f, n_exc, n_out)
    V = np.array(run.output_var_exc, dtype=float)
    n_per = np.asarray(run.n_periods_exc)
    D = 2.0 * (n_per.astype(float) - 1.0)[:, :, None] * np.ones(V.shape[2])  # (f, n_exc, n_out)
    removed = 0
    pp = run.period_phasor_exc
    if pp is not None and run.speed_rpm != 0.0 and shaft_orders > 0:

        in_cols = [j for j, c in enumerate(sweep.channels) if c.role == "input"]
        out_cols = [j for j, c in enumerate(sweep.channels) if c.role == "output"]
        n_in = len(in_cols)
        for e in range(X.shape[1]):  # each channel of each pattern fitted once
            mean, var, dof = fit_shaft_harmonics(pp[:, e], n_per[:, e], f, abs(run.speed_rpm) / 60.0,
                                                 in_cols + out_cols, shaft_orders)
            X[:, e, :], Y[:, e, :] = mean[:, :n_in], mean[:, n_in:]
            V[:, e, :], D[:, e, :] = var[:, n_in:], dof[:, n_in:]
        removed = shaft_orders
    H = ls_frf(X, Y)  # (f, n_out, n_in)
    Hv = ls_frf_var(X, V)
    pinv_used = np.abs(np.linalg.pinv(np.swapaxes(X, 1, 2))) > 0  # (f, n_exc, n_in): patterns entering input i
    frf = np.stack([H[:, o, i] for o, i in cols], axis=1)[keep]
    var = np.stack([Hv[:, o, i] for o, i in cols], axis=1)[keep]
    dof = np.stack([np.min(np.where(pinv_used[:, :, i], D[:, :, o], np.inf), axis=1) for o, i in cols], axis=1)[keep]
    i0 = cols[0][1]
    e0 = np.argmax(np.abs(X[:, :, i0]), axis=1)  # the pattern that drives the actuator most: its phasors
    rows = np.arange(f.size)
    return MeasuredRun(
        path=p, sha256=sha256, rig_id=sweep.rig_id, run_id=run.run_id, speed_rpm=float(run.speed_rpm),
        frequency_hz=f[keep], W=X[rows, e0, i0][keep], Zt=(frf[:, 0] * X[rows, e0, i0][keep]),
        output_var=var[:, 0] * np.abs(X[rows, e0, i0][keep]) ** 2, n_periods=n_per[rows, e0][keep], band_hz=band,
        n_dropped=int(np.count_nonzero(~keep)), dof=dof[:, 0], harmonics_removed=removed, pairs=tuple(pairs),
        frf_pairs=frf, var_pairs=var, dof_pairs=dof, sidebands=_sidebands(run, cols, keep),
    )


#: two frequency grids are the same when every point agrees within this (Hz): an ASCII UFF58 file keeps
#: 6 significant digits of the abscissa (up to 5e-4 Hz at 600 Hz)
GRID_TOLERANCE_HZ = 1e-3


def grid_mismatch(a: np.ndarray, b: np.ndarray, tolerance_hz: float = GRID_TOLERANCE_HZ) -> str | None:
    """Why grid ``a`` is not grid ``b`` (the size of the difference), or None when they match within
    ``tolerance_hz``."""
    if a.shape != b.shape:
        return (f"{a.size} points {a.min():g}-{a.max():g} Hz against {b.size} points {b.min():g}-{b.max():g} Hz"
                if a.size and b.size else f"{a.size} points against {b.size}")
    d = np.abs(a - b)
    k = int(np.argmax(d)) if d.size else 0
    if d.size and d[k] > tolerance_hz:
        return f"points differ by up to {d[k]:.3g} Hz (at {b[k]:g} Hz; tolerance {tolerance_hz:g} Hz)"
    return None


def _same_grid(a: np.ndarray, b: np.ndarray) -> bool:
    return grid_mismatch(a, b) is None


def resample_run(run: MeasuredRun, grid_hz: np.ndarray) -> MeasuredRun:
    """``run`` interpolated onto ``grid_hz`` (linear in the real and imaginary parts of each channel pair's
    FRF; an interpolated point's variance ``(1-t)^2 v_0 + t^2 v_1``, independent neighbours; dof the
    smaller). The result carries FRFs at a unit force. Points outside the run's range are refused."""
    f = run.frequency_hz
    g = np.asarray(grid_hz, dtype=float)
    if g.min() < f.min() - GRID_TOLERANCE_HZ or g.max() > f.max() + GRID_TOLERANCE_HZ:
        raise InputError(run.path, f"/runs/{run.run_id}/frequency", f"cannot resample {f.min():g}-{f.max():g} Hz "
                         f"onto {g.min():g}-{g.max():g} Hz without extrapolating")
    est = frf_estimate(run)
    j = np.clip(np.searchsorted(f, g, side="right") - 1, 0, f.size - 2)
    t = np.clip((g - f[j]) / (f[j + 1] - f[j]), 0.0, 1.0)[:, None]
    frf = (1 - t) * est.frf[j] + t * est.frf[j + 1]
    var = (1 - t) ** 2 * est.var[j] + t**2 * est.var[j + 1]
    dof = np.minimum(est.dof[j], est.dof[j + 1])
    n = g.size
    return dataclasses.replace(
        run, frequency_hz=g, W=np.ones(n, complex), Zt=frf[:, 0], output_var=var[:, 0],
        n_periods=np.minimum(run.n_periods[j], run.n_periods[j + 1]), dof=dof[:, 0], frf_pairs=frf, var_pairs=var,
        dof_pairs=dof, resampled_from=int(f.size))


def run_harmonics(runs: list[MeasuredRun], also_rpm: tuple[float, ...] = ()) -> ShaftHarmonics:
    """The points of the runs' (shared) grid on a shaft harmonic 1X..4X (:mod:`rotorcheck.signal.harmonics`):
    at every run's speed and at ``also_rpm`` (a baseline's), with each point's coarsest lock-in resolution
    ``f / N`` over the runs (N: the periods the point averaged; an FRF-only run assumes the default)."""
    f = runs[0].frequency_hz
    res = [lockin_resolution_hz(f, r.n_periods) for r in runs]
    speeds = tuple(dict.fromkeys([float(r.speed_rpm) for r in runs] + [float(s) for s in also_rpm]))
    return shaft_harmonic_points(f, speeds, np.max([r for r, _ in res], axis=0),
                                 assumed_periods=any(a for _, a in res))


def variance_dof(run: MeasuredRun) -> np.ndarray:
    return run.dof if run.dof is not None else 2.0 * (run.n_periods.astype(float) - 1.0)


def frf_estimate(run: MeasuredRun) -> FrfEstimate:
    """The run's FRF with its noise (variance of the mean FRF and its dof) for measured detection: one
    column per channel pair (f, P), the rig's actuator -> sensor first."""

    if run.frf_pairs is not None and run.var_pairs is not None and run.dof_pairs is not None:
        return FrfEstimate(run.frf_pairs, run.var_pairs, run.dof_pairs)
    return _est(run.W, run.Zt, run.output_var, variance_dof(run))


def healthy_estimate(runs: list[MeasuredRun]) -> FrfEstimate:
    """The measured healthy FRF: the mean of the healthy runs with its variance and Welch dof."""

    return combine_sweeps([frf_estimate(r) for r in runs])


#: healthy sweeps are averaged when none differs from the others' mean beyond this chance (Sidak over the sweeps)
REPEAT_LEVEL = 0.01


@dataclass(frozen=True)
class HealthyReference:
    """The healthy FRF a baseline detects against (:func:`healthy_reference`): ``estimate``; ``reference`` the
    run it is (None: the mean of every run); ``chi2`` (K,) each run's whitened distance from the mean of the
    others and ``threshold`` what a repeat stays below; ``note`` in words."""

    estimate: FrfEstimate
    reference: int | None
    chi2: np.ndarray
    threshold: float
    note: str


def healthy_reference(runs: list[MeasuredRun], exclude: np.ndarray | None = None) -> HealthyReference:
    """The healthy FRF of several healthy sweeps: their mean when they are repeats of one state (no sweep
    differs from the mean of the others beyond both noises: ``2 sum |T_i - mean_-i|^2 / (var_i + var_mean_-i)``
    below its quantile, each point's term 2 F(2, Welch dof) and the sum a scaled chi-square of their mean and
    variance, Sidak at :data:`REPEAT_LEVEL` over the sweeps); else the most central sweep alone (the least
    median whitened distance to the others). A mean of sweeps at different states (drift between them) is no
    state of the machine: its resonances are smeared beyond its own variance, and the change to a new sweep is
    then neither benign change nor noise as predicted. Points ``exclude`` (f,) (shaft harmonics) and points
    without a finite variance are left out."""
    ests = [frf_estimate(r) for r in runs]
    k = len(ests)
    if k == 1:
        return HealthyReference(ests[0], None, np.zeros(1), float("inf"), "")
    use = np.ones(ests[0].frf.shape[0], dtype=bool) if exclude is None else ~np.asarray(exclude, dtype=bool)

    def chi2(a: FrfEstimate, b: FrfEstimate) -> tuple[float, float, float]:
        """``(2 sum |a - b|^2 / (var_a + var_b), its mean and variance under a repeat)``: each point's term is
        2 F(2, d) with d the Welch dof of the two variances (chi-square with 2 dof where d is infinite)."""
        v = a.var + b.var
        ok = use[:, None] & np.isfinite(v) & (v > 0) & np.isfinite(a.frf) & np.isfinite(b.frf)
        d = welch_dof([a.var[ok], b.var[ok]], [a.dof[ok], b.dof[ok]])
        with np.errstate(divide="ignore", invalid="ignore"):
            mean = np.where(np.isfinite(d) & (d > 4), 2.0 * d / (d - 2.0), 2.0)
            var = np.where(np.isfinite(d) & (d > 4), 4.0 * d**3 / ((d - 2.0) ** 2 * (d - 4.0)), 4.0)
        return float(np.sum(2.0 * np.abs(a.frf - b.frf)[ok] ** 2 / v[ok])), float(mean.sum()), float(var.sum())

    loo = [chi2(e, combine_sweeps([o for j, o in enumerate(ests) if j != i])) for i, e in enumerate(ests)]
    dist = np.array([c for c, _, _ in loo])
    # the sum of the terms as a scaled chi-square with their mean and variance (Satterthwaite), Sidak over sweeps
    mean, var = max(m for _, m, _ in loo), max(v for _, _, v in loo)
    scale, nu = var / (2.0 * mean) if mean > 0 else 1.0, 2.0 * mean**2 / var if var > 0 else 0.0
    thr = float(scale * chdtri(nu, 1.0 - (1.0 - REPEAT_LEVEL) ** (1.0 / k))) if nu > 0 else float("inf")
    if np.all(dist <= thr):
        return HealthyReference(combine_sweeps(ests), None, dist, thr,
                                f"the {k} healthy sweeps are repeats of one state (each within {thr:.4g} of the "
                                f"others' mean in chi-square, the largest {dist.max():.4g}): their mean is the "
                                "healthy FRF")
    pair = np.zeros((k, k))  # symmetric: each pair once
    for i in range(k):
        for j in range(i + 1, k):
            pair[i, j] = pair[j, i] = chi2(ests[i], ests[j])[0]
    central = int(np.argmin([np.median(np.delete(row, i)) for i, row in enumerate(pair)]))
    note = (f"the {k} healthy sweeps differ beyond their noise ({int(np.sum(dist > thr))} of them from the others' "
            f"mean: chi-square up to {dist.max():.4g} against {thr:.4g} at {REPEAT_LEVEL:g}; drift between them): a "
            "mean of them is no state of the machine, so the healthy FRF is the most central sweep alone, "
            f"{runs[central].path.name} ({runs[central].run_id}); the others "
            "still bound the noise and the model error")
    return HealthyReference(ests[central], central, dist, thr, note)


def aligned_pairs(run: MeasuredRun, keys: list[list[str]] | None) -> MeasuredRun:
    """``run`` with its channel pairs in the order ``keys`` (``[output, input]`` labels) when it holds the
    same pairs in another order (a channel table with its rows in another order); as it is otherwise."""
    have = pair_keys(run)
    if keys is None or have == keys or sorted(have) != sorted(keys) or run.n_pairs < 2:
        return run
    # the rig's own pair stays first in both (it is placed first on reading), so W, Zt, output_var hold
    return with_pairs(run, [have.index(k) for k in keys])


def with_pairs(run: MeasuredRun, order: list[int]) -> MeasuredRun:
    """``run`` with the channel pairs of indices ``order``, in that order (their FRFs, variances and degrees of
    freedom); W, Zt and output_var stay the rig's own pair's phasors."""

    def cols(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else np.asarray(a)[:, order]

    return dataclasses.replace(run, pairs=tuple(run.pairs[k] for k in order), frf_pairs=cols(run.frf_pairs),
                               var_pairs=cols(run.var_pairs), dof_pairs=cols(run.dof_pairs))


def _show_pairs(keys: list[list[str]]) -> str:
    return ", ".join(f"{o}<-{i}" for o, i in keys)


@dataclass(frozen=True)
class PairGrid:
    """A several-pair run's outputs and inputs (model ports, first-seen order) when its pairs are every
    output against every input, and where each pair sits in the (output, input) matrix."""

    outputs: list[Any]
    inputs: list[Any]
    index: list[tuple[int, int]]

    @classmethod
    def of(cls, run: MeasuredRun) -> PairGrid | None:
        """The grid of ``run``'s pairs; None with one pair or when some output/input pair is missing."""

        if run.n_pairs < 2:
            return None
        outs = list({port_label(p.output): p.output for p in run.pairs}.items())
        ins = list({port_label(p.input): p.input for p in run.pairs}.items())
        if len(run.pairs) != len(outs) * len(ins):
            return None
        o_at, i_at = {k: n for n, (k, _) in enumerate(outs)}, {k: n for n, (k, _) in enumerate(ins)}
        index = [(o_at[port_label(p.output)], i_at[port_label(p.input)]) for p in run.pairs]
        return cls([v for _, v in outs], [v for _, v in ins], index)

    def matrix(self, cols: np.ndarray) -> np.ndarray:
        """(..., f, P) pair columns -> (..., f, n_out, n_in)."""
        out = np.zeros((*cols.shape[:-1], len(self.outputs), len(self.inputs)), dtype=cols.dtype)
        for k, (o, i) in enumerate(self.index):
            out[..., o, i] = cols[..., k]
        return out


def pair_experiments(rig: RigConfig, run: MeasuredRun, confidence: float = 0.99
                     ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray], np.ndarray]:
    """A several-pair run as experiments for the model-centred modes (``--enclose data``): ``(Me, W, Z,
    V)`` with Me the additive uncertainty on the model's FRF matrix (f, n_out, n_in), one experiment per
    input (unit force, W (f, n_in); Z the measured FRF column (f, n_out)) and V (f,) m/N the noise bound
    per point: the largest pair's standard deviation times the complex-Gaussian quantile, Sidak over
    every point and pair at ``confidence``."""

    grid = PairGrid.of(run)
    if run.n_pairs < 2 or run.frf_pairs is None or run.var_pairs is None:
        raise InputError(run.path, "/channels", "one channel pair: no experiments to form")
    if grid is None:
        raise InputError(run.path, "/channels", "the channel pairs are not every output against every input")
    nf = run.frequency_hz.size
    T = grid.matrix(np.asarray(run.frf_pairs))
    Gm = grid.matrix(pair_receptance(rig, run.frequency_hz, run.speed_rpm, run.pairs))
    q = float(np.sqrt(-np.log(point_miss(confidence, nf * len(run.pairs)))))
    V = q * np.sqrt(np.max(run.var_pairs, axis=1))
    n_in = len(grid.inputs)
    W = [np.broadcast_to(np.eye(n_in, dtype=complex)[i], (nf, n_in)).copy() for i in range(n_in)]
    return additive_me(Gm), W, [T[:, :, i] for i in range(n_in)], V


def pair_keys(run: MeasuredRun) -> list[list[str]]:
    """The run's channel pairs as [output, input] port labels (the rig's actuator -> sensor first)."""
    return [list(p.key()) for p in run.pairs]


def baseline_pairs(baseline: Baseline) -> list[list[str]] | None:
    """The channel pairs a baseline was validated on (None: made before channel pairs were stored)."""
    return baseline.healthy.channel_pairs


def per_pair(x: np.ndarray, f: np.ndarray, n_pairs: int, run: MeasuredRun) -> np.ndarray:
    """A healthy array as (f, P), checked against the run's channel pairs."""
    a = np.asarray(x)
    a = a.reshape(f.size, -1) if a.size % max(f.size, 1) == 0 else a
    if a.shape != (f.size, n_pairs):
        raise InputError(run.path, "/channels", f"the sweep has {n_pairs} channel pairs on {f.size} points, the "
                         f"healthy baseline {a.shape[1] if a.ndim == 2 else '?'} on {a.shape[0]}")
    return a


def healthy_frf_of(baseline: Baseline) -> np.ndarray | None:
    """The baseline's healthy FRF of the io pair (f,), m/N: stored, else from its phasors; None without."""
    if baseline.healthy_frf is not None:
        return np.asarray(baseline.healthy_frf)[:, 0]
    if baseline.input_phasor is not None and baseline.output_phasor is not None:
        return np.asarray(baseline.output_phasor[:, 0] / baseline.input_phasor[:, 0])
    return None

