"""Issue 14: the validation and detection figures, checked by their artists.

Each figure is built from a real detection on the bundled samples and inspected: what its title names,
where its legend sits, how many fault markers it carries against the report's count, that no phase band
is wider than 360 degrees, that the plotted ratio is the distance of the new data from the set computed
here a second way, and that the damage figure's reference is the port's static stiffness from a static
FE solve (not the frequency-response path the figure uses). (The decision figure with several channel pairs:
test_multichannel.py, beside the x/y standstill detection it shares.)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from rotorcheck import workflow
from rotorcheck.config import load_config
from rotorcheck.report.plots import FigureContext, damage_dynamics_figure, disk_band
from rotorcheck.resources import configs_dir, samples_dir

CR = samples_dir() / "crack_rig"
TM = samples_dir() / "three_mass"


@pytest.fixture(scope="module")
def breathing(sample_pipeline: Callable[..., tuple[object, object]]) -> tuple[object, object]:
    """The breathing crack at 1000 rpm against the measured baseline (joint test)."""
    return sample_pipeline(configs_dir() / "crack_rig.yaml", CR / "healthy_1000rpm.h5",
                           CR / "breathing_crack_1000rpm.h5", "measured")


@pytest.fixture(scope="module")
def three_mass(sample_pipeline: Callable[..., tuple[object, object]]) -> tuple[object, object]:
    """Three-mass trial 1 (a lumped rig that does not rotate) with the set enclosing every system."""
    return sample_pipeline(configs_dir() / "three_mass_trial1.yaml", TM / "healthy.h5", TM / "damaged.h5", "system")


def _drawn(fig: Figure) -> None:
    fig.canvas.draw()  # type: ignore[no-untyped-call]  # Figure() gets a FigureCanvasBase: Agg draws


def _legend_outside_axes(fig: Figure) -> None:
    """Every legend's box lies outside every axes' data area (display coordinates)."""
    _drawn(fig)
    boxes = [ax.get_window_extent() for ax in fig.axes]
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    assert legends, "no legend"
    for leg in legends:
        lb = leg.get_window_extent()
        for b in boxes:
            assert not lb.overlaps(b), f"legend {lb} overlaps axes {b}"


def _fault_markers(ax: object) -> int:
    return sum(len(line.get_xdata()) for line in ax.get_lines() if line.get_gid() == "fault_points")  # type: ignore[attr-defined]


def test_context_names_rig_speed_channels_sweep_baseline() -> None:
    ctx = FigureContext("crack_rig", 1000.0, "s6.x <- s8.x", "new.h5", "out/baseline.h5")
    t = ctx.title("Detection")
    for part in ("crack_rig", "1000 rpm", "s6.x <- s8.x", "new.h5", "out/baseline.h5"):
        assert part in t
    assert "standstill (0 rpm)" in FigureContext("crack_rig", 0.0).title("Bode")
    assert "rpm" not in FigureContext("three_mass", None, "m1 <- m1").title("Bode")


def test_detection_figures_name_what_they_show(breathing: tuple, three_mass: tuple) -> None:
    _, out = breathing
    figs = workflow.detection_figures(out, baseline_path="base/baseline.h5")  # type: ignore[arg-type]
    assert set(figs) == set(workflow.PLOT_STEMS_DETECT)
    for stem, fig in figs.items():
        title = fig.axes[0].get_title()
        for part in ("crack_rig", "at 1000 rpm", "s6.x <- s8.x", "breathing_crack_1000rpm.h5", "base/baseline.h5"):
            assert part in title, (stem, part, title)
    _, out3 = three_mass
    for stem, fig in workflow.detection_figures(out3).items():  # type: ignore[arg-type]
        title = fig.axes[0].get_title()
        assert "three_mass" in title and "rpm" not in title, (stem, title)


@pytest.mark.parametrize("case", ["breathing", "three_mass"])
def test_fault_markers_equal_the_report_and_legends_sit_outside(case: str, request: pytest.FixtureRequest) -> None:
    _, out = request.getfixturevalue(case)
    rep = out.report()  # type: ignore[attr-defined]
    n = rep["n_fault_points"]
    assert n > 0
    figs = workflow.detection_figures(out)  # type: ignore[arg-type]
    for stem in ("detection_decision", "detection_bode", "damage_dynamics"):
        assert _fault_markers(figs[stem].axes[0]) == n, stem
    assert _fault_markers(figs["detection_bode"].axes[1]) == n  # phase too
    for stem, fig in figs.items():
        _legend_outside_axes(fig)
        for ax in fig.axes:
            assert ax.get_ylabel(), (stem, "y label")
    # the new data's dots stay visible: fault circles are open, the healthy dots are drawn above the new ones
    ax_m = figs["detection_bode"].axes[0]
    circles = next(ln for ln in ax_m.get_lines() if ln.get_gid() == "fault_points")
    assert circles.get_markerfacecolor() == "none"
    z = {ln.get_label(): ln.get_zorder() for ln in ax_m.get_lines()}
    assert z["healthy data"] > z["new data"]


def test_decision_ratio_is_the_distance_from_the_set(breathing: tuple) -> None:
    """Measured detection: the plotted ratio equals |T_new - T_h| / allowance computed here from the baseline
    and the new run; red points are exactly those above the threshold 1, grey ones at or below it."""
    _val, out = breathing
    b, run = out.baseline, out.run  # type: ignore[attr-defined]
    distance = np.abs(run.frf - b.healthy_frf[:, 0])  # the rig's own pair is the first column
    ratio = distance / out.measured.radius[:, 0]  # type: ignore[attr-defined]
    fig = workflow.detection_figures(out)["detection_decision"]  # type: ignore[arg-type]
    ax = fig.axes[0]
    lines = {ln.get_gid() or ln.get_label(): ln for ln in ax.get_lines()}
    f = run.frequency_hz
    for key in ("fault_points", next(k for k in lines if str(k).startswith("explained"))):
        x, y = np.asarray(lines[key].get_xdata()), np.asarray(lines[key].get_ydata())
        idx = np.searchsorted(f, x)
        np.testing.assert_allclose(y, ratio[idx], rtol=1e-6)
        assert np.all(y > 1.0) if key == "fault_points" else np.all(y <= 1.0)
    # the joint panel: the dot is T of the report, the dashed line its threshold
    rep = out.report()  # type: ignore[attr-defined]
    panel = {ln.get_gid(): ln for ln in fig.axes[1].get_lines()}
    assert float(np.asarray(panel["joint_statistic"].get_xdata())[0]) == pytest.approx(rep["joint_statistic"],
                                                                                      rel=1e-12)
    assert np.allclose(panel["joint_threshold"].get_xdata(), rep["joint_threshold"])
    assert "Rule" in ax.get_title() and "joint GLR" in ax.get_title()


def _vertical_extents(coll: PolyCollection) -> list[float]:
    """Largest vertical extent at any x of each polygon of a fill_between."""
    out = []
    for path in coll.get_paths():
        v = path.vertices
        for x in np.unique(np.round(v[:, 0], 9)):
            ys = v[np.isclose(v[:, 0], x), 1]
            out.append(float(ys.max() - ys.min()))
    return out


def test_no_phase_band_wider_than_360_and_origin_disks_hatched() -> None:
    """A set over the origin: magnitude band down to the axis (not a clipped floor), phase band exactly 360 deg
    wide and hatched; elsewhere the phase half width is asin(rho/|c|) (closed form)."""
    from rotorcheck.report.plots import bode_band_figure

    f = np.linspace(10, 100, 50)
    model = 1e-6 / (1 - (f / 55) ** 2 + 0.05j * f / 55)
    radius = np.abs(model) * np.where((f > 40) & (f < 60), 1.5, 0.3)  # over the origin near 55 Hz
    fig = bode_band_figure(f, model, model, radius, healthy_frf=model * 1.01, damaged_frf=model * 1.2,
                           fault=np.zeros(f.size, dtype=bool), context=FigureContext("r", 100.0))
    ax_m, ax_p = fig.axes[:2]
    widths = [w for c in ax_p.collections for w in _vertical_extents(c)]
    assert max(widths) <= 360.0 + 1e-9
    hatched = [c for c in ax_p.collections if c.get_hatch()]
    assert hatched and max(_vertical_extents(hatched[0])) == pytest.approx(360.0)
    band = disk_band(model, radius)
    ok = ~band["full_phase"]
    np.testing.assert_allclose(band["phase_half_width"][ok], np.degrees(np.arcsin(radius[ok] / np.abs(model[ok]))))
    lo, _hi = ax_m.get_ylim()
    assert lo >= np.min(np.abs(model)) / 4 and lo > 0  # no axis down to 1e-10


def test_damage_figure_marks_unbounded_and_not_significant() -> None:
    f = np.linspace(10, 300, 60)
    d = np.full(f.size, 5e3 + 0j)
    lo = np.where(f < 100, 3e3, 0.0)
    hi = np.where(f > 250, np.inf, 8e3)
    fig = damage_dynamics_figure(f, d, lo, hi, fault=f < 100, context=FigureContext("r", 0.0),
                                 reference_n_per_m=1.6e3, reference_label={1.0: "1 % of k", 0.1: "0.1 % of k"})
    ax = fig.axes[0]
    spans = [p for p in ax.patches if p.get_hatch()]
    covered = np.zeros(f.size, dtype=bool)
    for p in spans:
        x0 = p.get_x() if hasattr(p, "get_x") else p.get_path().vertices[:, 0].min()
        ext = p.get_path().get_extents(p.get_patch_transform() if hasattr(p, "get_patch_transform") else None)
        covered |= (f >= min(x0, ext.x0) - 1e-9) & (f <= ext.x1 + 1e-9)
    assert np.array_equal(covered, hi == np.inf)
    solid = next(ln for ln in ax.get_lines() if "bound excludes 0" in str(ln.get_label()))
    y = np.asarray(solid.get_ydata(), dtype=float)
    assert np.array_equal(np.isfinite(y), lo > 0)  # solid exactly where significant
    assert ax.get_ylim()[0] < 3e3 and ax.get_ylim()[0] > 0  # the bound's floor is the axis, not a clip above it
    refs = [ln for ln in ax.get_lines() if "1 % of k" in str(ln.get_label())]
    assert refs and np.allclose(refs[0].get_ydata(), 1.6e3)
    none = damage_dynamics_figure(f, d, np.zeros(f.size), np.full(f.size, 8e3), context=FigureContext("r", 0.0))
    assert any(t.get_gid() == "not_significant" for t in none.axes[0].texts)
    assert not any(t.get_gid() == "not_significant" for t in ax.texts)


def test_port_reference_is_the_static_stiffness_from_a_static_solve(breathing: tuple) -> None:
    """1 % of the damage port's static stiffness: k = 1 / (K^-1)_port from the assembled stiffness (with
    bearings), against the figure's line from the nominal model's E11 at 1 mHz."""
    from rotorcheck.fe.assembly import build_system

    _, out = breathing
    rig = out.rig  # type: ignore[attr-defined]
    system = build_system(rig)
    K = system.matrices(out.run.speed_rpm)[3]  # type: ignore[attr-defined]
    i = system.port_dof(rig.damage.port)
    e = np.zeros(K.shape[0])
    e[i] = 1.0
    k_static = 1.0 / np.linalg.solve(K, e)[i]
    fig = workflow.detection_figures(out)["damage_dynamics"]  # type: ignore[arg-type]
    ref = next(ln for ln in fig.axes[0].get_lines() if str(ln.get_label()).startswith("1 % of the damage port"))
    assert float(np.asarray(ref.get_ydata())[0]) == pytest.approx(0.01 * k_static, rel=1e-3)


def test_complex_plane_draws_the_set_and_the_data_noise(breathing: tuple) -> None:
    _, out = breathing
    fig = workflow.detection_figures(out, at_hz=54.0)["detection_complex_plane"]  # type: ignore[arg-type]
    ax = fig.axes[0]
    _legend_outside_axes(fig)
    assert "54.0" in ax.get_title() and "radii from the centre" in ax.get_title()
    labels = [str(ln.get_label()) for ln in ax.get_lines()]
    assert any("its noise bound" in lab for lab in labels)
    i = int(np.argmin(np.abs(out.run.frequency_hz - 54.0)))  # type: ignore[attr-defined]
    m_per = _unit_of(ax)  # m/N per drawn unit, from the axis label and the units table
    disk = m_per * ax.patches[0].get_path().vertices
    c = complex(out.baseline.healthy_frf[i, 0])  # type: ignore[attr-defined]
    r = np.abs(disk[:, 0] + 1j * disk[:, 1] - c)
    np.testing.assert_allclose(r, out.measured.radius[i, 0], rtol=1e-9)  # type: ignore[attr-defined]
    # by default (the fault point nearest ratio 2) framed on the set and the data: the whole disk and both data
    # points inside the axes' limits, the disk at least a tenth of the frame (not a speck beside the origin)
    fig = workflow.detection_figures(out)["detection_complex_plane"]  # type: ignore[arg-type]
    ax = fig.axes[0]
    _drawn(fig)
    f_at = float(ax.get_title().split("Complex plane at ", 1)[1].split(" Hz", 1)[0])
    i = int(np.argmin(np.abs(out.run.frequency_hz - f_at)))  # type: ignore[attr-defined]
    assert out.detection.fault[i]  # type: ignore[attr-defined]
    disk = ax.patches[0].get_path().vertices  # drawn units, as the limits and the data points
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= disk[:, 0].min() and disk[:, 0].max() <= x1 and y0 <= disk[:, 1].min() and disk[:, 1].max() <= y1
    for lab in ("healthy data", "new data"):
        pt = next(ln for ln in ax.get_lines() if ln.get_label() == lab)
        assert x0 <= float(np.asarray(pt.get_xdata())[0]) <= x1 and y0 <= float(np.asarray(pt.get_ydata())[0]) <= y1
    assert 2 * out.measured.radius[i, 0] > 0.1 * (x1 - x0) * _unit_of(ax)  # type: ignore[attr-defined]


def _unit_of(ax: object) -> float:
    """m/N per unit of a complex-plane axis, read from its x label ("Re receptance (nm/N)")."""
    from rotorcheck.units import UNITS

    label = ax.get_xlabel()  # type: ignore[attr-defined]
    assert label == ax.get_ylabel().replace("Im", "Re")  # type: ignore[attr-defined]
    return UNITS["receptance"][label.rsplit("(", 1)[1].rstrip(")")]


def test_complex_plane_in_engineering_units_without_offset() -> None:
    """A set far from the origin and small beside it (centre -8.527e-7 m/N, radius 1e-10: ticks read -8.526,
    -8.528 with "1e-7" in a corner before): drawn in nm/N, plain tick labels, no offset text, equal scales,
    the limits as set (no "Ignoring fixed limits" warning), the frame holding the set and the data."""
    import warnings

    from rotorcheck.report.plots import complex_plane_figure

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = complex_plane_figure(50.0, complex(-8.5e-7, -1e-8), complex(-8.527e-7, 0.0), 1e-10,
                                   healthy=complex(-8.5272e-7, 0.3e-10), damaged=complex(-8.5255e-7, 1e-10),
                                   context=FigureContext("r", 0.0), damaged_noise=2e-11)
        FigureCanvasAgg(fig)
        fig.canvas.draw()
    ax = fig.axes[0]
    assert _unit_of(ax) == 1e-9 and ax.get_xlabel() == "Re receptance (nm/N)"
    for axis in (ax.xaxis, ax.yaxis):
        assert axis.get_offset_text().get_text() == ""
        labels = [t.get_text() for t in axis.get_ticklabels() if t.get_text()]
        assert labels and not any("e" in lab.lower() for lab in labels)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x1 - x0 == pytest.approx(y1 - y0)
    assert x0 < -852.72 < -852.55 < x1 and x1 - x0 < 1.0  # both data points (nm/N), framed on the set
    assert any(t.get_gid() == "model_off_frame" for t in ax.texts)  # the model, 10 nm/N away, pointed at
    box = ax.get_window_extent()
    assert box.width == pytest.approx(box.height, rel=1e-3)  # equal scales: a square frame in a square box


def test_frf_unit_scales_the_plots(breathing: tuple) -> None:
    _, out = breathing
    m = workflow.detection_figures(out, frf_unit="m/N")["detection_bode"].axes[0]  # type: ignore[arg-type]
    u = workflow.detection_figures(out, frf_unit="um/N")["detection_bode"].axes[0]  # type: ignore[arg-type]
    assert "(um/N)" in u.get_ylabel() and "(m/N)" in m.get_ylabel()
    ym = next(ln for ln in m.get_lines() if ln.get_label() == "new data").get_ydata()
    yu = next(ln for ln in u.get_lines() if ln.get_label() == "new data").get_ydata()
    np.testing.assert_allclose(np.asarray(yu), 1e6 * np.asarray(ym), rtol=1e-12)
    from rotorcheck.errors import InputError

    with pytest.raises(InputError, match="--frf-unit"):
        workflow.detection_figures(out, frf_unit="in/lbf")  # type: ignore[arg-type]


def test_location_figure_colours_elements_by_status_and_draws_the_intervals() -> None:
    """A location result built here: excluded elements grey, consistent blue, the best red, on the rotor
    drawing's element patches; one bar per consistent element spanning its certified loss interval (%)."""
    from matplotlib.colors import to_rgba

    from rotorcheck.location import CandidateResult, LocationResult
    from rotorcheck.report.plots import location_figure

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    z = np.asarray(cfg.stations, dtype=float)
    status = {el.start: ("consistent" if el.start in (3, 4, 5) else "excluded") for el in cfg.shaft}
    intervals = {3: (0.10, 0.30), 4: (0.40, 0.55), 5: (0.05, 0.60)}
    cands = [CandidateResult(element=e, z_start_m=float(z[e - 1]), z_end_m=float(z[e]), status=s,
                             rank={4: 1, 3: 2, 5: 3}.get(e), loss_interval=intervals.get(e, (np.nan, np.nan)),
                             depth_interval=(0.2, None if e == 5 else 0.3), excluding_frequencies_hz=(50.0,),
                             loss_estimate=float(np.mean(intervals[e])) if e in intervals else None)
             for e, s in status.items()]
    loc = LocationResult(hypothesis="open", healthy_excluded=True, candidates=cands, channels=["s6.x<-s8.x"],
                         points_used=100, z=3.0)
    fig = location_figure(cfg, loc, "title names the sweep")
    ax, bx = fig.axes[0], fig.axes[-1]
    face = {p.get_gid(): p.get_facecolor() for p in ax.patches if str(p.get_gid()).startswith("element ")}
    for e, s in status.items():
        want = "tab:red" if e == 4 else ("tab:blue" if s == "consistent" else "0.8")
        assert np.allclose(face[f"element {e}"], to_rgba(want)), e
    bars = [ln for ln in bx.get_lines() if ln.get_linewidth() == 5]
    assert len(bars) == 3
    spans = sorted((float(np.mean(b.get_xdata())), tuple(np.asarray(b.get_ydata(), dtype=float))) for b in bars)
    for (mid, (lo, hi)), e in zip(spans, (3, 4, 5)):
        assert mid == pytest.approx(0.5 * (z[e - 1] + z[e]))
        assert (lo, hi) == pytest.approx((100 * intervals[e][0], 100 * intervals[e][1]))
    notes = [t.get_text() for t in bx.texts]
    assert "#3\ndepth at least 20 %" in notes and "#1\ndepth 20-30 %" in notes
    assert ax.get_title(loc="left") == "title names the sweep"


def test_validation_figures_name_and_place(breathing: tuple) -> None:
    """The validation Bode and complex plane: titles with rig, speed, channels, sweep and baseline; legends
    outside; the healthy data inside the drawn set at the plotted frequency (the set encloses it)."""
    val, _ = breathing
    figs = workflow.validation_figures(val, baseline_path="out/baseline.h5")  # type: ignore[arg-type]
    assert set(figs) == set(workflow.PLOT_STEMS_VALIDATE)
    for fig in figs.values():
        title = fig.axes[0].get_title()
        for part in ("Validation" if fig is figs["validation_bode"] else "Complex plane", "crack_rig",
                     "at 1000 rpm", "s6.x <- s8.x", "healthy_1000rpm.h5", "out/baseline.h5"):
            assert part in title, (part, title)
        _legend_outside_axes(fig)
    ax = figs["validation_complex_plane"].axes[0]
    disk = ax.patches[0].get_path().vertices
    centre = disk.mean(axis=0)
    radius = np.max(np.hypot(*(disk - centre).T))
    healthy = next(ln for ln in ax.get_lines() if ln.get_label() == "healthy data")
    hx, hy = float(np.asarray(healthy.get_xdata())[0]), float(np.asarray(healthy.get_ydata())[0])
    assert np.hypot(hx - centre[0], hy - centre[1]) <= radius * (1 + 1e-6)


@pytest.fixture(scope="module")
def repeat_healthy(sample_pipeline: Callable[..., tuple[object, object]]) -> tuple[object, object]:
    """The repeat healthy sweep at 1000 rpm against the measured baseline of ``breathing`` (a healthy shaft)."""
    return sample_pipeline(configs_dir() / "crack_rig.yaml", CR / "healthy_1000rpm.h5",
                           CR / "healthy_1000rpm_repeat.h5", "measured")


def _estimate_lines(ax: object) -> list:
    return [ln for ln in ax.get_lines() if ln.get_color() == "tab:red"]  # type: ignore[attr-defined]


def test_report_figures_raise_no_warning(breathing: tuple, repeat_healthy: tuple, three_mass: tuple,
                                         tmp_path: Path) -> None:
    """Every validation and detection figure built and saved with warnings as errors (matplotlib's "Ignoring
    fixed x limits to fulfill fixed data aspect" came on every validate and detect; a joint statistic of 0
    on a log axis warned too)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for k, (val, out) in enumerate((breathing, repeat_healthy, three_mass)):
            written = workflow.validation_plots(val, tmp_path / str(k))  # type: ignore[arg-type]
            written += workflow.detection_plots(out, tmp_path / str(k), show_nominal_damage=True)  # type: ignore[arg-type]
            assert len(written) == 6
        fig = decision_figure_with_joint(0.0, 8.0)  # a statistic of 0
        FigureCanvasAgg(fig)
        fig.canvas.draw()


def decision_figure_with_joint(t: float, threshold: float) -> Figure:
    from rotorcheck.report.plots import decision_figure

    f = np.linspace(10.0, 100.0, 20)
    ratio = np.linspace(0.2, 0.9, 20)
    return decision_figure(f, ratio, np.zeros(20, dtype=bool), np.full(20, "ok"), FigureContext("r", 0.0),
                           "healthy" if t <= threshold else "damage", "joint test",
                           joint={"statistic": t, "threshold": threshold, "p_value": 0.5, "false_alarm": 0.01})


@pytest.mark.parametrize(("t", "threshold", "scale"), [(0.0, 8.0, "linear"), (17.1, 8.4, "linear"),
                                                      (5.2e4, 8.4, "symlog")])
def test_joint_panel_is_a_dot_against_its_threshold(t: float, threshold: float, scale: str) -> None:
    """The sweep's statistic as a dot at T (0 included, on the axis), the threshold a dashed line at its value,
    both inside the x limits; linear unless T is over 20 thresholds (then symlog, linear up to the threshold)."""
    fig = decision_figure_with_joint(t, threshold)
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    bx = fig.axes[1]
    lines = {ln.get_gid(): ln for ln in bx.get_lines()}
    x_t = float(np.asarray(lines["joint_statistic"].get_xdata())[0])
    assert x_t == t and np.allclose(lines["joint_threshold"].get_xdata(), threshold)
    x0, x1 = bx.get_xlim()
    assert x0 <= min(t, 0.0) and max(t, threshold) < x1
    assert bx.get_xscale() == scale
    assert not bx.patches or all(p.get_width() > 0 for p in bx.patches if hasattr(p, "get_width"))


def test_damage_figure_hides_the_nominal_estimate_by_default(breathing: tuple) -> None:
    """The anchored D_u leads; the nominal-E22 D_u (model error, not to be read) is absent by default and, when
    asked for, the thinnest line, grey and dashed, never red."""
    _, out = breathing
    hidden = workflow.detection_figures(out)["damage_dynamics"].axes[0]  # type: ignore[arg-type]
    assert not any("nominal E22" in str(ln.get_label()) for ln in hidden.get_lines())
    shown = workflow.detection_figures(out, show_nominal_damage=True)["damage_dynamics"].axes[0]  # type: ignore[arg-type]
    nominal = next(ln for ln in shown.get_lines() if "nominal E22" in str(ln.get_label()))
    np.testing.assert_allclose(np.asarray(nominal.get_ydata()), np.abs(out.damage))  # type: ignore[attr-defined]
    widths = [ln.get_linewidth() for ln in shown.get_lines() if ln is not nominal and ln.get_linestyle() != "None"]
    assert nominal.get_linewidth() < min(widths) and nominal.get_linestyle() == "--"
    assert nominal.get_color() == "0.55"


def test_damage_figure_of_a_healthy_shaft_draws_no_estimate(repeat_healthy: tuple) -> None:
    """The repeat healthy sweep: D_u's bound holds 0 at every frequency, so no estimate is drawn (magnitude or
    phase), the figure says NOT SIGNIFICANT and the phase panel says why it is empty."""
    _, out = repeat_healthy
    a = out.anchored_set  # type: ignore[attr-defined]
    assert not np.any(np.asarray(a.min_abs) > 0)  # the premise: nothing significant (the report's bound)
    fig = workflow.detection_figures(out)["damage_dynamics"]  # type: ignore[arg-type]
    ax_m, ax_p = fig.axes[:2]
    for ax in (ax_m, ax_p):
        for ln in _estimate_lines(ax):
            assert not np.any(np.isfinite(np.asarray(ln.get_ydata(), dtype=float)))
    assert any(t.get_gid() == "not_significant" for t in ax_m.texts)
    assert any("phase not shown" in t.get_text() for t in ax_p.texts)


def test_damage_phase_unwrapped_where_significant_and_axis_fitted() -> None:
    """D_u with a phase ramp over three turns (-540..+540 deg), significant except between 40 and 50 Hz: the
    drawn phase is the ramp itself (closed form) up to a whole turn per run, with no jump over 180 deg between
    neighbours; NaN where not significant; the axis spans the drawn phase and its band, not +-200 deg."""
    f = np.linspace(10.0, 100.0, 181)
    ramp = np.linspace(-540.0, 540.0, f.size)
    d = 4e3 * np.exp(1j * np.radians(ramp))
    sig = ~((f > 40.0) & (f < 50.0))
    lo = np.where(sig, 3e3, 0.0)
    fig = damage_dynamics_figure(f, d, lo, np.full(f.size, 5e3), np.degrees(np.angle(d)) - 5.0,
                                 np.degrees(np.angle(d)) + 5.0, context=FigureContext("r", 0.0))
    ax_p = fig.axes[1]
    ph = np.asarray(_estimate_lines(ax_p)[0].get_ydata(), dtype=float)
    assert np.array_equal(np.isfinite(ph), sig)
    for run in (f <= 40.0, f >= 50.0):
        turns = (ph[run] - ramp[run]) / 360.0
        np.testing.assert_allclose(turns, np.round(turns[0]), atol=1e-9)  # the ramp, one whole-turn shift per run
        assert np.max(np.abs(np.diff(ph[run]))) < 10.0
    lo_y, hi_y = ax_p.get_ylim()
    band = [c for c in ax_p.collections if c.get_facecolor().size]
    verts = np.concatenate([p.vertices for c in band for p in c.get_paths()])
    assert lo_y <= min(np.nanmin(ph), verts[:, 1].min()) and max(np.nanmax(ph), verts[:, 1].max()) <= hi_y
    assert hi_y - lo_y < 1.3 * (max(np.nanmax(ph), verts[:, 1].max()) - min(np.nanmin(ph), verts[:, 1].min())) + 25
    # the band follows its estimate's turn: every band vertex within 5 deg (+ rounding) of the drawn phase
    x_ph = f[sig]
    near = np.interp(verts[:, 0], x_ph, ph[sig])
    assert np.max(np.abs(verts[:, 1] - near)) < 5.0 + 1e-6


def test_bode_phase_axis_fitted_to_the_data(breathing: tuple) -> None:
    """Detection Bode of the breathing crack: data in about -185..0 deg; the phase axis holds every drawn
    point and spans at most the drawn range plus 10 % and 2 x 10 deg (it spanned -350..+200 before)."""
    _, out = breathing
    ax_p = workflow.detection_figures(out)["detection_bode"].axes[1]  # type: ignore[arg-type]
    y = np.concatenate([np.asarray(ln.get_ydata(), dtype=float) for ln in ax_p.get_lines()])
    lo, hi = ax_p.get_ylim()
    assert lo <= np.nanmin(y) and np.nanmax(y) <= hi
    span = np.nanmax(y) - np.nanmin(y)
    assert 150.0 < span < 260.0 and hi - lo <= 1.2 * span + 20.0 + 1e-9


def test_amplitude_and_phase_labels_state_their_convention(breathing: tuple) -> None:
    """Wherever an amplitude or a phase is drawn its axis says 0-peak (the sweep's phasors are peak values,
    sweep-format.md) and the phase's sense."""
    _, out = breathing
    figs = workflow.detection_figures(out)  # type: ignore[arg-type]
    for stem in ("detection_bode", "damage_dynamics"):
        ax_m, ax_p = figs[stem].axes[:2]
        assert "0-peak" in ax_m.get_ylabel(), stem
        assert "+ =" in ax_p.get_ylabel() and "leads" in ax_p.get_ylabel(), stem
