"""Commands on sweep files: ``info`` (validate and summarise), ``convert`` (between formats), ``ingest``
(time records in) and ``simulate`` (a sweep of a truth rig)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.markup import escape

from rotorcheck.cli.common import (
    DEFAULT_POINTS,
    EXIT_OK,
    ForceOpt,
    JsonOpt,
    app,
    at_least,
    check_speed,
    emit_json,
    err,
    progress,
    split_list,
    utc_now,
)
from rotorcheck.errors import InputError, check_rig_id, finite_positive, in_open_unit


def _warn_harmonics(run: dict[str, Any]) -> None:
    """The run's shaft-harmonic warning (summary's ``shaft_harmonics_warning``), if any."""
    if run["shaft_harmonics_warning"]:
        err.print(f"[yellow]warning[/]: run {run['run_id']}: {escape(run['shaft_harmonics_warning'])}")


@app.command()
def info(
    sweep: Annotated[Path, typer.Argument(help="Sweep file (HDF5, rotorcheck.sweep v1, v2 or v3).")],
    as_json: JsonOpt = False,
    confidence: Annotated[float, typer.Option(help="Family-wise confidence of the noise bound.")] = 0.99,
) -> int:
    """Validate a sweep file and summarise it: runs, speeds, grid, channels, noise estimate."""
    from rotorcheck.sweep.hdf5io import read_sweep, sweep_sha256  # lazy: h5py only when the command runs
    from rotorcheck.sweep.summary import summarize  # lazy: h5py only when the command runs

    in_open_unit(confidence, "--confidence")
    sw = read_sweep(sweep)
    doc = summarize(sw, confidence=confidence)
    doc["file"] = str(sweep)
    doc["sha256"] = sweep_sha256(sweep)
    err.print(f"{sweep}: valid rotorcheck.sweep v{doc['schema_version']}, rig_id {sw.rig_id!r}, source {sw.source}, "
              f"{sw.generator}")
    from rotorcheck.resources import configs_dir  # lazy: keeps `rotorcheck --help` start-up light

    doc["rig_bundled"] = (configs_dir() / f"{sw.rig_id}.yaml").exists()
    if not doc["rig_bundled"]:
        err.print(f"[yellow]rig_id {sw.rig_id!r} is not a bundled rig: fit-noise, validate, detect and locate "
                  "need --rig (or a baseline that names the rig file)[/]")
    chans = ", ".join(f"{c.name} ({c.role} s{c.node}.{c.direction} {c.unit})" for c in sw.channels)
    err.print(f"channels: {chans}")
    for run in doc["runs"]:
        g, nz, noise = run["grid"], run["noise"]["all_outputs"], run["noise"]
        if run["frf_only"]:
            sd = noise.get("frf_std_m_per_n")
            spread = f"frf std median {sd['median']:.3g} m/N" if sd else "no frf variance"
            err.print(f"run {run['run_id']}: {run['speed_rpm']:g} rpm, {g['n']} points {g['min_hz']:g}-{g['max_hz']:g} "
                      f"Hz, FRF only (no phasors); {spread}; noise: {run['noise_source']}")
            _warn_harmonics(run)
            continue
        patterns = f", {run['n_exc']} excitation patterns" if run["n_exc"] and run["n_exc"] > 1 else ""
        cleaned = ""
        if "pooled_bound_harmonics_removed_m" in noise:
            cleaned = (f"; with shaft harmonics 1X-{noise['shaft_orders_removed']}X removed: "
                       f"{noise['pooled_bound_harmonics_removed_m']:.3g} m "
                       f"pooled ({noise['excess_scatter_points_harmonics_removed']} points with excess scatter)")
        err.print(
            f"run {run['run_id']}: {run['speed_rpm']:g} rpm, {g['n']} points "
            f"{g['min_hz']:g}-{g['max_hz']:g} Hz, {run['n_periods_min']}-{run['n_periods_max']} periods{patterns}; "
            f"noise std median {nz['median_std_m']:.3g} m, "
            f"family-wise {confidence:.0%} bound {nz['sidak_bound_m']:.3g} m (max over points), "
            f"{noise['pooled_bound_m']:.3g} m pooled ({noise['excess_scatter_points']} points with excess scatter)"
            + cleaned
        )
        sb = run.get("sidebands")
        if sb:
            p_sb = sb["scan_p_value"]
            err.print(f"run {run['run_id']}: sidebands k = {', '.join(f'{k:+d}' for k in sb['orders'])}: "
                      f"{sb['n_tones']} separable tones ({sb['n_not_separable']} not); against a time-invariant "
                      f"rotor the scan's p = {p_sb:.3g} ({'beyond noise' if p_sb < 0.01 else 'noise'})")
        _warn_harmonics(run)
    if as_json:
        emit_json(doc)
    return EXIT_OK



@app.command()
def convert(
    source: Annotated[Path, typer.Argument(help="File to read: .h5/.hdf5, .uff/.unv (UFF58), .csv (tidy; wide with "
                                                "--wide).")],
    target: Annotated[Path, typer.Argument(help="File to write; format from its extension (or --to).")],
    from_format: Annotated[str | None, typer.Option("--from", help="SOURCE format: hdf5 | uff | csv | wide.")] = None,
    to_format: Annotated[str | None, typer.Option("--to", help="TARGET format: hdf5 | uff | csv | wide.")] = None,
    wide: Annotated[bool, typer.Option("--wide", help="The .csv side is a wide CSV (one row per frequency).")] = False,
    column_map: Annotated[Path | None, typer.Option(
        "--column-map", help="Column map (YAML/JSON) of a wide CSV read (default <stem>.columns.yaml beside it; "
                             "the side file of a tidy CSV), or where a written wide CSV's map goes.")] = None,
    ascii_58: Annotated[bool, typer.Option("--ascii", help="Write ASCII UFF 58 (default binary 58b, bit-exact; ASCII "
                                                           "keeps 6 digits of the frequency).")] = False,
    speed: Annotated[float | None, typer.Option("--speed", help="Speed, rpm, where the file states none.")] = None,
    noise_source: Annotated[str | None, typer.Option(
        "--noise-source", help="Where an FRF-only run's variance comes from: 'measured' or 'assumed: <rule>' ('X % "
                               "of |H|', 'X % of max |H|' are computed).")] = None,
    noise_var: Annotated[float | None, typer.Option(
        "--noise-var", help="Assumed variance of every FRF entry of an FRF-only run, (m/N)^2.")] = None,
    rig_id: Annotated[str | None, typer.Option("--rig-id", help="Rig id where the file states none.")] = None,
    run_id: Annotated[str | None, typer.Option(
        "--run-id", help="Name of the run of a file without run ids; else the one run to convert.")] = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> int:
    """Convert a sweep between HDF5, UFF58, tidy CSV and wide CSV (FRF-only data need a noise statement)."""
    from rotorcheck.sweep.convert import ConvertOptions  # lazy: h5py, pyuff only when the command runs

    if rig_id is not None:
        check_rig_id(rig_id, None, "--rig-id")
    from rotorcheck.sweep.convert import convert as convert_files  # lazy: h5py, pyuff only when the command runs

    opts = ConvertOptions(speed_rpm=speed, noise_source=noise_source, noise_var=noise_var, rig_id=rig_id,
                          run_id=run_id, column_map=column_map, ascii=ascii_58, force=force)
    doc = convert_files(source, target, from_format=from_format, to_format=to_format, wide=wide, options=opts)
    for r in doc["runs"]:
        what = f"FRF only, noise: {r['noise_source']}" if r["frf_only"] else "phasors"
        err.print(f"run {r['run_id']}: {r['speed_rpm']:g} rpm, {r['n_points']} points {r['f_min_hz']:g}-"
                  f"{r['f_max_hz']:g} Hz, {what}")
    err.print(f"{source} ({doc['format_in']}) -> {doc['format_out']}: wrote {', '.join(doc['files'])}")
    if as_json:
        emit_json(doc)
    return EXIT_OK



@app.command()
def ingest(
    files: Annotated[list[Path], typer.Argument(metavar="RECORD... OUT.h5", help=(
        "Time records of one sweep (.mat .tdms .wav .csv .parquet .uff .h5), then the sweep file to write."))],
    channel_map: Annotated[Path, typer.Option("--map", help="Channel map YAML (docs/ingest.md).")],
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> int:
    """Stepped-sine time records (force or current, probes, keyphasor) -> a sweep file (docs/ingest.md)."""
    from rotorcheck.ingest import ingest_files  # lazy: the readers (h5py, pydantic) only when the command runs

    if len(files) < 2:
        raise InputError(None, "RECORD... OUT.h5", "give at least one time record and the sweep file to write")
    *records, output = files
    res = ingest_files(records, channel_map, output, force=force)
    s = res.summary
    for note in res.notes:
        err.print(f"  {escape(note)}")
    err.print(f"wrote {output}: run {s['run_id']} at {s['speed_rpm']:.6g} rpm, {s['n_steps']} steps "
              f"{s['f_min_hz']:.6g}-{s['f_max_hz']:.6g} Hz, {s['n_periods_min']}-{s['n_periods_max']} periods")
    if as_json:
        emit_json({"file": str(output), **s})
    return EXIT_OK


def sideband_orders(text: str) -> tuple[int, ...]:
    """``--sidebands``: distinct nonzero integers, comma separated ("" for none)."""
    from rotorcheck.config.analysis import sideband_order_problem  # lazy: pydantic only when the command runs

    try:
        orders = tuple(int(k) for k in split_list([text]))
    except ValueError:
        raise InputError(None, "--sidebands", f"expected integers such as -2,-1,1,2, got {text!r}") from None
    why = sideband_order_problem(orders)
    if why:
        raise InputError(None, "--sidebands", f"orders must be distinct nonzero integers: {why}")
    return orders


@app.command()
def simulate(
    output: Annotated[Path, typer.Argument(help="Sweep file to write (HDF5).")],
    rig: Annotated[Path | None, typer.Option("--rig", help="Truth rig (default configs/crack_rig_truth.yaml).")] = None,
    speed: Annotated[float | None, typer.Option(
        "--speed", help="Spin speed, rpm (default: the rig's first analysis.speeds_rpm, said on stderr).")] = None,
    fault: Annotated[str | None, typer.Option("--fault", help="A fault named in the rig's faults section.")] = None,
    f_min: Annotated[float | None, typer.Option(
        "--f-min", help="First frequency, Hz (default: the rig's analysis.band_hz).")] = None,
    f_max: Annotated[float | None, typer.Option(
        "--f-max", help="Last frequency, Hz (default: the rig's analysis.band_hz).")] = None,
    points: Annotated[int | None, typer.Option(
        "--points", help="Number of frequency points, linear grid (default: the rig's analysis.n_points, else "
                         f"{DEFAULT_POINTS}).")] = None,
    periods: Annotated[int | None, typer.Option("--periods", help="Periods averaged per point.")] = None,
    noise: Annotated[float | None, typer.Option("--noise", help="Output noise std per sample, m.")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Random seed.")] = 0,
    harmonics: Annotated[int, typer.Option("--harmonics", help="Harmonic-balance order (breathing crack).")] = 8,
    shaft_angle: Annotated[str, typer.Option(
        "--shaft-angle", help="Shaft angle at the sweep start, degrees, or 'random' (free-running; drawn from "
                              "--seed).")] = "0",
    crack_depth: Annotated[float | None, typer.Option(
        "--crack-depth", help="Depth of the --fault crack as a fraction of the shaft diameter (e.g. 0.1).")] = None,
    keep_periods: Annotated[bool, typer.Option(help="Store the per-period phasors.")] = True,
    sidebands: Annotated[str | None, typer.Option(
        "--sidebands", help="Sideband orders k to measure at f + k x speed, e.g. -2,-1,1,2 (a rotating sweep; "
                            "format version 3). Default: the rig's measurement.sideband_orders.")] = None,
    actuator: Annotated[list[str] | None, typer.Option(
        "--actuator", "--actuators", help="A force input at a station and direction, e.g. 8x (several: repeat or "
                                         "8x,8y; driven one at a time). Default: the rig's actuator.")] = None,
    sensor: Annotated[list[str] | None, typer.Option(
        "--sensor", "--sensors", help="A displacement output, e.g. 6y (several: repeat or 6x,6y). Default: the rig's "
                                     "sensor.")] = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> int:
    """Simulate a stepped-sine sweep of a (truth) rig, healthy or with a named fault; several --actuator /
    --sensor give an x/y sweep (format version 2)."""
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs
    from rotorcheck.fileio import check_writable  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.resources import configs_dir  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.sim.rig_sim import (  # lazy: the simulator (FE model, h5py) only when the command runs
        shaft_angle_from,
        simulate_rig,
        step_settings,
    )
    from rotorcheck.sweep.hdf5io import write_sweep  # lazy: h5py only when the command runs

    check_speed(speed)
    finite_positive(f_min, "--f-min")
    finite_positive(f_max, "--f-max")
    finite_positive(noise, "--noise", allow_zero=True)
    at_least(points, 2, "--points")
    at_least(periods, 1, "--periods")
    at_least(seed, 0, "--seed")
    at_least(harmonics, 1, "--harmonics")
    check_writable([output], force)
    rig_path = rig if rig is not None else configs_dir() / "crack_rig_truth.yaml"
    if rig is None:
        err.print(f"no --rig: simulating the bundled truth rig {rig_path}")
    cfg = workflow.load_rig(rig_path)
    if speed is None:
        speed = float(cfg.analysis.speeds_rpm[0])
        err.print(f"no --speed: simulating at {speed:g} rpm (the rig's first analysis speed)")
    if (f_min is None or f_max is None) and "band_hz" not in cfg.analysis.model_fields_set:
        err.print(f"{rig_path}: no analysis.band_hz; simulating {cfg.analysis.band_hz[0]:g}-"
                  f"{cfg.analysis.band_hz[1]:g} Hz (default)")
    f_min = cfg.analysis.band_hz[0] if f_min is None else f_min
    f_max = cfg.analysis.band_hz[1] if f_max is None else f_max
    if points is None:
        points = cfg.analysis.n_points or DEFAULT_POINTS
        if cfg.analysis.n_points is None:
            err.print(f"{rig_path}: no analysis.n_points; simulating {points} points (default)")
    if points < 2 or not (0 < f_min < f_max):
        raise InputError(None, "--points/--f-min/--f-max", "need 0 < f-min < f-max and at least 2 points")
    if cfg.measurement.output_noise_std == 0.0 and (noise is None or noise == 0.0):
        err.print(f"[yellow]warning[/]: {rig_path} sets no measurement noise (measurement.output_noise_std): the "
                  "simulated sweep is noise-free")
    angle = shaft_angle_from(shaft_angle, seed)
    if crack_depth is not None:
        if fault is None:
            raise InputError(None, "--crack-depth", "needs --fault naming a crack of the rig")
        cfg = workflow.rig_with_crack_depth(cfg, rig_path, fault, crack_depth)
    st = step_settings(cfg, keep_periods=keep_periods)
    if periods is not None:
        st = dataclasses.replace(st, n_periods=periods)
    if noise is not None:
        st = dataclasses.replace(st, output_noise_std=noise)
    if sidebands is not None:
        st = dataclasses.replace(st, sideband_orders=sideband_orders(sidebands))
    if st.sideband_orders and speed == 0.0:
        raise InputError(None, "--sidebands", "a sweep at standstill has no sidebands (give --speed)")
    grid = np.linspace(f_min, f_max, points)
    with progress(f"simulating {points} points at {speed:g} rpm" + (f" with {fault}" if fault else "")):
        if actuator or sensor:
            from rotorcheck.nominal import parse_port  # lazy: pydantic (the rig schema) only when the command runs
            from rotorcheck.sim.rig_sim import simulate_rig_patterns  # lazy: the simulator only when the command runs

            acts = ([parse_port(a, "--actuator") for a in split_list(actuator)] if actuator
                    else [cfg.io_ports("simulate").actuator])
            sens = ([parse_port(x, "--sensor") for x in split_list(sensor)] if sensor
                    else [cfg.io_ports("simulate").sensor])
            sw = simulate_rig_patterns(cfg, grid, acts, sens, speed_rpm=speed, fault=fault, seed=seed,
                                       n_harmonics=harmonics, settings=st, created_utc=utc_now(),
                                       shaft_angle_rad=angle)
        else:
            sw = simulate_rig(cfg, grid, speed, fault=fault, seed=seed, n_harmonics=harmonics, settings=st,
                              created_utc=utc_now(), shaft_angle_rad=angle)
    write_sweep(sw, output, force=force)
    err.print(f"wrote {output}: {sw.generator}; {points} points {f_min:g}-{f_max:g} Hz at {speed:g} rpm")
    if as_json:
        emit_json({"file": str(output), "rig_id": sw.rig_id, "generator": sw.generator, "speed_rpm": speed,
                    "fault": fault, "points": points, "seed": seed, "shaft_angle_deg": float(np.degrees(angle)),
                    "crack_depth": crack_depth})
    return EXIT_OK
