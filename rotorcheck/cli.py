"""Command line: a thin layer over the library (see ``../shared/spec/cli.md``).

Human summaries go to stderr; ``--json`` prints one JSON document on stdout and nothing else there.
Exit codes: 0 ok / no damage, 1 damage detected (detect only), 2 unusable input or failure,
3 inconclusive. An unexpected exception is 2, never 1.
"""

from __future__ import annotations

import copy
import json
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from rotorcheck.errors import InputError, UserInputError, finite_positive, in_open_unit
from rotorcheck.report.schema import DetectionReport

EXIT_OK, EXIT_DAMAGE, EXIT_INPUT, EXIT_INCONCLUSIVE = 0, 1, 2, 3
#: frequency points of a simulated sweep when neither --points nor the rig's analysis.n_points sets them
DEFAULT_POINTS = 262
#: the largest spin speed an option accepts, rpm (1e308 rpm overflows every frequency computed from it)
MAX_SPEED_RPM = 1e6


def _speed(value: float | None, option: str = "--speed") -> float | None:
    """A spin speed option: None or a finite number of rpm in [0, MAX_SPEED_RPM], else an InputError naming it."""
    return finite_positive(value, option, allow_zero=True, maximum=MAX_SPEED_RPM)


def _at_least(value: int | None, minimum: int, option: str) -> int | None:
    """An integer option: None or >= ``minimum``, else an InputError naming it."""
    if value is not None and value < minimum:
        raise InputError(None, option, f"must be >= {minimum}, got {value}")
    return value

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Has this shaft changed, where in the spectrum, and what exactly changed?",
    context_settings={"help_option_names": ["-h", "--help"]},  # inherited by every command
)
err = Console(stderr=True, highlight=False, soft_wrap=True)  # never break paths in messages


def _progress(text: str) -> Any:
    """A spinner with ``text`` on stderr while a step runs (rich); nothing when stderr is not a terminal."""
    import contextlib

    return err.status(text, spinner="dots") if err.is_terminal else contextlib.nullcontext()

RigOpt = Annotated[
    Path | None,
    typer.Option("--rig", help="Rig YAML (default: the bundled rig named by the sweep's rig_id)."),
]
OutOpt = Annotated[Path, typer.Option("--out", help="Output folder (created).")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON document on stdout.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Overwrite existing outputs.")]
DEFAULT_OUT = Path("rotorcheck-out")
PlotFormatOpt = Annotated[str, typer.Option("--plot-format", help="png (default) | pdf | both.")]
FrfUnitOpt = Annotated[str, typer.Option("--frf-unit", help="Receptance unit of the plots: m/N (default) | mm/N | "
                                                             "um/N.")]


def _emit_json(doc: dict[str, Any]) -> None:
    """One strict JSON document on stdout (non-finite numbers as the strings "inf"/"nan")."""
    from rotorcheck.report.reports import render_json

    sys.stdout.write(render_json(doc))
    sys.stdout.flush()


# --------------------------------------------------------------------------------------------
# top-level options


def package_version() -> str:
    """The installed distribution's version (importlib.metadata), else ``rotorcheck.__version__``."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rotorcheck")
    except PackageNotFoundError:  # imported from a checkout that is not installed
        from rotorcheck import __version__

        return __version__


def _print_version(value: bool) -> None:
    if value:
        sys.stdout.write(f"rotorcheck {package_version()}\n")
        raise typer.Exit(EXIT_OK)


def _print_samples_dir(value: bool) -> None:
    if value:
        from rotorcheck.resources import samples_dir

        sys.stdout.write(f"{samples_dir()}\n")
        raise typer.Exit(EXIT_OK)


@app.callback()
def _top_level(
    version: Annotated[bool, typer.Option(
        "--version", is_eager=True, callback=_print_version, help="Print 'rotorcheck <version>' and exit.")] = False,
    samples: Annotated[bool, typer.Option(
        "--samples-dir", is_eager=True, callback=_print_samples_dir,
        help="Print the folder of the bundled sample sweeps (e.g. crack_rig/healthy_1000rpm.h5) and exit.")] = False,
) -> None:
    """Has this shaft changed, where in the spectrum, and what exactly changed?"""


# --------------------------------------------------------------------------------------------
# commands


@app.command()
def model(
    rig: Annotated[Path | None, typer.Argument(help="Rig YAML (default: configs/crack_rig.yaml).")] = None,
    speed: Annotated[float | None, typer.Option(
        "--speed", help="Spin speed, rpm (default: every speed of the rig's analysis.speeds_rpm).")] = None,
    out: OutOpt = DEFAULT_OUT,
    as_json: JsonOpt = False,
    force: ForceOpt = False,
    plots: Annotated[bool, typer.Option(help="Write Campbell, mode-shape and rotor plots.")] = True,
    plot_format: PlotFormatOpt = "png",
    speed_unit: Annotated[str, typer.Option("--speed-unit", help="Speed axis of the Campbell diagram: rpm | Hz.")
                          ] = "rpm",
) -> int:
    """Natural frequencies, damping, whirl and critical speeds; Campbell, mode-shape and rotor plots."""
    from rotorcheck.resources import default_rig_path
    from rotorcheck.workflow import model_report

    _speed(speed)
    rig_path = rig if rig is not None else default_rig_path("crack_rig")
    from rotorcheck.workflow import plot_formats

    with _progress(f"solving the model of {rig_path}" + (" and plotting" if plots else "")):
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
        _emit_json(summary)
    return EXIT_OK


@app.command()
def info(
    sweep: Annotated[Path, typer.Argument(help="Sweep file (HDF5, rotorcheck.sweep v1 or v2).")],
    as_json: JsonOpt = False,
    confidence: Annotated[float, typer.Option(help="Family-wise confidence of the noise bound.")] = 0.99,
) -> int:
    """Validate a sweep file and summarise it: runs, speeds, grid, channels, noise estimate."""
    from rotorcheck.sweep.hdf5io import read_sweep, sweep_sha256
    from rotorcheck.sweep.summary import summarize

    in_open_unit(confidence, "--confidence")
    sw = read_sweep(sweep)
    doc = summarize(sw, confidence=confidence)
    doc["file"] = str(sweep)
    doc["sha256"] = sweep_sha256(sweep)
    err.print(f"{sweep}: valid rotorcheck.sweep v{doc['schema_version']}, rig_id {sw.rig_id!r}, source {sw.source}, "
              f"{sw.generator}")
    from rotorcheck.resources import configs_dir

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
    if as_json:
        _emit_json(doc)
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
    from rotorcheck.errors import check_rig_id
    from rotorcheck.sweep.convert import ConvertOptions

    if rig_id is not None:
        check_rig_id(rig_id, None, "--rig-id")
    from rotorcheck.sweep.convert import convert as convert_files

    opts = ConvertOptions(speed_rpm=speed, noise_source=noise_source, noise_var=noise_var, rig_id=rig_id,
                          run_id=run_id, column_map=column_map, ascii=ascii_58, force=force)
    doc = convert_files(source, target, from_format=from_format, to_format=to_format, wide=wide, options=opts)
    for r in doc["runs"]:
        what = f"FRF only, noise: {r['noise_source']}" if r["frf_only"] else "phasors"
        err.print(f"run {r['run_id']}: {r['speed_rpm']:g} rpm, {r['n_points']} points {r['f_min_hz']:g}-"
                  f"{r['f_max_hz']:g} Hz, {what}")
    err.print(f"{source} ({doc['format_in']}) -> {doc['format_out']}: wrote {', '.join(doc['files'])}")
    if as_json:
        _emit_json(doc)
    return EXIT_OK


@app.command()
def crack(
    rig: Annotated[Path | None, typer.Argument(help="Rig YAML (default: the truth rig).")] = None,
    fault: Annotated[str, typer.Option("--fault", help="Breathing crack in the rig.")] = "breathing_crack",
    unbalance: Annotated[float, typer.Option("--unbalance", help="Unbalance at the first disc, g m.")] = 0.2,
    out: OutOpt = DEFAULT_OUT,
    plot_format: PlotFormatOpt = "png",
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """The cracked rotor: stiffness over a revolution, orbits, spectra at 1000 and 750 rpm (Fig. 56-58)."""
    from rotorcheck.resources import configs_dir
    from rotorcheck.workflow import crack_report, plot_formats

    finite_positive(unbalance, "--unbalance", allow_zero=True)
    rig_path = rig if rig is not None else configs_dir() / "crack_rig_truth.yaml"
    with _progress(f"the cracked rotor ({fault}): harmonic balance, orbits, spectra"):
        doc = crack_report(rig_path, fault=fault, unbalance_g_m=unbalance, out_dir=out, force=force,
                           formats=plot_formats(plot_format))
    for key, h in doc["harmonics"].items():
        amps = ", ".join(f"{n}X {x * 1e6:.3g}" for n, x in zip(h["order"][1:5], h["x_m"][1:5]))
        err.print(f"{key:16s} x at station {doc['station']} (um): {amps}")
    for p_ in doc["files"]:
        err.print(f"wrote {p_}")
    if as_json:
        _emit_json(doc)
    return EXIT_OK


def _element_list(text: str) -> tuple[int, ...] | None:
    """``--elements 3,4,5`` as element numbers (None: every element)."""
    try:
        return tuple(int(x) for x in text.replace(" ", "").split(",") if x) or None
    except ValueError:
        raise InputError(None, "--elements", f"{text!r} is no list of element numbers (e.g. 3,4,5)") from None


def _fail_at(spec: str) -> tuple[int, ...]:
    """Testing hook ``--fail-at 3,17`` (hidden): the solver fails at those point indices."""
    try:
        return tuple(int(x) for x in spec.split(",") if x.strip())
    except ValueError:
        raise InputError(None, "--fail-at", f"expected comma-separated point indices, got {spec!r}") from None


FailAtOpt = Annotated[str, typer.Option("--fail-at", hidden=True, help="Testing: fail the solver at these points.")]


RunOpt = Annotated[str | None, typer.Option("--run", help="Run id inside the sweep file (default: the only one).")]


@app.command("fit-noise")
def fit_noise(
    sweep: Annotated[Path | None, typer.Argument(help="Healthy sweep (default: bundled healthy_1000rpm).")] = None,
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
    from rotorcheck import workflow
    from rotorcheck.baseline import write_baseline
    from rotorcheck.fileio import check_writable
    from rotorcheck.resources import samples_dir

    sweep_path = sweep if sweep is not None else samples_dir() / "crack_rig" / "healthy_1000rpm.h5"
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
        _emit_json(workflow.noise_report(nb, sweep_path, target).to_dict())
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
    learn_drift: Annotated[bool, typer.Option(
        "--learn-drift", help="Learn from the healthy sweeps (>= 3, drifted across the ranges) how the machine "
                              "drifts: a correction of the model's benign change, directions, kappa.")] = False,
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
    from rotorcheck import workflow
    from rotorcheck.baseline import write_baseline
    from rotorcheck.fileio import check_output_place, claim_outputs

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
        with _progress(f"validating run {first.run_id} ({len(runs)} healthy sweeps, {first.frequency_hz.size} points)"):
            outcome = workflow.validate(cfg, runs, nb, enclose=enclose, fail_at=_fail_at(fail_at), update=update,
                                        learn_drift=learn_drift)
        outcome.baseline.provenance.rig_path = str(Path(rig_path).resolve())  # later commands need no --rig
        if reused_from and nb is noise:
            outcome.baseline.provenance.noise_fitted_on_sweep = reused_from
        outcomes.append(outcome)
        for line in (workflow.update_summary(outcome), workflow.learning_summary(outcome)):
            if line:
                err.print(line)
        with _progress("writing plots"):
            files = (workflow.validation_plots(outcome, plot_dir, at, formats, out / "baseline.h5", frf_unit)
                     if plots else [])
        res = outcome.result
        n_bad += outcome.n_not_enclosed
        g = res.gamma[np.isfinite(res.gamma)]
        unit = "m/N" if outcome.model.structure == "additive" else (
            "(relative)" if outcome.model.structure == "multiplicative" else f"({outcome.model.parameter})")
        err.print(f"{f'run {first.run_id} ({first.speed_rpm:g} rpm): ' if several else ''}gamma over {res.gamma.size} "
                  f"points ({enclose}): median {np.median(g):.3g}, max {np.max(g):.3g} {unit}")
        if outcome.n_not_enclosed:
            bad = np.flatnonzero(res.status != "ok")
            err.print(f"[yellow]{outcome.n_not_enclosed} points not enclosed[/]: " + ", ".join(
                f"{runs[0].frequency_hz[i]:.1f} Hz ({res.status[i]})" for i in bad[:10]))
        for p_ in files:
            err.print(f"wrote {p_}")
        written += map(Path, files)
        docs.append(outcome.typed_report(nb, target).to_dict())
        if outcome.baseline.provenance.noise_fitted_on_sweep:  # a bound from another sweep, as asked
            docs[-1]["noise_fitted_on_sweep"] = outcome.baseline.provenance.noise_fitted_on_sweep
    write_baseline(outcomes[0].baseline, target, [o.baseline for o in outcomes[1:]])
    _record_run("validate", [target, *written], [out, *plot_dirs], force)
    err.print(f"wrote {target}" + (f" ({len(outcomes)} runs: {', '.join(run_ids)})" if several else ""))
    if as_json:
        _emit_json(docs[0] if not several else {"runs": docs})
    return EXIT_INCONCLUSIVE if n_bad else EXIT_OK


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
    fail_at: FailAtOpt = "",
    as_json: JsonOpt = False,
    force: ForceOpt = False,
) -> int:
    """Steps 4-5: verdict (joint test or certified fault points) and the damage with its bound; a file of
    several runs: each run against the baseline's run at its speed, one verdict for the file."""
    from rotorcheck import workflow
    from rotorcheck.fileio import atomic_write_text, claim_outputs
    from rotorcheck.report.reports import REPORT_FILES, render_json, write_reports

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
    settings = workflow.DetectorSettings(confidence, false_alarm, _fail_at(fail_at))
    with _progress(f"detecting {sweep.name} against {base_path}"):
        check = workflow.detect_pairs(cfg, rig_file, sweep, base_path, pairs, rule, settings, locate, say=err.print)
    summary: list[dict[str, Any]] = []
    written: list[Path] = []
    for d, (base, mrun), outcome in zip(dirs, pairs, check.outcomes):
        with _progress("writing reports and plots"):
            report = outcome.typed_report()
            report.baseline = str(base_path)
            plot_files = workflow.detection_plots(outcome, d, at, formats, base_path, frf_unit) if plots else []
            files = write_reports(report, d, plot_files, base_path)
        _print_outcome(outcome, report, prefix=f"run {mrun.run_id} ({mrun.speed_rpm:g} rpm): " if several else "")
        written += [*files, *map(Path, plot_files)]
        if not several:
            _record_run("detect", written, [out], force)
            for p_ in [*map(str, files), *plot_files]:
                err.print(f"wrote {p_}")
            if as_json:
                _emit_json(report.to_dict())
            return outcome.exit_code
        summary.append({"run_id": mrun.run_id, "speed_rpm": mrun.speed_rpm, "baseline_run_id": base.run_id,
                        "verdict": report.verdict, "verdict_reason": report.verdict_reason,
                        "report": str(d / "report.json")})
    doc = {"sweep": str(sweep), "verdict": check.verdict, "verdict_rule": workflow.FILE_RULE, "runs": summary}
    atomic_write_text(out / "report.json", render_json(doc))
    _record_run("detect", [*written, out / "report.json"], [out, *dirs], force)
    err.print(f"file verdict: {check.verdict.upper()} ({len(pairs)} runs); wrote {out / 'report.json'}")
    if as_json:
        _emit_json(doc)
    return check.exit_code


def _record_run(command: str, written: list[Path], folders: list[Path], force: bool) -> None:
    """Record what this run of ``command`` wrote (the folders' manifests); a forced run then removes what an
    earlier run of the command wrote there and this one did not rewrite (e.g. plots after --no-plots)."""
    from rotorcheck.fileio import record_outputs, remove_stale_outputs

    record_outputs(written, command)
    if force:
        for p_ in remove_stale_outputs(folders, command, written):
            err.print(f"removed {p_} (an earlier {command} run's output this run did not rewrite)")


def _print_outcome(outcome: Any, report: DetectionReport, prefix: str = "") -> None:
    from rotorcheck import workflow

    v = outcome.verdict
    colour = {"damage": "bold red", "healthy": "bold green", "inconclusive": "bold yellow"}[v.verdict]
    err.print(f"{prefix}[{colour}]{v.verdict.upper()}[/]: {v.reason}")
    err.print(f"{report.n_fault_points} of {report.n_points} points are fault points"
              + (f" (sweep p-value {report.p_value:.3g}, {report.confidence:.0%} family-wise)"
                 if report.p_value is not None and report.confidence is not None else ""))
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
    elements: Annotated[str, typer.Option(
        "--elements", help="Candidate shaft elements, e.g. 3,4,5 (default: every element).")] = "",
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
    from rotorcheck import workflow
    from rotorcheck.fileio import atomic_write_text, check_writable
    from rotorcheck.report.reports import render_json

    formats = workflow.plot_formats(plot_format)
    base_path = baseline if baseline is not None else out / "baseline.h5"
    els = _element_list(elements)
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
    with _progress(f"locating the change of {sweep.name} (every candidate element, certified)"):
        res = workflow.locate_damage(cfg, base, mrun, false_alarm, els, section_length)
    doc = {"sweep": str(sweep), "sweep_sha256": mrun.sha256, "baseline": str(base_path), "rig_id": cfg.rig_id,
           "speed_rpm": mrun.speed_rpm, **res.to_dict()}
    atomic_write_text(out / "location.json", render_json(doc))
    written = [out / "location.json"]
    if plots:
        from rotorcheck.report.figures import save_figure
        from rotorcheck.report.plots import location_figure

        written += save_figure(location_figure(cfg, res, f"{sweep.name}: {res.summary()}"), out / "location", formats)
    from rotorcheck.report.html import render_location_html

    atomic_write_text(out / "location.html", render_location_html(doc, [str(p) for p in written[1:]], cfg.sha256()))
    written.append(out / "location.html")
    err.print(("[bold red]" if res.best is not None else "[bold green]") + res.summary() + "[/]")
    if res.single_channel is not None:
        err.print("one channel alone: " + res.single_channel.summary())
    for p_ in written:
        err.print(f"wrote {p_}")
    if as_json:
        _emit_json(doc)
    return EXIT_DAMAGE if res.best is not None else EXIT_OK


@app.command()
def ingest(
    files: Annotated[list[Path], typer.Argument(metavar="RECORD... OUT.h5", help=(
        "Time records of one sweep (.mat .tdms .wav .csv .parquet .uff .h5), then the sweep file to write."))],
    channel_map: Annotated[Path, typer.Option("--map", help="Channel map YAML (docs/ingest.md).")],
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> int:
    """Stepped-sine time records (force or current, probes, keyphasor) -> a sweep file (docs/ingest.md)."""
    from rotorcheck.ingest import ingest_files

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
        _emit_json({"file": str(output), **s})
    return EXIT_OK


@app.command()
def simulate(
    output: Annotated[Path, typer.Argument(help="Sweep file to write (HDF5).")],
    rig: Annotated[Path | None, typer.Option("--rig", help="Truth rig (default configs/crack_rig_truth.yaml).")] = None,
    speed: Annotated[float, typer.Option("--speed", help="Spin speed, rpm.")] = 0.0,
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
    actuator: Annotated[list[str] | None, typer.Option(
        "--actuator", help="A force input at a station and direction, e.g. 8x (repeat for several; driven one at a "
                           "time). Default: the rig's actuator.")] = None,
    sensor: Annotated[list[str] | None, typer.Option(
        "--sensor", help="A displacement output, e.g. 6y (repeat for several). Default: the rig's sensor.")] = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> int:
    """Simulate a stepped-sine sweep of a (truth) rig, healthy or with a named fault; several --actuator /
    --sensor give an x/y sweep (format version 2)."""
    import dataclasses

    from rotorcheck import workflow
    from rotorcheck.fileio import check_writable
    from rotorcheck.resources import configs_dir
    from rotorcheck.sim.rig_sim import shaft_angle_from, simulate_rig, step_settings
    from rotorcheck.sweep.hdf5io import write_sweep

    _speed(speed)
    finite_positive(f_min, "--f-min")
    finite_positive(f_max, "--f-max")
    finite_positive(noise, "--noise", allow_zero=True)
    _at_least(points, 2, "--points")
    _at_least(periods, 1, "--periods")
    _at_least(seed, 0, "--seed")
    _at_least(harmonics, 1, "--harmonics")
    check_writable([output], force)
    rig_path = rig if rig is not None else configs_dir() / "crack_rig_truth.yaml"
    cfg = workflow.load_rig(rig_path)
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
    grid = np.linspace(f_min, f_max, points)
    with _progress(f"simulating {points} points at {speed:g} rpm" + (f" with {fault}" if fault else "")):
        if actuator or sensor:
            from rotorcheck.nominal import parse_port
            from rotorcheck.sim.rig_sim import simulate_rig_patterns

            acts = ([parse_port(a, "--actuator") for a in actuator] if actuator
                    else [cfg.io_ports("simulate").actuator])
            sens = [parse_port(x, "--sensor") for x in sensor] if sensor else [cfg.io_ports("simulate").sensor]
            sw = simulate_rig_patterns(cfg, grid, acts, sens, speed_rpm=speed, fault=fault, seed=seed,
                                       n_harmonics=harmonics, settings=st, created_utc=_utc_now(),
                                       shaft_angle_rad=angle)
        else:
            sw = simulate_rig(cfg, grid, speed, fault=fault, seed=seed, n_harmonics=harmonics, settings=st,
                              created_utc=_utc_now(), shaft_angle_rad=angle)
    write_sweep(sw, output, force=force)
    err.print(f"wrote {output}: {sw.generator}; {points} points {f_min:g}-{f_max:g} Hz at {speed:g} rpm")
    if as_json:
        _emit_json({"file": str(output), "rig_id": sw.rig_id, "generator": sw.generator, "speed_rpm": speed,
                    "fault": fault, "points": points, "seed": seed, "shaft_angle_deg": float(np.degrees(angle)),
                    "crack_depth": crack_depth})
    return EXIT_OK


def _utc_now() -> str:
    import datetime as dt

    return dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


@app.command()
def schema(
    out: Annotated[Path | None, typer.Option("--out", help="Write to this file instead of stdout.")] = None,
    force: ForceOpt = False,
) -> int:
    """JSON Schema of the rig YAML, for editors."""
    from rotorcheck.config import json_schema
    from rotorcheck.fileio import atomic_write_text, check_writable

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
    rig: Annotated[Path | None, typer.Argument(help="Rig YAML (default: configs/crack_rig.yaml).")] = None,
    baseline: Annotated[Path | None, typer.Option(
        "--baseline", help="Noise, grid and speed from this baseline (its healthy variance per point).")] = None,
    noise_std: Annotated[float | None, typer.Option(
        "--noise-std", help="Stated output noise per sample, m (default: the rig's measurement section).")] = None,
    periods: Annotated[int | None, typer.Option(
        "--periods", help="Periods averaged per frequency point (default: the rig's measurement).")] = None,
    speed: Annotated[float | None, typer.Option(
        "--speed", help="Spin speed, rpm (default: the baseline's, else the rig's first analysis speed).")] = None,
    sensors: Annotated[str, typer.Option(
        "--sensors", help="Sensor ports, e.g. 6x,6y,2x (default: the rig's sensor).")] = "",
    actuators: Annotated[str, typer.Option(
        "--actuators", help="Actuator ports, e.g. 8x,8y (default: the rig's actuator).")] = "",
    elements: Annotated[str, typer.Option("--elements", help="Shaft elements, e.g. 3,4,6 (default: all).")] = "",
    false_alarm: Annotated[float, typer.Option("--false-alarm", help="False-alarm rate per sweep.")] = 0.01,
    candidate_sensors: Annotated[str, typer.Option(
        "--candidate-sensors", help="Rank sensor sets from these ports, e.g. 2x,2y,4x,6x,6y (stated noise).")] = "",
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
    from rotorcheck import workflow
    from rotorcheck.baseline import read_baseline
    from rotorcheck.fileio import atomic_write_text, check_writable
    from rotorcheck.report.reports import render_json
    from rotorcheck.resources import default_rig_path

    finite_positive(noise_std, "--noise-std")
    _speed(speed)
    _at_least(periods, 1, "--periods")
    _at_least(max_sensors, 1, "--max-sensors")
    in_open_unit(false_alarm, "--false-alarm")
    rig_path = rig if rig is not None else default_rig_path("crack_rig")
    cfg = workflow.load_rig(rig_path)
    els = workflow.check_elements(cfg, _element_list(elements))
    split = lambda t: [x for x in t.replace(" ", "").split(",") if x]  # noqa: E731
    formats = workflow.plot_formats(plot_format)
    targets = [out / "detectability.json"] + (workflow.plot_paths(out, ("detectability",), formats) if plots else [])
    check_writable(targets, force)
    base = read_baseline(baseline) if baseline is not None else None
    if base is not None and base.rig_id != cfg.rig_id:
        raise InputError(baseline, "/@rig_id", f"baseline for rig {base.rig_id!r}, not {cfg.rig_id!r}")
    with _progress(f"predicting what {cfg.rig_id} can detect, element by element"):
        det = workflow.detectability_for_rig(cfg, speed, base, noise_std, periods, split(sensors), split(actuators),
                                             false_alarm, els, source=str(baseline or rig_path))
    doc = {"rig": str(rig_path), **det.to_dict()}
    if candidate_sensors:
        if base is not None:
            raise InputError(None, "--candidate-sensors", "ranking sensors needs stated noise (--noise-std), "
                             "not a baseline's channels")
        with _progress(f"ranking sensor sets of up to {max_sensors} from {candidate_sensors}"):
            doc["sensor_sets"] = workflow.sensor_ranking_for_rig(
                cfg, split(candidate_sensors), max_sensors, speed, noise_std, periods, split(sensors),
                split(actuators), false_alarm, source=str(rig_path))
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
        from rotorcheck.report.figures import save_figure
        from rotorcheck.report.plots import detectability_figure

        written += save_figure(detectability_figure(cfg, det), out / "detectability", formats)
    err.print(det.summary())
    for p_ in written:
        err.print(f"wrote {p_}")
    if as_json:
        _emit_json(doc)
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
    from rotorcheck.errors import check_rig_id
    from rotorcheck.fileio import atomic_write_text, check_writable
    from rotorcheck.ross_import import import_ross

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
        _emit_json({"rig": str(out), "rig_id": result.rig["rig_id"], "not_carried": list(result.not_carried)})
    return EXIT_OK


def _register_fleet() -> None:
    """`rotorcheck fleet` (issue 15): many machines over time (rotorcheck.fleet)."""
    from rotorcheck.fleet import command as fleet_command

    fleet_command.register(app)


_register_fleet()


# --------------------------------------------------------------------------------------------
# entry point


def main(argv: list[str] | None = None) -> int:
    """Run the CLI and return its exit code; every failure maps to the documented codes."""
    command = typer.main.get_command(app)
    version_opt = next(p for p in command.params if p.name == "version")
    for sub in getattr(command, "commands", {}).values():  # `rotorcheck <command> --version` too (cli.md)
        opt = copy.copy(version_opt)
        opt.expose_value = False  # eager: prints and exits; never passed to the command
        sub.params.append(opt)
    try:
        return _run(command, argv)
    finally:
        from rotorcheck.fileio import release_claims

        release_claims()  # the outputs this command claimed (fileio.claim_outputs)


def _run(command: Any, argv: list[str] | None) -> int:
    """:func:`main` without the claims' release."""
    try:
        rc = command.main(args=argv, prog_name="rotorcheck", standalone_mode=False)
    except (UserInputError, FileExistsError) as exc:  # InputError, ConfigError, SweepFormatError
        err.print(f"[bold red]error:[/] {escape(str(exc))}")
        return EXIT_INPUT
    except typer.Exit as exc:
        return int(exc.exit_code)
    except OSError as exc:  # a file the OS refused (no permission, full disk, a folder in the way): name it
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        if exc.filename is None:
            err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
            return EXIT_INPUT
        err.print(f"[bold red]error:[/] {escape(str(exc.filename))}: {escape(exc.strerror or str(exc))}")
        return EXIT_INPUT
    except typer.Abort:
        err.print("aborted")
        return EXIT_INPUT
    except Exception as exc:  # the contract: an unexpected exception is 2, never 1
        if hasattr(exc, "show") and hasattr(exc, "exit_code"):  # click/typer usage errors
            exc.show(file=sys.stderr)
            return EXIT_INPUT if exc.exit_code else EXIT_OK
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
        return EXIT_INPUT
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except BaseException as exc:  # a native panic (pyo3's PanicException) outside a guarded solver call: still 2
        if os.environ.get("ROTORCHECK_DEBUG"):
            raise
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {escape(str(exc))}")
        return EXIT_INPUT
    return rc if isinstance(rc, int) else EXIT_OK


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())


if __name__ == "__main__":
    run()
