"""Commands on a new sweep against the baseline: ``detect`` (steps 4-5) and ``locate``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape

from rotorcheck.cli.common import (
    DEFAULT_OUT,
    EXIT_DAMAGE,
    EXIT_OK,
    FailAtOpt,
    ForceOpt,
    FrfUnitOpt,
    JsonOpt,
    OutOpt,
    PlotFormatOpt,
    RigOpt,
    RunOpt,
    Steps,
    app,
    element_list,
    emit_json,
    err,
    fail_at_points,
    progress,
    record_run,
)
from rotorcheck.errors import InputError, finite_positive, in_open_unit
from rotorcheck.report.content import fmt_p
from rotorcheck.report.schema import DetectionReport, LocationReport


@app.command()
def detect(
    sweep: Annotated[Path, typer.Argument(help="New sweep to check against the healthy baseline.")],
    rig: RigOpt = None,
    out: OutOpt = DEFAULT_OUT,
    baseline: Annotated[Path | None, typer.Option("--baseline", help="Baseline (default <out>/baseline.h5).")] = None,
    run: RunOpt = None,
    at: Annotated[float | None, typer.Option("--at", help="Frequency (Hz) of the complex-plane plot.")] = None,
    plots: Annotated[bool, typer.Option(help="Write the detection plots.")] = True,
    confidence: Annotated[float, typer.Option(
        help="Family-wise confidence of measured detection (1 - false-alarm probability per sweep).")] = 0.99,
    rule: Annotated[str | None, typer.Option(
        "--rule", help="Verdict rule: joint (default with a measured baseline: one test over all points, benign "
                       "change inside the rig's variability ranges allowed) or certified (per-point fault points).")
    ] = None,
    false_alarm: Annotated[float, typer.Option(
        "--false-alarm", help="False-alarm probability per sweep of the joint test.")] = 0.01,
    resample: Annotated[bool, typer.Option(
        "--resample", help="Interpolate the new sweep onto the baseline's frequency grid when they differ.")] = False,
    locate: Annotated[bool, typer.Option(
        "--locate", help="When the verdict is damage, locate it too (the 'location' section; see `locate`).")] = False,
    plot_format: PlotFormatOpt = "png",
    frf_unit: FrfUnitOpt = "m/N",
    show_nominal: Annotated[bool, typer.Option(
        "--show-nominal", help="Also draw the nominal-E22 damage dynamics (carries the model's own error: not to "
                               "read) in damage_dynamics.png.")] = False,
    fail_at: FailAtOpt = "",
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """Steps 4-5: verdict (joint test or certified fault points) and the damage with its bound; a file of
    several runs: each run against the baseline's run at its speed, one verdict for the file."""
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs
    from rotorcheck.fileio import atomic_write_text, claim_outputs  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.report.reports import REPORT_FILES, render_json, write_reports  # lazy: keeps start-up light

    in_open_unit(confidence, "--confidence")
    in_open_unit(false_alarm, "--false-alarm")
    formats = workflow.plot_formats(plot_format)
    workflow.check_frf_unit(frf_unit)
    base_path = baseline if baseline is not None else out / "baseline.h5"
    cfg, rig_file, pairs = workflow.paired_runs(sweep, base_path, rig, run, resample, say=err.print)
    several = len(pairs) > 1
    dirs = [out / r.run_id for _, r in pairs] if several else [out]
    targets = (([out / "report.json"] if several else []) + [d / f for d in dirs for f in REPORT_FILES]
               + ([p for d in dirs for p in workflow.plot_paths(d, workflow.PLOT_STEMS_DETECT, formats)]
                  if plots else []))
    claim_outputs(targets, force, "detect", fresh=targets)  # one run at a time writes them
    settings = workflow.DetectorSettings(confidence, false_alarm, fail_at_points(fail_at))
    with Steps(f"detecting {sweep.name} against {base_path}", quiet=as_json) as tick:
        check = workflow.detect_pairs(cfg, rig_file, sweep, base_path, pairs, rule, settings, locate, say=err.print,
                                      progress=tick)
    summary: list[dict[str, Any]] = []
    written: list[Path] = []
    for d, (base, mrun), outcome in zip(dirs, pairs, check.outcomes):
        with progress("writing reports and plots"):
            report = outcome.typed_report()
            report.baseline = str(base_path)
            plot_files = (workflow.detection_plots(outcome, d, at, formats, base_path, frf_unit, show_nominal)
                          if plots else [])
            files = write_reports(report, d, plot_files, base_path)
        print_outcome(outcome, report, prefix=f"run {mrun.run_id} ({mrun.speed_rpm:g} rpm): " if several else "")
        written += [*files, *map(Path, plot_files)]
        if not several:
            record_run("detect", written, [out], force)
            for p_ in [*map(str, files), *plot_files]:
                err.print(f"wrote {p_}")
            if as_json:
                emit_json(report.to_dict())
            return outcome.exit_code
        summary.append({"run_id": mrun.run_id, "speed_rpm": mrun.speed_rpm, "baseline_run_id": base.run_id,
                        "verdict": report.verdict, "verdict_reason": report.verdict_reason,
                        "report": str(d / "report.json")})
    doc = {"sweep": str(sweep), "verdict": check.verdict, "verdict_rule": workflow.FILE_RULE, "runs": summary}
    atomic_write_text(out / "report.json", render_json(doc))
    record_run("detect", [*written, out / "report.json"], [out, *dirs], force)
    err.print(f"file verdict: {check.verdict.upper()} ({len(pairs)} runs); wrote {out / 'report.json'}")
    if as_json:
        emit_json(doc)
    return check.exit_code



def print_outcome(outcome: Any, report: DetectionReport, prefix: str = "") -> None:
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs

    v = outcome.verdict
    colour = {"damage": "bold red", "healthy": "bold green", "inconclusive": "bold yellow"}[v.verdict]
    err.print(f"{prefix}[{colour}]{v.verdict.upper()}[/]: {escape(report.conclusion or '')}")
    err.print(f"details: {v.reason}; {report.n_fault_points} of {report.n_points} points are fault points"
              + (f" (sweep p-value {fmt_p(report.p_value)}, {report.confidence:.0%} family-wise)"
                 if report.p_value is not None and report.confidence is not None else ""))
    if outcome.harmonics_warning:
        err.print(f"[yellow]warning[/]: {escape(outcome.harmonics_warning)}")
    damage = v.verdict == "damage"  # a healthy verdict shows no finding: no element, no damage estimate
    for line in (workflow.joint_summary(outcome), workflow.anchored_summary(outcome) if damage else ""):
        if line:
            err.print(line)
    if outcome.location is not None:
        err.print("location: " + outcome.location.summary())


@app.command()
def locate(
    sweep: Annotated[Path, typer.Argument(help="New sweep whose change to locate against the healthy baseline.")],
    rig: RigOpt = None,
    out: OutOpt = DEFAULT_OUT,
    baseline: Annotated[Path | None, typer.Option("--baseline", help="Baseline (default <out>/baseline.h5).")] = None,
    run: RunOpt = None,
    elements: Annotated[list[str] | None, typer.Option(
        "--elements", "--element", help="Candidate shaft elements, e.g. 3,4,5 or repeated (default: every element).")
    ] = None,
    section_length: Annotated[float | None, typer.Option(
        "--crack-section-length", help="Breathing crack section length for depths, m (default: the rig's crack's, "
                                       "else the element's diameter).")] = None,
    false_alarm: Annotated[float, typer.Option(
        "--false-alarm", help="Chance per sweep that the true element is excluded (Sidak over the points used).")
    ] = 0.01,
    resample: Annotated[bool, typer.Option(
        "--resample", help="Interpolate the new sweep onto the baseline's frequency grid when they differ.")] = False,
    plots: Annotated[bool, typer.Option(help="Write the location plot (the shaft, elements by status).")] = True,
    plot_format: PlotFormatOpt = "png",
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """Where and how big: every shaft element as a candidate for a local stiffness loss, each excluded with
    a certificate (the frequencies named) or given a certified interval of loss and crack depth; the
    consistent ones ranked. Writes <out>/location.json (and location.png); exit 1 when a damage is located,
    0 when the change needs none (no damage to locate), 2 on bad input."""
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs
    from rotorcheck.fileio import atomic_write_text, check_writable  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.report.reports import render_json  # lazy: keeps `rotorcheck --help` start-up light

    formats = workflow.plot_formats(plot_format)
    base_path = baseline if baseline is not None else out / "baseline.h5"
    els = element_list(elements)
    finite_positive(section_length, "--crack-section-length")
    in_open_unit(false_alarm, "--false-alarm")
    targets = [out / "location.json", out / "location.html"] + (workflow.plot_paths(out, ("location",), formats)
                                                                 if plots else [])
    check_writable(targets, force)
    cfg, _, pairs = workflow.paired_runs(sweep, base_path, rig, run, resample, say=err.print)
    if len(pairs) > 1:
        raise InputError(sweep, "/runs", f"{len(pairs)} runs ({', '.join(r.run_id for _, r in pairs)}); choose one "
                         "with --run")
    base, mrun = pairs[0]
    with Steps(f"locating the change of {sweep.name}", quiet=as_json) as tick:
        res = workflow.locate_damage(cfg, base, mrun, false_alarm, els, section_length, progress=tick)
    report = LocationReport(str(sweep), mrun.sha256, str(base_path), cfg.rig_id, mrun.speed_rpm, res)
    doc = report.to_json()
    atomic_write_text(out / "location.json", render_json(doc))
    written = [out / "location.json"]
    if plots:
        from rotorcheck.report.figures import save_figure  # lazy: matplotlib only when plotting
        from rotorcheck.report.plots import location_figure  # lazy: matplotlib only when plotting

        written += save_figure(location_figure(cfg, res, f"{sweep.name}: {res.summary()}"), out / "location", formats)
    from rotorcheck.report.html import render_location_html  # lazy: keeps `rotorcheck --help` start-up light

    atomic_write_text(out / "location.html", render_location_html(report, [str(p) for p in written[1:]], cfg.sha256()))
    written.append(out / "location.html")
    err.print(("[bold red]" if res.best is not None else "[bold green]") + res.summary() + "[/]")
    if res.single_channel is not None:
        err.print("one channel alone: " + res.single_channel.summary())
    for p_ in written:
        err.print(f"wrote {p_}")
    if as_json:
        emit_json(doc)
    return EXIT_DAMAGE if res.best is not None else EXIT_OK
