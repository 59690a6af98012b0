"""Real-recording quirks: each handled (right phasors, a line in the run notes) or refused with an
InputError naming the file, the channel and the time, and nothing written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.stats

from rotorcheck.cli import main as cli_main
from rotorcheck.errors import InputError
from rotorcheck.ingest import analyse, ingest_files, open_record, parse_channel_map
from rotorcheck.ingest.record import TimeRecord
from rotorcheck.sim.simulator import Tone, lti_plant
from rotorcheck.sim.time_records import RecordSpec, SimulatedRecord, channel_map_dict, simulate_record, write_record
from tests.ingest.ingest_helpers import FREQS, cmap_of, frf, settings, small_record, truth


def _ok(run, freqs=FREQS, level=1e-4) -> None:
    """Phasors within noise of the truth (F(2, 2(N-1)) quantile, family-wise over the points)."""
    idx = [int(np.argmin(np.abs(freqs - f))) for f in run.frequency]
    z = np.abs(run.output_phasor - truth(freqs)[idx]) ** 2 / run.output_var
    assert np.all(z < scipy.stats.f.ppf(1 - level / z.size, 2, 2 * (int(run.n_periods.min()) - 1))), z


def _with(sim: SimulatedRecord, **chans: np.ndarray) -> TimeRecord:
    r = sim.record
    return TimeRecord("rec.h5", r.fs_hz, r.t0_s, {**r.channels, **chans})


def _refused(exc: pytest.ExceptionInfo, *parts: str) -> None:
    msg = str(exc.value)
    for p in parts:
        assert p in msg, msg


@pytest.fixture(scope="module")
def sim() -> SimulatedRecord:
    return small_record(seed=3)


@pytest.fixture(scope="module")
def turning() -> SimulatedRecord:
    plant = lti_plant(frf, 2)
    dist = [Tone(1000 / 60, np.array([1e-6, 5e-7]))]
    return simulate_record(plant, FREQS, settings(32), dist, 4, RecordSpec(fs_hz=5000.0, probe_names=("p6x", "p2x")),
                           1000.0, 0.4, (8, "x"), [(6, "x"), (2, "x")])


def _probe_clipped(sim: SimulatedRecord, t0: float, t1: float) -> tuple[np.ndarray, float]:
    """The probe with a burst in [t0, t1) driven into a rail just above its normal peak (flat-topped
    there), and that rail."""
    x = np.array(sim.record.channels["p6x"], dtype=float)
    t = sim.record.t0_s + np.arange(x.size) / sim.record.fs_hz
    ptp = float(x.max() - x.min())
    rail = float(x.max()) + 0.05 * ptp
    sel = (t >= t0) & (t < t1)
    x[sel] += ptp
    return np.minimum(x, rail), rail


@pytest.mark.parametrize("rails", [False, True])
def test_clipped_periods_dropped(sim: SimulatedRecord, rails: bool) -> None:
    f, a, _b = sim.steps[1]
    t_an = a + 8 / f  # after settling
    x, rail = _probe_clipped(sim, t_an + 3 / f, t_an + 7 / f)
    doc = channel_map_dict(sim, "crack_rig")
    if rails:
        doc["probes"][0]["rails"] = [-100.0, rail - 1e-9]
    run = analyse([_with(sim, p6x=x)], parse_channel_map(doc)).sweep.runs["0rpm"]
    assert run.n_periods[1] < sim.n_periods[1] and run.n_periods[0] == sim.n_periods[0]
    assert "dropped for clipping" in run.notes and "p6x" in run.notes
    _ok(run)


def test_clipping_refused(sim: SimulatedRecord, tmp_path: Path) -> None:
    _f, a, b = sim.steps[0]
    x, _ = _probe_clipped(sim, a, b)  # every period of the step
    rec = write_record(TimeRecord("x", sim.record.fs_hz, 0.0, {**sim.record.channels, "p6x": x}), tmp_path / "r.h5")
    with pytest.raises(InputError) as exc:
        ingest_files([rec], cmap_of(sim), tmp_path / "out.h5")
    _refused(exc, str(rec), "'p6x'", "t = ", "clipped")
    assert not (tmp_path / "out.h5").exists()


def _kp_edit(sim: SimulatedRecord, drop: list[int] = (), extra: list[int] = ()) -> np.ndarray:
    kp = np.array(sim.record.channels["keyphasor"], dtype=float)
    high = kp > 2.5
    starts = np.flatnonzero(~high[:-1] & high[1:]) + 1
    ends = np.flatnonzero(high[:-1] & ~high[1:]) + 1
    for k in drop:
        kp[starts[k] - 3 : ends[ends > starts[k]][0] + 3] = 0.0
    for k in extra:  # a second pulse half a revolution later
        mid = (starts[k] + starts[k + 1]) // 2
        kp[mid : mid + 20] = 5.0
    return kp


@pytest.mark.parametrize("what", ["missing", "double"])
def test_keyphasor_repaired(turning: SimulatedRecord, what: str) -> None:
    kp = _kp_edit(turning, drop=[5] if what == "missing" else [], extra=[9] if what == "double" else [])
    run = analyse([_with(turning, keyphasor=kp)], cmap_of(turning)).sweep.runs["1000rpm"]
    assert f"{what} keyphasor pulse" in run.notes
    assert abs(run.speed_rpm - 1000.0) < 1e-3
    _ok(run)


def test_keyphasor_not_isolated_refused(turning: SimulatedRecord) -> None:
    kp = _kp_edit(turning, drop=[5, 6, 7])
    with pytest.raises(InputError) as exc:
        analyse([_with(turning, keyphasor=kp)], cmap_of(turning))
    _refused(exc, "rec.h5", "'keyphasor'", "t = ")


def test_keyphasor_without_pulses_refused(turning: SimulatedRecord) -> None:
    n = turning.record.n_samples
    flat = 0.01 * np.random.default_rng(0).standard_normal(n)
    with pytest.raises(InputError) as exc:
        analyse([_with(turning, keyphasor=flat)], cmap_of(turning))
    _refused(exc, "rec.h5", "'keyphasor'", "t = ", "no keyphasor pulses")


def _cut(sim: SimulatedRecord, t_end: float) -> TimeRecord:
    n = int((t_end - sim.record.t0_s) * sim.record.fs_hz)
    return TimeRecord("rec.h5", sim.record.fs_hz, sim.record.t0_s,
                      {k: np.asarray(v)[:n] for k, v in sim.record.channels.items()})


def test_step_cut_short_dropped(sim: SimulatedRecord) -> None:
    f, a, _b = sim.steps[-1]
    run = analyse([_cut(sim, a + 12 / f)], cmap_of(sim)).sweep.runs["0rpm"]  # 4 periods after settling
    assert run.frequency.size == 2 and "warning: step at 123.4 Hz" in run.notes and "step dropped" in run.notes
    _ok(run)


def test_step_cut_short_refused(sim: SimulatedRecord) -> None:
    f, a, _b = sim.steps[-1]
    with pytest.raises(InputError) as exc:
        analyse([_cut(sim, a + 12 / f)], cmap_of(sim, short_step="refuse"))
    _refused(exc, "rec.h5", "t = ", "123.4 Hz", "min_periods")


def _split(sim: SimulatedRecord, tmp_path: Path, t_split: float, gap_s: float = 0.0) -> list[str]:
    r = sim.record
    n = int((t_split - r.t0_s) * r.fs_hz)
    k = round(gap_s * r.fs_hz)
    first = TimeRecord("a", r.fs_hz, r.t0_s, {c: np.asarray(v)[:n] for c, v in r.channels.items()})
    rest = {c: np.asarray(v)[n + k :] for c, v in r.channels.items()}
    second = TimeRecord("b", r.fs_hz, r.t0_s + (n + k) / r.fs_hz, rest)
    # written in reverse order: the reader orders them by time
    return [write_record(second, tmp_path / "part2.h5"), write_record(first, tmp_path / "part1.h5")]


def test_several_files_concatenated(sim: SimulatedRecord, tmp_path: Path) -> None:
    _f, a, b = sim.steps[1]
    files = _split(sim, tmp_path, 0.5 * (a + b))  # the cut inside a step
    run = ingest_files(files, cmap_of(sim), tmp_path / "out.h5").sweep.runs["0rpm"]
    whole = analyse([sim.record], cmap_of(sim)).sweep.runs["0rpm"]
    np.testing.assert_allclose(run.output_phasor, whole.output_phasor, rtol=1e-12)
    np.testing.assert_array_equal(run.n_periods, whole.n_periods)


@pytest.mark.parametrize("with_steps", [True, False])
def test_gap_inside_a_step_refused(sim: SimulatedRecord, tmp_path: Path, with_steps: bool) -> None:
    _f, a, b = sim.steps[1]
    files = _split(sim, tmp_path, 0.5 * (a + b), gap_s=0.05)
    with pytest.raises(InputError) as exc:
        ingest_files(files, cmap_of(sim, with_steps=with_steps), tmp_path / "out.h5")
    _refused(exc, "part", "t = ", "gap in time")
    assert not (tmp_path / "out.h5").exists()


def test_csv_time_gap_refused(sim: SimulatedRecord, tmp_path: Path) -> None:
    _f, a, b = sim.steps[0]
    rec = write_record(sim, tmp_path / "r.csv")
    lines = (tmp_path / "r.csv").read_text().splitlines(keepends=True)
    i0 = int(0.5 * (a + b) * sim.record.fs_hz)
    (tmp_path / "r.csv").write_text("".join(lines[: i0 + 1] + lines[i0 + 200 :]))  # 200 samples missing
    recs = open_record(rec)
    assert len(recs) == 2  # split at the gap
    with pytest.raises(InputError) as exc:
        ingest_files([rec], cmap_of(sim), tmp_path / "out.h5")
    _refused(exc, str(rec), "t = ", "gap in time")


def test_force_not_a_sine_refused(sim: SimulatedRecord, tmp_path: Path) -> None:
    x = np.asarray(sim.record.channels["force"]) / 10.0
    u = 10.0 * (x + 0.3 * (4 * x**3 - 3 * x))  # 30 % third harmonic (Chebyshev T3(cos) = cos 3)
    rec = write_record(TimeRecord("x", sim.record.fs_hz, 0.0, {**sim.record.channels, "force": u}), tmp_path / "r.h5")
    with pytest.raises(InputError) as exc:
        ingest_files([rec], cmap_of(sim), tmp_path / "out.h5")
    _refused(exc, str(rec), "'force'", "t = ", "not a sine")
    assert not (tmp_path / "out.h5").exists()


def test_mat_without_channel_refused(sim: SimulatedRecord, tmp_path: Path) -> None:
    cols = {k: np.asarray(v) for k, v in sim.record.channels.items() if k != "p2x"}
    scipy.io.savemat(tmp_path / "r.mat", {**cols, "sample_rate_hz": sim.record.fs_hz})
    with pytest.raises(InputError) as exc:
        ingest_files([tmp_path / "r.mat"], cmap_of(sim), tmp_path / "out.h5")
    _refused(exc, "r.mat", "'p2x'", "not in the record")


def test_truncated_tdms_exit_2(sim: SimulatedRecord, tmp_path: Path) -> None:
    rec = Path(write_record(sim, tmp_path / "r.tdms"))
    data = rec.read_bytes()
    rec.write_bytes(data[: len(data) // 2 + 7])
    cmap = tmp_path / "map.yaml"
    import yaml

    cmap.write_text(yaml.safe_dump(channel_map_dict(sim, "crack_rig", "tdms")))
    rc = cli_main(["ingest", str(rec), str(tmp_path / "out.h5"), "--map", str(cmap)])
    assert rc == 2 and not (tmp_path / "out.h5").exists()
    with pytest.raises(InputError) as exc:  # an input error naming the file, not an internal one
        ingest_files([rec], cmap, tmp_path / "out.h5")
    _refused(exc, str(rec), "truncated")


def test_channel_map_errors_name_file_and_field(tmp_path: Path, sim: SimulatedRecord) -> None:
    import yaml

    doc = channel_map_dict(sim, "crack_rig")
    doc["probes"][1]["sensitivity_v_per_m"] = -1.0
    p = tmp_path / "map.yaml"
    p.write_text(yaml.safe_dump(doc))
    rec = write_record(sim, tmp_path / "r.h5")
    with pytest.raises(InputError) as exc:
        ingest_files([rec], p, tmp_path / "out.h5")
    _refused(exc, str(p), "probes[1].sensitivity_v_per_m")
    del doc["probes"][1]["sensitivity_v_per_m"]
    p.write_text(yaml.safe_dump(doc))
    with pytest.raises(InputError) as exc:
        ingest_files([rec], p, tmp_path / "out.h5")
    _refused(exc, str(p), "sensitivity_v_per_m", "required")


def test_steps_found_in_the_force(sim: SimulatedRecord) -> None:
    run = analyse([sim.record], cmap_of(sim, with_steps=False)).sweep.runs["0rpm"]
    np.testing.assert_allclose(run.frequency, FREQS, rtol=1e-6)
    # the phase reference is the first zero crossing, so compare the FRF (reference-free)
    h = run.frf[:, :, 0]
    var_h = run.output_var / np.abs(run.input_phasor) ** 2
    z = np.abs(h - np.array([frf(f) for f in FREQS])) ** 2 / var_h
    assert np.all(z < scipy.stats.f.ppf(1 - 1e-4, 2, 2 * (int(run.n_periods.min()) - 1))), z
    assert np.all(run.n_periods >= sim.n_periods - 2)


def test_cli_refuses_overwrite(sim: SimulatedRecord, tmp_path: Path) -> None:
    import yaml

    rec = write_record(sim, tmp_path / "r.h5")
    cmap = tmp_path / "map.yaml"
    cmap.write_text(yaml.safe_dump(channel_map_dict(sim, "crack_rig")))
    out = tmp_path / "out.h5"
    assert cli_main(["ingest", rec, str(out), "--map", str(cmap)]) == 0
    stamp = out.stat().st_mtime_ns
    assert cli_main(["ingest", rec, str(out), "--map", str(cmap)]) == 2
    assert out.stat().st_mtime_ns == stamp
    assert cli_main(["ingest", rec, str(out), "--map", str(cmap), "--force"]) == 0


def test_offset_and_strong_drift_removed() -> None:
    # 3 V offset and 2 V/s drift on the probes (the signal is ~0.1-1 V): the phasors stay within noise
    sim = small_record(seed=9, probe_offset_v=3.0, probe_drift_v_per_s=2.0)
    _ok(analyse([sim.record], cmap_of(sim)).sweep.runs["0rpm"])


def test_rig_file_and_csv_without_time_column(sim: SimulatedRecord, tmp_path: Path) -> None:
    import yaml

    from rotorcheck.resources import configs_dir

    r = sim.record
    (tmp_path / "r.csv").write_text(",".join(r.channels) + "\n" + "\n".join(
        ",".join(f"{float(np.asarray(c)[i]):.10e}" for c in r.channels.values()) for i in range(r.n_samples)) + "\n")
    doc = channel_map_dict(sim, "unused")
    del doc["rig_id"]
    doc["rig"] = str(configs_dir() / "crack_rig.yaml")
    doc["sample_rate_hz"] = r.fs_hz
    (tmp_path / "map.yaml").write_text(yaml.safe_dump(doc))
    res = ingest_files([tmp_path / "r.csv"], tmp_path / "map.yaml", tmp_path / "out.h5")
    assert res.sweep.rig_id == "crack_rig"
    _ok(res.sweep.runs["0rpm"])
