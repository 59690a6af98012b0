"""Simulated time recordings of a stepped-sine test, written in the formats :mod:`rotorcheck.ingest` reads.

Same plant, noise and shaft angle as the phasor path (:func:`rotorcheck.sim.simulator.simulate_fast`):
the same timeline (:func:`point_start_times`, :func:`settle_counts`), the same output tones per point in
its local time (:func:`rotorcheck.sim.simulator.local_tones`), the force ``Re{F exp(j w (t - t0_j))}``
(N), white Gaussian noise of the settings' per-sample std on the outputs (m) and the force (N). What a
rig adds is modelled too: a sample clock not locked to the excitation (``fs_hz``), probes recorded in
volts (``sensitivity_v_per_m``) with a DC offset and a slow linear drift, an actuator current (A =
N / ``gain_n_per_a``) when asked, and a keyphasor: a pulse per revolution whose rising edge (a linear
ramp over a few samples, centred: its mid-level crossing) is at shaft angle 0 (shaft angle
``theta0 + 2 pi Omega t``, as :func:`rotorcheck.sim.rig_sim.at_shaft_angle`). Seeded, deterministic.

Writers: :func:`write_record` (mat v5, mat v7.3, TDMS, WAV, CSV, UFF58 type 1, HDF5, Parquet when pyarrow is
installed) and :func:`channel_map_dict` (the matching channel map, with the exact step table).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import h5py
import numpy as np

from rotorcheck.fileio import atomic_path
from rotorcheck.ingest.record import TimeRecord
from rotorcheck.sim.simulator import (
    Plant,
    StepSettings,
    Tone,
    _force,
    _freqs,
    _n_periods,
    disturbance_arrays,
    local_tones,
    point_start_times,
    settle_counts,
)

__all__ = ["RECORD_FORMATS", "RecordSpec", "SimulatedRecord", "channel_map_dict", "record_suffix",
           "simulate_record", "simulate_rig_record", "write_record"]

RECORD_FORMATS = ("mat", "mat73", "tdms", "wav", "csv", "uff", "hdf5", "parquet")
_EXT = {"mat": ".mat", "mat73": ".mat", "tdms": ".tdms", "wav": ".wav", "csv": ".csv", "uff": ".uff",
        "hdf5": ".h5", "parquet": ".parquet"}


@dataclass(frozen=True)
class RecordSpec:
    """How the rig records: sample rate (Hz), force as N or actuator current (A, with its gain N/A),
    probe sensitivity (V/m), offset (V) and drift (V/s), keyphasor height (V) and pulse width (fraction
    of a revolution), names of the channels."""

    fs_hz: float = 25600.0
    force_unit: str = "N"
    gain_n_per_a: float = 10.0
    sensitivity_v_per_m: float = 7874.0
    probe_offset_v: float = 0.5
    probe_drift_v_per_s: float = 0.002
    kp_high_v: float = 5.0
    kp_width: float = 0.1
    kp_ramp_samples: float = 3.0
    force_name: str = "force"
    probe_names: tuple[str, ...] = ()
    kp_name: str = "keyphasor"


@dataclass
class SimulatedRecord:
    """The record (channels in recorded units), the step table (Hz, s, s; one row per point, the
    patterns of a frequency in turn), the speed (rpm), the inputs' and the probes' (station, direction),
    the periods per frequency and the settling, the force channels' names."""

    record: TimeRecord
    steps: list[tuple[float, float, float]]
    speed_rpm: float
    force_ports: list[tuple[int, str]]
    probe_ports: list[tuple[int, str]]
    spec: RecordSpec
    n_periods: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    settle_periods: int = 16
    settle_s: float = 0.0
    force_names: list[str] = field(default_factory=list)


def _keyphasor(t: np.ndarray, speed_rpm: float, theta0: float, spec: RecordSpec) -> np.ndarray:
    """Pulse train (V): high for ``kp_width`` of a turn, its rising edge a ramp of ``kp_ramp_samples`` samples
    centred on shaft angle 0 (so that a crossing of the mid-level, where a keyphasor reader marks the pulse, is
    at angle 0)."""
    if speed_rpm == 0.0:
        return np.zeros(t.size)
    om = 2.0 * np.pi * speed_rpm / 60.0
    ramp = spec.kp_ramp_samples * om / (2.0 * np.pi * spec.fs_hz)  # a turn's fraction per ramp
    # the turn's fraction from half a ramp before angle 0
    frac = np.mod((theta0 + om * t) / (2.0 * np.pi) + 0.5 * ramp, 1.0)
    up = np.clip(frac / ramp, 0.0, 1.0)
    down = np.clip((spec.kp_width - frac) / ramp, 0.0, 1.0)
    return spec.kp_high_v * np.minimum(up, down)


def simulate_record(plant: Plant | Sequence[Plant], frequency_hz: Sequence[float] | np.ndarray,
                    settings: StepSettings, disturbances: Sequence[Tone] = (),
                    rng: np.random.Generator | int | None = 0, spec: RecordSpec | None = None,
                    speed_rpm: float = 0.0, shaft_angle_rad: float = 0.0,
                    force_port: tuple[int, str] | Sequence[tuple[int, str]] = (1, "x"),
                    probe_ports: Sequence[tuple[int, str]] = ((2, "x"),)) -> SimulatedRecord:
    """A stepped-sine recording of ``plant`` on the phasor path's timeline (see the module docstring).

    Several plants (one per input, as :func:`rotorcheck.sim.simulator.simulate_fast_patterns`): at
    each frequency the inputs are driven one at a time, each point with its own settling, on the same
    frequency-major timeline; ``force_port`` then lists the inputs' ports and the force channels are
    ``<force_name>0``, ``<force_name>1``, ... ``disturbances`` and ``shaft_angle_rad`` as
    :func:`rotorcheck.sim.rig_sim.at_shaft_angle` turned them (the tones already carry the start angle;
    it only places the keyphasor pulses). Noise: per sample, ``settings.output_noise_std`` (m) and
    ``settings.input_noise_std`` (N, on the driven input).
    """
    sp = spec or RecordSpec()
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    plants = [plant] if isinstance(plant, Plant) else list(plant)
    ports: list[tuple[int, str]] = ([force_port] if isinstance(force_port[0], int)  # type: ignore[list-item]
                                    else [(int(p[0]), str(p[1])) for p in force_port])  # type: ignore[index]
    ne = len(plants)
    if len(ports) != ne:
        raise ValueError(f"{len(ports)} force ports for {ne} plants (one per input)")
    f = _freqs(frequency_hz)
    n = _n_periods(settings, f.size)
    f_pts, n_pts = np.repeat(f, ne), np.repeat(n, ne)
    t0 = point_start_times(f_pts, dataclasses.replace(settings, n_periods=[int(v) for v in n_pts]))
    ends = t0 + (settle_counts(f_pts, settings) + n_pts) / f_pts
    n_out = plants[0].n_out
    names = list(sp.probe_names) or [f"probe{k}" for k in range(n_out)]
    if len(names) != n_out:
        raise ValueError(f"{len(names)} probe names for {n_out} outputs")
    n_samp = int(np.ceil((ends[-1] - settings.t_start_s) * sp.fs_hz))
    t = settings.t_start_s + np.arange(n_samp) / sp.fs_hz
    u = np.zeros((ne, n_samp))
    y = np.zeros((n_out, n_samp))
    d_freq, d_amp = disturbance_arrays(disturbances, n_out)
    for q, fq in enumerate(f_pts):
        e = q % ne
        a, b = np.searchsorted(t, [t0[q], ends[q]])
        b2 = np.searchsorted(t, t0[q + 1]) if q + 1 < f_pts.size else n_samp  # dwell: disturbances only
        force = _force(settings.force_amplitude, fq)
        tau = t[a:b] - t0[q]
        u[e, a:b] = np.real(force * np.exp(2j * np.pi * fq * tau))
        freqs, amps = local_tones(plants[e], fq, force, t0[q], d_freq, d_amp)
        y[:, a:b] = np.real(amps.T @ np.exp(2j * np.pi * np.outer(freqs, tau)))
        if b2 > b and d_freq.size:
            y[:, b:b2] = np.real(d_amp.T @ np.exp(2j * np.pi * np.outer(d_freq, t[b:b2])))
        if settings.input_noise_std:
            u[e, a:b] += float(settings.input_noise_std) * gen.standard_normal(b - a)
    out_std = np.broadcast_to(np.asarray(settings.output_noise_std, dtype=np.float64), (n_out,))
    y = y + out_std[:, None] * gen.standard_normal((n_out, n_samp))
    chans: dict[str, Any] = {}
    force_names = [sp.force_name] if ne == 1 else [f"{sp.force_name}{e}" for e in range(ne)]
    for e, name in enumerate(force_names):
        chans[name] = u[e] / sp.gain_n_per_a if sp.force_unit == "A" else u[e]
    for k, name in enumerate(names):
        chans[name] = y[k] * sp.sensitivity_v_per_m + sp.probe_offset_v + sp.probe_drift_v_per_s * t
    if speed_rpm != 0.0:
        chans[sp.kp_name] = _keyphasor(t, speed_rpm, shaft_angle_rad, sp)
    rec = TimeRecord("<simulated>", sp.fs_hz, settings.t_start_s, chans)
    steps = [(float(fq), float(a), float(b)) for fq, a, b in zip(f_pts, t0, ends)]
    return SimulatedRecord(rec, steps, speed_rpm, ports, list(probe_ports), sp, n, settings.settle_periods,
                           settings.settle_s, force_names)


def channel_map_dict(sim: SimulatedRecord, rig_id: str, fmt: str = "hdf5", with_steps: bool = True,
                     run_id: str | None = None, **analysis: Any) -> dict[str, Any]:
    """The channel map of a record written by :func:`write_record` in ``fmt`` (WAV channels are
    numbered "0", "1", ... in the record's channel order); the analysis settles as the simulator did,
    ``analysis`` adds settings."""
    sp = sim.spec
    names = list(sim.record.channels)
    label = (lambda n: str(names.index(n))) if fmt == "wav" else (lambda n: n)
    forces: list[dict[str, Any]] = []
    for name, port in zip(sim.force_names, sim.force_ports):
        fc: dict[str, Any] = {"channel": label(name), "station": port[0], "direction": port[1], "unit": sp.force_unit}
        if sp.force_unit == "A":
            fc["gain_n_per_a"] = sp.gain_n_per_a
        forces.append(fc)
    probe_names = [n for n in names if n not in (*sim.force_names, sp.kp_name)]
    doc: dict[str, Any] = {
        "rig_id": rig_id,
        "run_id": run_id or f"{sim.speed_rpm:g}rpm",
        **({"force": forces[0]} if len(forces) == 1 else {"forces": forces}),
        "probes": [{"channel": label(n), "station": p[0], "direction": p[1], "unit": "V",
                    "sensitivity_v_per_m": sp.sensitivity_v_per_m} for n, p in zip(probe_names, sim.probe_ports)],
    }
    if fmt == "mat73":
        doc["format"] = "mat"
    if sim.speed_rpm != 0.0:
        doc["keyphasor"] = {"channel": label(sp.kp_name)}
    else:
        doc["speed_rpm"] = 0.0
    if with_steps:
        doc["steps"] = [{"frequency_hz": f, "start_s": a, "end_s": b} for f, a, b in sim.steps]
    doc["analysis"] = {"settle_periods": sim.settle_periods, "settle_s": sim.settle_s, **analysis}
    return doc


def record_suffix(fmt: str) -> str:
    """The file extension of a record format (".mat" for both MATLAB versions)."""
    return _EXT[fmt]


def write_record(sim: SimulatedRecord | TimeRecord, path: str | os.PathLike[str], fmt: str | None = None) -> str:
    """Write the record in ``fmt`` (default from the extension; "mat73" for MATLAB v7.3) atomically;
    returns the path written."""
    rec = sim.record if isinstance(sim, SimulatedRecord) else sim
    p = os.fspath(path)
    kind = fmt or next((k for k, e in _EXT.items() if p.endswith(e) and k != "mat73"), "")
    if kind not in RECORD_FORMATS:
        raise ValueError(f"unknown record format {kind!r} (known: {', '.join(RECORD_FORMATS)})")
    cols = {k: np.asarray(v, dtype=np.float64) for k, v in rec.channels.items()}
    with atomic_path(p) as tmp:
        _WRITERS[kind](str(tmp), cols, rec.fs_hz, rec.t0_s)
    return p


def _mat(path: str, cols: dict[str, np.ndarray], fs: float, t0: float) -> None:
    import scipy.io  # lazy: scipy.io only for a MATLAB v5 file

    with open(path, "wb") as fh:
        scipy.io.savemat(fh, {**cols, "sample_rate_hz": fs, "start_s": t0}, do_compression=False)


def _mat73(path: str, cols: dict[str, np.ndarray], fs: float, t0: float) -> None:
    with h5py.File(path, "w", userblock_size=512) as h5:
        for name, a in {**cols, "sample_rate_hz": np.array([fs]), "start_s": np.array([t0])}.items():
            ds = h5.create_dataset(name, data=np.asarray(a, dtype=np.float64)[:, None], chunks=None)
            ds.attrs["MATLAB_class"] = np.bytes_("double")
    head = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created by: rotorcheck HDF5 schema 1.00 ."
    with open(path, "r+b") as fh:
        fh.write(head.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM")


def _tdms(path: str, cols: dict[str, np.ndarray], fs: float, t0: float, chunk: int = 1 << 18) -> None:
    from nptdms import ChannelObject, GroupObject, TdmsWriter  # lazy: npTDMS only for a TDMS file

    n = len(next(iter(cols.values())))
    with TdmsWriter(path) as w:
        for s in range(0, max(n, 1), chunk):
            objs: list[Any] = [GroupObject("record", properties={"n_samples": n})] if s == 0 else []
            for name, a in cols.items():
                props = {"wf_increment": 1.0 / fs, "wf_start_offset": t0, "unit_string": "V"} if s == 0 else {}
                objs.append(ChannelObject("record", name, a[s : s + chunk], properties=props))
            w.write_segment(objs)


def _wav(path: str, cols: dict[str, np.ndarray], fs: float, t0: float) -> None:
    import scipy.io.wavfile  # lazy: scipy.io only for a WAV file

    if abs(fs - round(fs)) > 1e-9 or t0 != 0.0:
        raise ValueError("WAV needs an integer sample rate and a record starting at 0 s")
    data = np.stack(list(cols.values()), axis=1).astype(np.float32)
    scipy.io.wavfile.write(path, round(fs), data)


def _csv(path: str, cols: dict[str, np.ndarray], fs: float, t0: float, chunk: int = 1 << 16) -> None:
    names = list(cols)
    n = len(cols[names[0]])
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(["time", *names]) + "\n")
        for s in range(0, n, chunk):
            i = np.arange(s, min(n, s + chunk))
            block = np.column_stack([t0 + i / fs, *(cols[k][i] for k in names)])
            np.savetxt(fh, block, delimiter=",", fmt=["%.10f"] + ["%.10e"] * len(names))


def _uff(path: str, cols: dict[str, np.ndarray], fs: float, t0: float) -> None:
    import pyuff  # lazy: pyuff only for a UFF58 file

    sets = []
    for k, (name, a) in enumerate(cols.items()):
        x = t0 + np.arange(a.size) / fs
        sets.append({"type": 58, "binary": 1, "func_type": 1, "func_id": 0, "ver_num": 0, "load_case_id": 0,
                     "id1": name, "id2": "rotorcheck simulated time record", "id3": "NONE", "id4": "NONE",
                     "id5": "NONE", "rsp_ent_name": "NONE", "rsp_node": k + 1, "rsp_dir": 1, "ref_ent_name": "NONE",
                     "ref_node": 0, "ref_dir": 0, "abscissa_spacing": 1, "abscissa_spec_data_type": 17,
                     "abscissa_axis_units_lab": "s", "ordinate_spec_data_type": 0, "ordinate_axis_units_lab": "V",
                     "orddenom_spec_data_type": 0, "orddenom_axis_units_lab": "NONE", "z_axis_spec_data_type": 0,
                     "z_axis_value": 0.0, "x": x, "data": a})
    # the temp file is empty: "add" (pyuff's binary "overwrite" truncates the header it writes, as in sweep.uff)
    pyuff.UFF(path).write_sets(sets, mode="add")


def _hdf5(path: str, cols: dict[str, np.ndarray], fs: float, t0: float) -> None:
    with h5py.File(path, "w") as h5:
        h5.attrs["sample_rate_hz"] = fs
        h5.attrs["start_s"] = t0
        for name, a in cols.items():
            h5.create_dataset(name, data=a, chunks=(min(a.size, 1 << 16),) if a.size else None)


def _parquet(path: str, cols: dict[str, np.ndarray], fs: float, t0: float) -> None:
    import pyarrow as pa  # lazy: an optional dependency, only for a Parquet file
    import pyarrow.parquet as pq  # lazy: an optional dependency, only for a Parquet file

    table = pa.table(cols).replace_schema_metadata({"sample_rate_hz": repr(fs), "start_s": repr(t0)})
    pq.write_table(table, path)


_WRITERS = {"mat": _mat, "mat73": _mat73, "tdms": _tdms, "wav": _wav, "csv": _csv, "uff": _uff, "hdf5": _hdf5,
            "parquet": _parquet}


def simulate_rig_record(config: Any, frequency_hz: Sequence[float] | np.ndarray, speed_rpm: float = 0.0,
                        fault: str | None = None, seed: int = 0, spec: RecordSpec | None = None,
                        settings: StepSettings | None = None, shaft_angle_rad: float = 0.0,
                        n_harmonics: int = 8) -> SimulatedRecord:
    """A time recording of a rig config (usually a truth rig) with the plant, disturbances, noise and
    shaft angle of :func:`rotorcheck.sim.rig_sim.simulate_rig` (force at the actuator port, one probe
    at the sensor port)."""
    from rotorcheck.sim.rig_sim import at_shaft_angle, rig_plant, step_settings  # lazy: the FE model only for a rig

    f = np.asarray(frequency_hz, dtype=float)
    rp = at_shaft_angle(rig_plant(config, speed_rpm, fault, n_harmonics, float(f.max())), speed_rpm,
                        shaft_angle_rad)
    st = settings if settings is not None else step_settings(config, keep_periods=False)
    ports = config.io_ports("a simulated time record")
    act, sen = ports.actuator, ports.sensor
    sp = spec or RecordSpec(probe_names=(f"disp_s{sen.station}_{sen.direction}",))
    return simulate_record(rp.plant, f, st, rp.disturbances, seed, sp, speed_rpm, shaft_angle_rad,
                           (int(act.station), act.direction), [(int(sen.station), sen.direction)])
