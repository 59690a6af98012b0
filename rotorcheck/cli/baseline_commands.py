"""Commands that build the healthy baseline: ``fit-noise`` (step 2) and ``validate`` (step 3)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape

from rotorcheck.cli.common import (
    DEFAULT_OUT,
    EXIT_INCONCLUSIVE,
    EXIT_OK,
    DemoOpt,
    FailAtOpt,
    ForceOpt,
    FrfUnitOpt,
    JsonOpt,
    OutOpt,
    PlotFormatOpt,
    RigOpt,
    RunOpt,
    app,
    bundled_or_given,
    emit_json,
    err,
    fail_at_points,
    progress,
    record_run,
)
from rotorcheck.errors import in_open_unit


@app.command("fit-noise")
def fit_noise(
    sweep: Annotated[Path | None, typer.Argument(help="Healthy sweep (--demo: the bundled healthy_1000rpm).")] = None,
    demo: DemoOpt = False,
    rig: RigOpt = None,
    out: OutOpt = DEFAULT_OUT,
    method: Annotated[str, typer.Option(help="pooled | per-point | max | floor | manual")] = "pooled",
    value: Annotated[float | None, typer.Option("--value", help="Manual bound, m (--method manual).")] = None,
    confidence: Annotated[float, typer.Option(help="Family-wise confidence over the points.")] = 0.99,
    run: RunOpt = None,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """Step 2: fit the noise bound V (m) and write it into <out>/baseline.h5."""
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs
    from rotorcheck.baseline import write_baseline  # lazy: h5py only when the command runs
    from rotorcheck.fileio import check_writable  # lazy: keeps `rotorcheck --help` start-up light
    from rotorcheck.resources import samples_dir  # lazy: keeps `rotorcheck --help` start-up light

    sweep_path = bundled_or_given(sweep, demo, samples_dir() / "crack_rig" / "healthy_1000rpm.h5", "healthy sweep",
                                  "SWEEP")
    in_open_unit(confidence, "--confidence")
    target = out / "baseline.h5"
    check_writable([target], force)
    cfg, rig_path, (mrun,) = workflow.load_rig_and_runs(sweep_path, rig, target, run)
    nb = workflow.fit_noise(mrun, method=method, confidence=confidence, manual_m=value)
    base = workflow.noise_baseline(cfg, mrun, nb)
    base.provenance.rig_path = str(Path(rig_path).resolve())  # later commands need no --rig
    write_baseline(base, target)
    conf = f", {nb.confidence:.0%} family-wise over {mrun.frequency_hz.size} points" if nb.confidence else ""
    err.print(f"noise bound V = {nb.value_m * 1e6:.4g} um ({nb.method}{conf}) from {sweep_path}")
    excess = nb.details.get("excess_scatter_hz", [])
    if excess:
        err.print(f"{len(excess)} points scatter beyond the pooled noise (synchronous leaks?): "
                  + ", ".join(f"{x:.1f}" for x in excess[:12]) + (" ..." if len(excess) > 12 else "") + " Hz")
    err.print(f"wrote {target}")
    if as_json:
        emit_json(workflow.noise_report(nb, sweep_path, target).to_dict())
    return EXIT_OK


@app.command()
def validate(
    sweeps: Annotated[list[Path], typer.Argument(help="One or several healthy sweeps (gamma encloses them all).")],
    rig: RigOpt = None,
    out: OutOpt = DEFAULT_OUT,
    enclose: Annotated[str, typer.Option(
        help="measured (default: detect against the measured healthy FRF within both sweeps' noise) | "
             "system (against the nominal model, set enclosing every system consistent with the data) | "
             "data (the dissertation's FDMVOP)")] = "measured",
    run: RunOpt = None,
    at: Annotated[float | None, typer.Option("--at", help="Frequency (Hz) of the complex-plane plot.")] = None,
    plots: Annotated[bool, typer.Option(help="Write the validation plots.")] = True,
    learn_drift: Annotated[bool | None, typer.Option(
        "--learn-drift/--no-learn-drift", help="Learn from the healthy sweeps (>= 3, drifted across the ranges) where "
        "the machine drifts: the ranges move over the centres that allow every sweep's fitted state; kappa from "
        "the sweeps left out. Default: learned when 3 or more sweeps differ beyond their "
        "noise.", show_default=False)] = None,
    update: Annotated[bool, typer.Option(
        "--update", help="Fit the rig's variability parameters to the healthy FRF (model updating) and predict "
                         "benign change around the updated model.")] = False,
    plot_format: PlotFormatOpt = "png",
    frf_unit: FrfUnitOpt = "m/N",
    fail_at: FailAtOpt = "",
    reuse_noise: Annotated[bool, typer.Option(
        "--reuse-noise", help="Validate with a noise bound fitted on another sweep (recorded in the baseline).")
    ] = False,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """Step 3: bound the model error per frequency (gamma) so the uncertain model encloses the healthy data
    (a file of several runs, one per speed: every run, one validated set each)."""
    from rotorcheck import workflow  # lazy: the pipeline (scipy, pydantic, h5py) only when the command runs
    from rotorcheck.baseline import write_baseline  # lazy: h5py only when the command runs
    from rotorcheck.fileio import check_output_place, claim_outputs  # lazy: keeps `rotorcheck --help` start-up light

    formats = workflow.plot_formats(plot_format)
    workflow.check_frf_unit(frf_unit)
    target = out / "baseline.h5"
    check_output_place(target)
    cfg, rig_path, firsts = workflow.load_rig_and_runs(sweeps[0], rig, target, run, every_run=True)
    others = [workflow.read_runs(p, cfg, [r.run_id for r in firsts]) for p in sweeps[1:]]
    run_ids = [r.run_id for r in firsts]
    several = len(run_ids) > 1  # a file of several runs (speeds): one validated set per run
    plot_dirs = [out / rid if several else out for rid in run_ids]
    plot_targets = [p for d in plot_dirs for p in workflow.plot_paths(d, workflow.PLOT_STEMS_VALIDATE, formats)
                    ] if plots else []
    # one run at a time writes them: claimed before the prior baseline is read
    claim_outputs([target, *plot_targets], force, "validate", fresh=plot_targets)
    noise = workflow.prior_noise(target, cfg, force, firsts[0].sha256, reuse_noise)
    prior_run = noise.details["run_id"] if noise is not None else None
    reused_from = noise.details.get("fitted_on_sweep", "") if noise is not None else ""
    if noise is not None:
        err.print(f"noise bound V = {noise.value_m * 1e6:.4g} um from {target} ({noise.method}, run {prior_run})")
        if reused_from:
            err.print(f"[yellow]the noise bound was fitted on another sweep (sha256 {reused_from[:12]}); used as "
                      "asked (--reuse-noise), recorded in the baseline[/]")
    written: list[Path] = []
    outcomes, n_bad, docs = [], 0, []
    for k, (first, plot_dir) in enumerate(zip(firsts, plot_dirs)):
        runs = [first] + [o[k] for o in others]
        nb = noise if noise is not None and (not several or prior_run == first.run_id) else None
        if nb is None:
            nb = workflow.fit_noise(runs[0])
            err.print(f"run {first.run_id}: fitted V = {nb.value_m * 1e6:.4g} um ({nb.method}, "
                      f"{nb.confidence:.0%}) from {runs[0].path}")
        with progress(f"validating run {first.run_id} ({len(runs)} healthy sweeps, {first.frequency_hz.size} points)"):
            outcome = workflow.validate(cfg, runs, nb, enclose=enclose, fail_at=fail_at_points(fail_at), update=update,
                                        learn_drift=learn_drift)
        outcome.baseline.provenance.rig_path = str(Path(rig_path).resolve())  # later commands need no --rig
        if reused_from and nb is noise:
            outcome.baseline.provenance.noise_fitted_on_sweep = reused_from
        outcomes.append(outcome)
        for line in (outcome.healthy_note, workflow.update_summary(outcome), workflow.learning_summary(outcome)):
            if line:
                err.print(line)
        if workflow.sideband_warning(outcome):
            err.print(f"[yellow]warning[/]: {escape(workflow.sideband_warning(outcome))}")
        with progress("writing plots"):
            files = (workflow.validation_plots(outcome, plot_dir, at, formats, out / "baseline.h5", frf_unit)
                     if plots else [])
        res = outcome.result
        n_bad += outcome.n_not_enclosed
        g = res.gamma[outcome.bounded]
        unit = "m/N" if outcome.model.structure == "additive" else (
            "(relative)" if outcome.model.structure == "multiplicative" else f"({outcome.model.parameter})")
        err.print(f"{f'run {first.run_id} ({first.speed_rpm:g} rpm): ' if several else ''}gamma over {g.size} "
                  f"points ({enclose}): median {np.median(g):.3g}, max {np.max(g):.3g} {unit}"
                  if g.size else f"gamma: no point enclosed ({enclose})")
        if outcome.harmonics_warning:
            err.print(f"[yellow]warning[/]: {escape(outcome.harmonics_warning)}")
        if outcome.n_not_enclosed:
            bad = np.flatnonzero(outcome.not_enclosed)
            err.print(f"[yellow]{outcome.n_not_enclosed} points not enclosed[/]: " + ", ".join(
                f"{runs[0].frequency_hz[i]:.1f} Hz ({res.status[i]})" for i in bad[:10]))
        for p_ in files:
            err.print(f"wrote {p_}")
        written += map(Path, files)
        docs.append(outcome.typed_report(nb, target).to_dict())
        if outcome.baseline.provenance.noise_fitted_on_sweep:  # a bound from another sweep, as asked
            docs[-1]["noise_fitted_on_sweep"] = outcome.baseline.provenance.noise_fitted_on_sweep
    write_baseline(outcomes[0].baseline, target, [o.baseline for o in outcomes[1:]])
    record_run("validate", [target, *written], [out, *plot_dirs], force)
    err.print(f"wrote {target}" + (f" ({len(outcomes)} runs: {', '.join(run_ids)})" if several else ""))
    if as_json:
        emit_json(docs[0] if not several else {"runs": docs})
    return EXIT_INCONCLUSIVE if n_bad else EXIT_OK
