"""Commands on a rig file alone: ``model`` (modes, Campbell), ``crack`` (the cracked rotor), ``schema``,
``detectability`` (what the rig can detect, per element) and ``import-ross``."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from rotorcheck.cli.common import (
    DEFAULT_OUT,
    EXIT_OK,
    DemoOpt,
    ForceOpt,
    JsonOpt,
    OutOpt,
    PlotFormatOpt,
    Steps,
    app,
    at_least,
    bundled_or_given,
    check_speed,
    element_list,
    emit_json,
    err,
    progress,
    split_list,
)
from rotorcheck.errors import InputError, check_rig_id, finite_positive, in_open_unit


@app.command()
def model(
    rig: Annotated[Path | None, typer.Argument(help="Rig YAML (--demo: the bundled configs/crack_rig.yaml).")] = None,
    speed: Annotated[float | None, typer.Option(
        "--speed", help="Spin speed, rpm (default: every speed of the rig's analysis.speeds_rpm).")] = None,
    demo: DemoOpt = False,
    out: OutOpt = DEFAULT_OUT,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
    plots: Annotated[bool, typer.Option(help="Write Campbell, mode-shape and rotor plots.")] = True,
    plot_format: PlotFormatOpt = "png",
    speed_unit: Annotated[str, typer.Option("--speed-unit", help="Speed axis of the Campbell diagram: rpm | Hz.")
                          ] = "rpm",
) -> int:
    """Natural frequencies, damping, whirl and critical speeds; Campbell, mode-shape and rotor plots."""
    from rotorcheck.resources import default_rig_path  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.workflow import model_report  # lazy: the pipeline only when the command runs

    check_speed(speed)
    rig_path = bundled_or_given(rig, demo, default_rig_path("crack_rig"), "rig", "RIG")
    from rotorcheck.workflow import plot_formats  # lazy: the pipeline only when the command runs

    with progress(f"solving the model of {rig_path}" + (" and plotting" if plots else "")):
        result = model_report(rig_path, speed_rpm=speed, out_dir=out if plots else None, force=force,
                              formats=plot_formats(plot_format), speed_unit=speed_unit)
    summary = result["summary"]
    for at in summary.get("at_speeds", [summary]):
        table = Table(title=f"{summary['rig_id']} at {at['speed_rpm']:g} rpm", title_justify="left")
        for col in ("mode", "f (Hz)", "zeta", "whirl"):
            table.add_column(col, justify="right")
        for i, m in enumerate(at["modes"], 1):
            table.add_row(str(i), f"{m['frequency_hz']:.2f}", f"{m['damping_ratio']:.4f}", m["whirl"])
        err.print(table)
    for w in dict.fromkeys(w for at in [summary] for w in at.get("warnings", [])):
        err.print(f"[yellow]warning:[/yellow] {w}")
    crit = ", ".join(f"{c:.0f}" for c in summary["critical_speeds_rpm"]) or "none"
    err.print(f"critical speeds (rpm, up to {summary.get('campbell_max_rpm', 0):.0f}): {crit}")
    for p in result["files"]:
        err.print(f"wrote {p}")
    if as_json:
        emit_json(summary)
    return EXIT_OK



@app.command()
def crack(
    rig: Annotated[Path | None, typer.Argument(help="Rig YAML (--demo: the bundled truth rig).")] = None,
    demo: DemoOpt = False,
    fault: Annotated[str, typer.Option("--fault", help="Breathing crack in the rig.")] = "breathing_crack",
    unbalance: Annotated[float, typer.Option("--unbalance", help="Unbalance at the first disc, g m.")] = 0.2,
    out: OutOpt = DEFAULT_OUT,
    plot_format: PlotFormatOpt = "png",
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """The cracked rotor: stiffness over a revolution, orbits, spectra at 1000 and 750 rpm (Fig. 56-58)."""
    from rotorcheck.resources import configs_dir  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.workflow import crack_report, plot_formats  # lazy: the pipeline only when the command runs

    finite_positive(unbalance, "--unbalance", allow_zero=True)
    rig_path = bundled_or_given(rig, demo, configs_dir() / "crack_rig_truth.yaml", "truth rig", "RIG")
    with progress(f"the cracked rotor ({fault}): harmonic balance, orbits, spectra"):
        doc = crack_report(rig_path, fault=fault, unbalance_g_m=unbalance, out_dir=out, force=force,
                           formats=plot_formats(plot_format))
    for key, h in doc["harmonics"].items():
        amps = ", ".join(f"{n}X {x * 1e6:.3g}" for n, x in zip(h["order"][1:5], h["x_m"][1:5]))
        err.print(f"{key:16s} x at station {doc['station']} (um): {amps}")
    for p_ in doc["files"]:
        err.print(f"wrote {p_}")
    if as_json:
        emit_json(doc)
    return EXIT_OK


@app.command()
def schema(
    out: Annotated[Path | None, typer.Option("--out", help="Write to this file instead of stdout.")] = None,
    force: ForceOpt = False,
) -> int:
    """JSON Schema of the rig YAML, for editors."""
    from rotorcheck.config import json_schema  # lazy: pydantic (the rig schema) only when the command runs
    from rotorcheck.fileio import atomic_write_text, check_writable  # lazy: keeps `rotorcheck --help` start-up light

    text = json.dumps(json_schema(), indent=2) + "\n"
    if out is None:
        sys.stdout.write(text)
    else:
        check_writable([out], force)
        atomic_write_text(out, text)
        err.print(f"wrote {out}")
    return EXIT_OK


@app.command()
def detectability(
    rig: Annotated[Path | None, typer.Argument(
        help="Rig YAML (default: the rig --baseline was made with; --demo: the bundled configs/crack_rig.yaml).")
    ] = None,
    demo: DemoOpt = False,
    baseline: Annotated[Path | None, typer.Option(
        "--baseline", help="Noise, grid and speed from this baseline (its healthy variance per point).")] = None,
    noise_std: Annotated[float | None, typer.Option(
        "--noise-std", help="Stated output noise per sample, m (default: the rig's measurement section).")] = None,
    periods: Annotated[int | None, typer.Option(
        "--periods", help="Periods averaged per frequency point (default: the rig's measurement).")] = None,
    speed: Annotated[float | None, typer.Option(
        "--speed", help="Spin speed, rpm (default: the baseline's, else the rig's first analysis speed).")] = None,
    sensors: Annotated[list[str] | None, typer.Option(
        "--sensor", "--sensors", help="Sensor ports, e.g. 6x,6y,2x or repeated (default: the rig's sensor).")] = None,
    actuators: Annotated[list[str] | None, typer.Option(
        "--actuator", "--actuators", help="Actuator ports, e.g. 8x,8y or repeated (default: the rig's actuator).")
    ] = None,
    elements: Annotated[list[str] | None, typer.Option(
        "--elements", "--element", help="Shaft elements, e.g. 3,4,6 or repeated (default: all).")] = None,
    false_alarm: Annotated[float, typer.Option("--false-alarm", help="False-alarm rate per sweep.")] = 0.01,
    candidate_sensors: Annotated[list[str] | None, typer.Option(
        "--candidate-sensors", "--candidate-sensor",
        help="Rank sensor sets from these ports, e.g. 2x,2y,4x,6x,6y or repeated (stated noise).")] = None,
    max_sensors: Annotated[int, typer.Option(
        "--max-sensors", help="Largest sensor set ranked (exact up to 64 sets, greedy beyond).")] = 2,
    out: OutOpt = DEFAULT_OUT,
    plots: Annotated[bool, typer.Option(help="Write the detectability plot along the shaft.")] = True,
    plot_format: PlotFormatOpt = "png",
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """Before the crack: per shaft element, the smallest open-crack stiffness loss and breathing-crack depth
    the default detector finds with 90 % power (noise only, and with the rig's benign ranges), beside the
    likelihood-ratio limit. Writes <out>/detectability.json (and detectability.png)."""
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs
    from rotorcheck.baseline import read_baseline, stored_rig  # lazy: h5py only when the command runs
    from rotorcheck.fileio import atomic_write_text, check_writable  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.report.reports import render_json  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.resources import default_rig_path  # lazy: keeps `rotorcheck --help` start-up light

    finite_positive(noise_std, "--noise-std")
    check_speed(speed)
    at_least(periods, 1, "--periods")
    at_least(max_sensors, 1, "--max-sensors")
    in_open_unit(false_alarm, "--false-alarm")
    stored = stored_rig(baseline)[1] if baseline is not None and rig is None and not demo else None
    rig_path = Path(stored) if stored else bundled_or_given(rig, demo, default_rig_path("crack_rig"), "rig", "RIG")
    if stored:
        err.print(f"rig {rig_path} (the one {baseline} was made with)")
    cfg = workflow.load_rig(rig_path)
    els = workflow.check_elements(cfg, element_list(elements))
    formats = workflow.plot_formats(plot_format)
    targets = [out / "detectability.json"] + (workflow.plot_paths(out, ("detectability",), formats) if plots else [])
    check_writable(targets, force)
    base = read_baseline(baseline) if baseline is not None else None
    if base is not None and base.rig_id != cfg.rig_id:
        raise InputError(baseline, "/@rig_id", f"baseline for rig {base.rig_id!r}, not {cfg.rig_id!r}")
    with Steps(f"predicting what {cfg.rig_id} can detect, element by element", quiet=as_json) as tick:
        det = workflow.detectability_for_rig(cfg, speed, base, noise_std, periods, split_list(sensors),
                                             split_list(actuators), false_alarm, els, source=str(baseline or rig_path),
                                             progress=tick)
    doc = {"rig": str(rig_path), **det.to_dict()}
    if candidate_sensors:
        if base is not None:
            raise InputError(None, "--candidate-sensors", "ranking sensors needs stated noise (--noise-std), "
                             "not a baseline's channels")
        with progress(f"ranking sensor sets of up to {max_sensors} from {', '.join(split_list(candidate_sensors))}"):
            doc["sensor_sets"] = workflow.sensor_ranking_for_rig(
                cfg, split_list(candidate_sensors), max_sensors, speed, noise_std, periods, split_list(sensors),
                split_list(actuators), false_alarm, source=str(rig_path))
        ss = doc["sensor_sets"]
        for k, s_ in enumerate(ss["best"], 1):
            d_ = s_["worst_breathing_depth_min"]
            err.print(f"sensor set #{k}: {', '.join(s_['sensors'])}: worst element {s_['worst_element']}, "
                      + ("none up to 50 %" if d_ is None else f"breathing depth {100 * d_:.3g} %"))
        cur = ss["current"]
        if cur is not None:
            d_ = cur["worst_breathing_depth_min"]
            gain = ss["gain_worst_loss"]
            err.print(f"current set {', '.join(cur['sensors'])}: worst element {cur['worst_element']}, "
                      + ("no depth up to 50 %" if d_ is None else f"breathing depth {100 * d_:.3g} %")
                      + ("" if gain is None else f"; the best set's worst open-crack loss is {gain:.3g}x smaller")
                      + f" ({ss['method']})")
    atomic_write_text(out / "detectability.json", render_json(doc))
    written = [out / "detectability.json"]
    if plots:
        from rotorcheck.report.figures import save_figure  # lazy: matplotlib only when plotting
        from rotorcheck.report.plots import detectability_figure  # lazy: matplotlib only when plotting

        written += save_figure(detectability_figure(cfg, det), out / "detectability", formats)
    err.print(det.summary())
    for p_ in written:
        err.print(f"wrote {p_}")
    if as_json:
        emit_json(doc)
    return EXIT_OK


@app.command("import-ross")
def import_ross_cmd(
    rotor: Annotated[Path, typer.Argument(help="A rotor saved by ROSS (Rotor.save), TOML.")],
    out: Annotated[Path, typer.Argument(help="The rig file to write (YAML).")],
    rig_id: Annotated[str | None, typer.Option("--rig-id", help="rig_id of the new rig (default: the file name).")]
    = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> int:
    """A ROSS rotor as a rotorcheck rig file, with what could not be carried over (stderr and the file's header)."""
    from rotorcheck.fileio import atomic_write_text, check_writable  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.ross_import import import_ross  # lazy: pydantic (the rig schema) only when the command runs

    if rig_id is not None:
        check_rig_id(rig_id, None, "--rig-id")
    check_writable([out], force)
    result = import_ross(rotor, rig_id=rig_id)
    atomic_write_text(out, result.to_yaml())
    err.print(f"wrote {out}: rig_id {result.rig['rig_id']!r}, {len(result.rig['stations'])} stations, "
              f"{len(result.rig['shaft'])} shaft elements (layers included), {len(result.rig.get('bearings', []))} "
              "bearings/seals; no ports (modal analysis; add ports for sweeps)")
    for note in result.not_carried:
        err.print(f"not carried: {note}")
    if as_json:
        emit_json({"rig": str(out), "rig_id": result.rig["rig_id"], "not_carried": list(result.not_carried)})
    return EXIT_OK
