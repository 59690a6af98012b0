"""Validation and detection figures by file stem (Bode with bands, complex plane, decision, damage dynamics)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rotorcheck.baseline import Baseline
from rotorcheck.config import RigConfig
from rotorcheck.errors import check_choice
from rotorcheck.nominal import NominalModel, primary_pair
from rotorcheck.robust.identify import moebius_disk_image
from rotorcheck.robust.lft import lft_upper
from rotorcheck.units import PLOT_FRF_UNITS
from rotorcheck.workflow.detection import DetectionOutcome, healthy_frf_of
from rotorcheck.workflow.measured import MeasuredRun
from rotorcheck.workflow.noise import frf_noise_radius
from rotorcheck.workflow.rigs import damage_port_name, port_static_stiffness
from rotorcheck.workflow.validation import ValidationOutcome

if TYPE_CHECKING:  # the plots module imports matplotlib: only when plotting
    from rotorcheck.report.plots import FigureContext


def uncertainty_disk(model: NominalModel, gamma: np.ndarray, noise_bound_m: float | np.ndarray, W: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Centre and radius (m/N) of the set of receptances the healthy uncertain model explains."""
    G = model.frf
    noise = noise_bound_m / np.abs(W)
    if model.structure == "additive":
        return G, gamma + noise
    if model.structure == "multiplicative":
        return G, gamma * np.abs(G) + noise

    me = model.me

    def fun(delta: np.ndarray) -> np.ndarray:
        return lft_upper(me, np.asarray(delta, complex)[:, None, None])[:, 0, 0]

    ds = moebius_disk_image(fun, gamma, n_freq=me.shape[0])
    radius = np.where(ds.kind == "disk", ds.radius, np.inf)
    centre = np.where(ds.kind == "disk", ds.centre, G)
    return centre, radius + noise


def _v_of(b: Baseline) -> float | np.ndarray:
    return b.noise_bound_per_point_m if b.noise_bound_per_point_m is not None else b.noise_bound_m


def _plot_index(f: np.ndarray, at_hz: float | None, score: np.ndarray) -> int:
    """``at_hz`` (nearest grid point), else the point of the largest finite ``score``."""
    if at_hz is not None:
        return int(np.argmin(np.abs(f - at_hz)))
    finite = np.where(np.isfinite(score), score, -np.inf)
    return int(np.argmax(finite))


def _telling_fault(ratio: np.ndarray, fault: np.ndarray) -> int:
    """The fault point that shows the decision best in the complex plane: the one whose distance ratio is
    nearest 2 (log scale): outside its set, but the set still visible beside it."""
    r = np.where(fault & np.isfinite(ratio) & (ratio > 0), ratio, np.nan)
    return int(np.nanargmin(np.abs(np.log(r / 2.0))))


def check_frf_unit(frf_unit: str) -> str:
    """``frf_unit`` when the plots know it (m/N, mm/N, um/N), else an InputError naming --frf-unit."""
    return check_choice(frf_unit, PLOT_FRF_UNITS, "--frf-unit")  # without importing matplotlib


def figure_context(rig: RigConfig, run: MeasuredRun, baseline_path: str | Path | None = None,
                   frf_unit: str = "m/N") -> FigureContext:
    """What a validation or detection figure shows: rig, speed (none for a lumped rig), the channel pair
    drawn (the rig's actuator -> sensor), the sweep file and the baseline file."""
    from rotorcheck.report.plots import FigureContext  # lazy: matplotlib only when plotting

    check_frf_unit(frf_unit)
    pair = run.pairs[0] if run.pairs else primary_pair(rig)
    out, inp = pair.key()
    channels = f"{out} <- {inp}" + (f" (1 of {run.n_pairs} channel pairs)" if run.n_pairs > 1 else "")
    return FigureContext(rig_id=rig.rig_id, speed_rpm=run.speed_rpm if rig.kind == "rotor" else None,
                         channels=channels, sweep=Path(run.path).name,
                         baseline=str(baseline_path) if baseline_path is not None else "", frf_unit=frf_unit,
                         n_pairs=run.n_pairs)


def validation_plots(outcome: ValidationOutcome, out_dir: str | Path, at_hz: float | None = None,
                     formats: tuple[str, ...] = ("png",), baseline_path: str | Path | None = None,
                     frf_unit: str = "m/N") -> list[str]:
    """:func:`validation_figures` written to ``out_dir`` (``formats``); returns the written paths."""
    from rotorcheck.report.figures import save_figures  # lazy: matplotlib only when plotting

    return save_figures(validation_figures(outcome, at_hz, baseline_path, frf_unit), out_dir, formats)


def validation_figures(outcome: ValidationOutcome, at_hz: float | None = None,
                       baseline_path: str | Path | None = None, frf_unit: str = "m/N") -> dict[str, Any]:
    """Bode with the uncertainty band and the complex plane at one frequency (``at_hz``, default the point
    of the largest relative model error), by file stem (:data:`PLOT_STEMS_VALIDATE`)."""
    from rotorcheck.report.plots import (  # lazy: matplotlib only when plotting
        bode_band_figure,
        complex_plane_figure,
    )

    b, run, model = outcome.baseline, outcome.runs[0], outcome.model
    ctx = figure_context(outcome.rig, run, baseline_path, frf_unit)
    centre, radius = uncertainty_disk(model, b.gamma, _v_of(b), run.W)
    title = ctx.title(f"Validation ({b.uncertainty}, enclose {b.enclose})")
    i = _plot_index(run.frequency_hz, at_hz, np.abs(run.frf - model.frf) / np.abs(model.frf))
    return {"validation_bode": bode_band_figure(run.frequency_hz, model.frf, centre, radius, healthy_frf=run.frf,
                                                title=title, context=ctx),
            "validation_complex_plane": complex_plane_figure(
                float(run.frequency_hz[i]), complex(model.frf[i]), complex(centre[i]), float(radius[i]),
                healthy=complex(run.frf[i]), context=ctx, healthy_noise=float(frf_noise_radius(run)[i]))}


def detection_plots(outcome: DetectionOutcome, out_dir: str | Path, at_hz: float | None = None,
                    formats: tuple[str, ...] = ("png",), baseline_path: str | Path | None = None,
                    frf_unit: str = "m/N", show_nominal_damage: bool = False) -> list[str]:
    """:func:`detection_figures` written to ``out_dir`` (``formats``); returns the written paths."""
    from rotorcheck.report.figures import save_figures  # lazy: matplotlib only when plotting

    return save_figures(detection_figures(outcome, at_hz, baseline_path, frf_unit, show_nominal_damage), out_dir,
                        formats)


def detection_figures(outcome: DetectionOutcome, at_hz: float | None = None,
                      baseline_path: str | Path | None = None, frf_unit: str = "m/N",
                      show_nominal_damage: bool = False) -> dict[str, Any]:
    """The detection figures by file stem (:data:`PLOT_STEMS_DETECT`): the decision (ratio per frequency
    against its threshold, the joint test), Bode with band, healthy and new data and fault points, complex
    plane at one frequency (``at_hz``, default the fault point nearest ratio 2), damage dynamics with its
    bound and the port's stiffness as reference. ``show_nominal_damage``: the damage figure also draws D_u
    with the nominal model's E22 (thin, grey; it carries the model error, not to be read) where the anchored
    estimate leads; hidden by default."""
    from rotorcheck.report.plots import (  # lazy: matplotlib only when plotting
        bode_band_figure,
        complex_plane_figure,
        damage_dynamics_figure,
        decision_figure,
    )

    figs: dict[str, Any] = {}
    b, run, model = outcome.baseline, outcome.run, outcome.model
    ctx = figure_context(outcome.rig, run, baseline_path, frf_unit)
    fault = np.asarray(outcome.detection.fault, dtype=bool)
    healthy = healthy_frf_of(b)
    if outcome.measured is not None and healthy is not None:  # the measured set: T_h within the allowance
        centre, radius = healthy, outcome.measured.radius[:, 0]
        set_label = "healthy data's set (noise of both sweeps)"
    else:
        assert b.gamma is not None, "a validated baseline"
        centre, radius = uncertainty_disk(model, b.gamma, _v_of(b), run.W)
        set_label = "uncertainty set (model + gamma_h + noise)"
    j = outcome.joint
    joint = None if j is None else {"statistic": j.statistic, "threshold": j.threshold, "p_value": j.p_value,
                                    "false_alarm": j.false_alarm}
    found = outcome.found  # the statistic that decided, per point, as the detector computed it
    decided, meaning = found.ratio, found.ratio_meaning
    figs["detection_decision"] = decision_figure(run.frequency_hz, decided, fault,
                                                 np.asarray(outcome.detection.status), ctx, outcome.verdict.verdict,
                                                 outcome.verdict_rule, meaning, joint, outcome.fault_beyond_benign)
    fig = bode_band_figure(run.frequency_hz, model.frf, centre, radius, healthy_frf=healthy, damaged_frf=run.frf,
                           fault=fault, title=ctx.title(f"Detection Bode ({outcome.verdict.verdict.upper()})"),
                           context=ctx, band_label=set_label + ": range over the disk")
    figs["detection_bode"] = fig
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = outcome.detection.gamma_required / np.maximum(outcome.detection.gamma_healthy, 1e-300)
    if at_hz is None and np.any(fault & np.isfinite(ratio)):
        own = fault & (ratio > 1.0)  # faults the drawn pair itself shows (with several pairs, not every one)
        i = _telling_fault(ratio, own if np.any(own) else fault)
    else:
        i = _plot_index(run.frequency_hz, at_hz, np.abs(run.frf - model.frf))
    h_i = None if healthy is None else complex(healthy[i])
    fig = complex_plane_figure(float(run.frequency_hz[i]), complex(model.frf[i]), complex(centre[i]),
                               float(radius[i]), healthy=h_i, damaged=complex(run.frf[i]), context=ctx,
                               damaged_noise=float(frf_noise_radius(run)[i]), set_label=set_label)
    figs["detection_complex_plane"] = fig
    ds = outcome.damage_set
    title = ctx.title(f"Damage dynamics D_u at the damage port {damage_port_name(outcome.rig)}")
    k_port = port_static_stiffness(outcome.rig, run.speed_rpm)
    ref = {"reference_n_per_m": 0.01 * k_port,
           "reference_label": {1.0: f"1 % of the damage port's static stiffness k = {k_port:.3g} N/m",
                               0.1: "0.1 % of k"}} if np.isfinite(k_port) else {}
    if outcome.anchored is not None and outcome.anchored_set is not None:  # lead with the anchored estimate
        a = outcome.anchored_set
        conf = f", {outcome.measured.confidence:.0%}" if outcome.measured is not None else ""
        fig = damage_dynamics_figure(run.frequency_hz, outcome.anchored, a.min_abs, a.max_abs,
                                     np.degrees(a.phase_min), np.degrees(a.phase_max), fault=fault, title=title,
                                     nominal=outcome.damage if show_nominal_damage else None,
                                     label="D_u anchored at the healthy data",
                                     bound_label=f"its bound (noise of both sweeps + channel error{conf})",
                                     context=ctx, **ref)  # type: ignore[arg-type]
    else:
        fig = damage_dynamics_figure(run.frequency_hz, outcome.damage, ds.min_abs, ds.max_abs,
                                     np.degrees(ds.phase_min), np.degrees(ds.phase_max), fault=fault, title=title,
                                     context=ctx, **ref)  # type: ignore[arg-type]
    figs["damage_dynamics"] = fig
    return figs


PLOT_STEMS_VALIDATE = ("validation_bode", "validation_complex_plane")


PLOT_STEMS_DETECT = ("detection_decision", "detection_bode", "detection_complex_plane", "damage_dynamics")

