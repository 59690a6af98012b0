"""Model figures (issue 14): Campbell, mode shapes, crack illustration and rotor drawing, checked by
their artists: labels and units, titles, label overlaps, legend placement, markers at the right places."""

from __future__ import annotations

import itertools
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Annotation, Text

from rotorcheck.config import RigConfig, UnbalanceMass, load_config
from rotorcheck.errors import InputError
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import campbell, model_summary, modes
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.report.campbell import WHIRL_STYLE, campbell_figure, order_criticals
from rotorcheck.report.crack_plots import crack_figures
from rotorcheck.report.rotor_drawing import boxes_overlap, text_extent
from rotorcheck.workflow import model_report
from tests.report.figure_checks import mode_shapes_fig, rotor_fig

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
RIGS = ("crack_rig", "overhung_rig", "compressor_rig")
OPERATING = {"crack_rig": 1000.0, "overhung_rig": 1500.0, "compressor_rig": 6000.0}


@cache
def rig(name: str) -> tuple[RigConfig, MechanicalSystem]:
    config = load_config(CONFIGS / f"{name}.yaml")
    return config, build_system(config)


@cache
def campbell_of(name: str) -> tuple[object, dict[int, tuple[tuple[float, ...], tuple[int, ...]]]]:
    config, system = rig(name)
    camp = campbell(system, np.linspace(0.0, config.analysis.campbell_max_rpm, 41), config.analysis.n_modes)
    return camp, order_criticals(system, camp, (1, 2))


def drawn(fig: Figure) -> Figure:
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig


def labels_of(fig: Figure) -> list[Text]:
    """Every free text of the figure's axes (annotations and texts; tick labels excluded)."""
    return [t for ax in fig.axes for t in ax.texts if t.get_visible() and t.get_text()]


def assert_no_overlap(texts: list[Text]) -> None:
    boxes = [(t.get_text(), text_extent(t)) for t in texts]
    for (a, ba), (b, bb) in itertools.combinations(boxes, 2):
        assert not boxes_overlap(ba, bb, pad=0.0), f"labels {a!r} and {b!r} overlap"


#: brute_criticals' forward frequencies on its grid, per (id of a system of rig(), max rpm, branches)
_GRID_MODES: dict[tuple[int, float, int], list[np.ndarray]] = {}


def brute_criticals(system: MechanicalSystem, max_rpm: float, order: int, n_branches: int) -> list[float]:
    """Independent reference: forward modes by frequency on a fine grid, sign changes of
    f_k(rpm) - order rpm / 60 bisected to 1e-4 rpm (the tests compare at 0.5 rpm: 5000 times coarser; the
    50 halvings used before went to round-off, 1e-12 rpm, at 2.5 times the modal solves)."""

    def forward(rpm: float) -> np.ndarray:
        md = modes(system, rpm, n_modes=2 * n_branches)
        return np.array([f for f, w in zip(md.frequency_hz, md.whirl) if w == "forward"])

    grid = np.linspace(50.0, max_rpm, 81)
    key = (id(system), max_rpm, n_branches)  # the grid's modes are the same for every order: solved once
    vals = _GRID_MODES[key] if key in _GRID_MODES else _GRID_MODES.setdefault(key, [forward(s) for s in grid])
    k_max = min(len(v) for v in vals)
    out = []
    for k in range(k_max):
        g = np.array([v[k] for v in vals]) - order * grid / 60.0
        for i in np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]:
            lo, hi = grid[i], grid[i + 1]
            while hi - lo > 1e-4:
                mid = 0.5 * (lo + hi)
                if np.sign(forward(mid)[k] - order * mid / 60.0) == np.sign(g[i]):
                    lo = mid
                else:
                    hi = mid
            out.append(0.5 * (lo + hi))
    return sorted(out)


@cache
def campbell_fig(name: str, speed_unit: str = "rpm") -> Figure:
    """The drawn Campbell figure of ``name``, built once per module run (the tests read its artists only)."""
    config, _ = rig(name)
    camp, crit = campbell_of(name)
    return drawn(campbell_figure(camp, (1, 2), rig_id=config.rig_id, operating_speed_rpm=OPERATING[name],
                                 speed_unit=speed_unit, criticals=crit))


def lines_by_gid(fig: Figure, prefix: str) -> list:
    return [ln for ax in fig.axes for ln in ax.get_lines() if str(ln.get_gid()).startswith(prefix)]


# -------------------------------------------------------------------------------------------- Campbell


@pytest.mark.parametrize("name", RIGS)
def test_campbell_labels_legend_and_title(name: str) -> None:
    fig = campbell_fig(name)
    ax, dx = fig.axes[:2]
    assert name in fig.get_suptitle() and f"{OPERATING[name]:.0f} rpm" in fig.get_suptitle()
    assert ax.get_ylabel() == "damped natural frequency (Hz)"
    assert "(%)" in dx.get_ylabel() and dx.get_xlabel() == "spin speed (rpm)"
    texts = labels_of(fig)
    assert_no_overlap(texts)
    # the legend is outside the data: no data point of any line lies in its box
    legend = fig.legends[0].get_window_extent()
    for a in (ax, dx):
        for ln in a.get_lines():
            if str(ln.get_gid()).startswith(("branch", "damping", "order", "critical")):
                pts = a.transData.transform(np.c_[ln.get_xdata(), ln.get_ydata()])
                pts = pts[np.all(np.isfinite(pts), axis=1)]
                assert not any(legend.contains(*p) for p in pts), ln.get_gid()
    # 1X and 2X labels inside the axes
    box = ax.get_window_extent()
    for n in (1, 2):
        (t,) = [t for t in ax.texts if t.get_gid() == f"order label {n}X"]
        assert t.get_text() == f"{n}X"
        tb = text_extent(t)
        assert box.x0 <= tb.x0 and tb.x1 <= box.x1 and box.y0 <= tb.y0 and tb.y1 <= box.y1
    # every branch labelled (number and whirl)
    camp, _ = campbell_of(name)
    names = {t.get_text() for t in ax.texts if str(t.get_gid()).startswith("label ")}
    assert names == {f"{b + 1}{w[0].upper()}" for b, w in enumerate(camp.branch_whirl)}


def test_campbell_forward_and_backward_both_visible() -> None:
    fig = campbell_fig("crack_rig")
    fwd = lines_by_gid(fig, "branch")
    f_lines = [ln for ln in fwd if ln.get_gid().endswith("forward")]
    b_lines = [ln for ln in fwd if ln.get_gid().endswith("backward")]
    assert f_lines and b_lines
    assert {ln.get_color() for ln in f_lines}.isdisjoint({ln.get_color() for ln in b_lines})
    assert {ln.get_linestyle() for ln in f_lines}.isdisjoint({ln.get_linestyle() for ln in b_lines})
    assert min(ln.get_zorder() for ln in b_lines) > max(ln.get_zorder() for ln in f_lines)
    assert WHIRL_STYLE["backward"]["zorder"] > WHIRL_STYLE["forward"]["zorder"]
    # damping panel: one curve per branch, in %
    camp, _ = campbell_of("crack_rig")
    damp = lines_by_gid(fig, "damping")
    assert {int(ln.get_gid().split()[1]) for ln in damp} == set(range(1, camp.frequency_hz.shape[1] + 1))
    assert np.isclose(np.nanmax(np.concatenate([ln.get_ydata() for ln in damp])),
                      100 * np.nanmax(camp.damping_ratio))


@pytest.mark.parametrize("name", ["crack_rig", "overhung_rig"])
def test_campbell_critical_markers_match_an_independent_solver(name: str) -> None:
    config, system = rig(name)
    camp, _ = campbell_of(name)
    fig = campbell_fig(name)
    for n in (1, 2):
        (marks,) = lines_by_gid(fig, f"critical {n}X")
        ref = brute_criticals(system, config.analysis.campbell_max_rpm, n, camp.frequency_hz.shape[1])
        assert len(ref) >= 1
        np.testing.assert_allclose(sorted(marks.get_xdata()), ref, atol=0.5)
        np.testing.assert_allclose(marks.get_ydata(), n * np.asarray(marks.get_xdata()) / 60.0)
        labels = [t.get_text() for t in fig.axes[0].texts if t.get_gid() == f"critical label {n}X"]
        assert len(labels) == len(ref) and all(f"{n}X" in s for s in labels)


def test_campbell_operating_speed_and_hz_unit() -> None:
    fig = campbell_fig("crack_rig", "rpm")
    ops = lines_by_gid(fig, "operating speed")
    assert len(ops) == 2 and all(np.allclose(ln.get_xdata(), 1000.0) for ln in ops)
    fig = campbell_fig("crack_rig", "Hz")
    ops = lines_by_gid(fig, "operating speed")
    assert all(np.allclose(ln.get_xdata(), 1000.0 / 60.0) for ln in ops)
    assert fig.axes[1].get_xlabel() == "spin speed (Hz)" and fig.axes[0].get_ylabel().endswith("(Hz)")
    _, crit = campbell_of("crack_rig")
    (marks,) = lines_by_gid(fig, "critical 1X")
    np.testing.assert_allclose(marks.get_xdata(), np.asarray(crit[1][0]) / 60.0)
    np.testing.assert_allclose(marks.get_ydata(), np.asarray(crit[1][0]) / 60.0)  # 1X: f = speed in Hz
    assert fig.axes[0].get_xlim()[1] == pytest.approx(10000.0 / 60.0)
    assert "16.67 Hz" in fig.get_suptitle()
    assert_no_overlap(labels_of(fig))
    with pytest.raises(ValueError, match="speed_unit"):
        campbell_figure(campbell_of("crack_rig")[0], speed_unit="rad/s")


# -------------------------------------------------------------------------------------------- mode shapes


@pytest.mark.parametrize(("name", "speed"), [("crack_rig", 0.0), ("crack_rig", 1000.0), ("compressor_rig", 6000.0)])
def test_mode_shapes_are_the_tables_modes(name: str, speed: float) -> None:
    config, _ = rig(name)
    table = model_summary(config, speed)["modes"]
    fig = mode_shapes_fig(name, speed)  # mode_shape_figure(system, speed, config=config), shared (figure_checks)
    panels = [ax for ax in fig.axes if lines_by_gid_ax(ax, "shape")]
    assert len(panels) == len(table)
    for i, (ax, row) in enumerate(zip(panels, table)):
        title = ax.get_title(loc="left")
        assert title.startswith(f"mode {i + 1}: {row['frequency_hz']:.2f} Hz"), title
    assert all("normalised deflection" in ax.get_ylabel() for ax in panels[::2])
    assert config.rig_id in fig.get_suptitle()
    assert ("standstill" if speed == 0 else f"{speed:g} rpm") in fig.get_suptitle()


def lines_by_gid_ax(ax, prefix: str) -> list:
    return [ln for ln in ax.get_lines() if str(ln.get_gid()).startswith(prefix)]


def test_mode_shapes_mark_the_rigs_parts_and_split_degenerate_pairs() -> None:
    config, system = rig("crack_rig")
    fig = mode_shapes_fig("crack_rig", 0.0)  # the figure of test_mode_shapes_are_the_tables_modes[crack_rig-0.0]
    z = system.station_positions
    panels = [ax for ax in fig.axes if lines_by_gid_ax(ax, "shape")]
    for ax in panels:
        def xs(gid: str, ax=ax) -> set[float]:
            return {round(float(np.ravel(ln.get_xdata())[0]), 9) for ln in lines_by_gid_ax(ax, gid)}

        assert xs("sensor") == {round(float(z[config.ports.sensor.station - 1]), 9)}
        assert xs("actuator") == {round(float(z[config.ports.actuator.station - 1]), 9)}
        assert xs("bearing") == {round(float(z[b.station - 1]), 9) for b in config.bearings}
        assert xs("disc") == {round(float(z[d.station - 1]), 9) for d in config.discs}
        crack = [p for p in ax.patches if p.get_gid() == "crack"]
        assert crack  # the damage element (4)
    # a degenerate pair at rest: mode 1 pure x plane, mode 2 pure y plane
    for i, plane in ((0, "x"), (1, "y"), (2, "x"), (3, "y")):
        (x_line,) = lines_by_gid_ax(panels[i], f"shape {i + 1} x")
        (y_line,) = lines_by_gid_ax(panels[i], f"shape {i + 1} y")
        own, other = (x_line, y_line) if plane == "x" else (y_line, x_line)
        assert np.max(np.abs(own.get_ydata())) == pytest.approx(1.0, rel=1e-2)  # 1 at a station
        assert np.max(np.abs(other.get_ydata())) < 1e-8
        assert f"{plane} plane" in panels[i].get_title(loc="left")


# -------------------------------------------------------------------------------------------- crack plots


def test_crack_figures_both_speeds_arrows_and_order_ticks() -> None:
    config = load_config(CONFIGS / "crack_rig_truth.yaml")
    system = build_system(config)
    crack = config.faults["breathing_crack"]
    unb = [UnbalanceMass(station=3, amount=0.2e-3, phase=-np.pi / 2)]
    out = crack_figures(system, crack, unb, station=6, speeds_rpm=(1000.0, 750.0), rig_id=config.rig_id)
    orbit = drawn(out["orbit"])
    assert [ax.get_title() for ax in orbit.axes] == ["1000 rpm", "750 rpm"]
    assert "crack_rig" in orbit.get_suptitle() and "station 6" in orbit.get_suptitle()
    for ax in orbit.axes:
        arrows = [t for t in ax.texts if isinstance(t, Annotation) and t.arrow_patch is not None]
        assert len(arrows) == 2  # healthy and cracked: direction of travel
        assert "(um)" in ax.get_xlabel() and "(um)" in ax.get_ylabel()
        assert {ln.get_gid() for ln in ax.get_lines()} >= {"start healthy", "start cracked"}
    legend = [t.get_text() for t in orbit.legends[0].get_texts()]
    assert any(s.startswith("start") for s in legend) and "direction of travel" in legend
    spec = drawn(out["spectrum"])
    main_axes = [ax for ax in spec.axes if ax.get_ylabel()]
    assert len(main_axes) == 2
    for ax, speed in zip(main_axes, (1000.0, 750.0)):
        assert "log scale" in ax.get_ylabel() and ax.get_yscale() == "log"
        assert [t.get_text() for t in ax.get_xticklabels()] == ["1X", "2X", "3X", "4X", "5X"]
        assert f"{speed:g} rpm" in ax.get_title(loc="left")
    assert "crack_rig" in spec.get_suptitle()
    for key in ("orbits_1000rpm", "orbits_750rpm", "cracked, 750 rpm", "healthy, 1000 rpm"):
        assert key in out["data"]


# -------------------------------------------------------------------------------------------- rotor drawing


@pytest.mark.parametrize("name", [*RIGS, "crack_rig_truth"])
def test_rotor_drawing(name: str) -> None:
    config = load_config(CONFIGS / f"{name}.yaml")
    fig = drawn(rotor_fig(name))  # rotor_figure(config), shared with test_figure_layout.py (figure_checks)
    ax = fig.axes[0]
    z = np.asarray(config.stations)
    patches = {p.get_gid(): p for p in ax.patches}
    for k in range(1, z.size):
        verts = patches[f"element {k}"].get_path().vertices
        assert verts[:, 0].min() == pytest.approx(z[k - 1]) and verts[:, 0].max() == pytest.approx(z[k])
    for d in config.discs:
        ext = patches[f"disc {d.name}"].get_bbox()
        assert 0.5 * (ext.x0 + ext.x1) == pytest.approx(z[d.station - 1])
        if d.outer_diameter is not None:
            assert ext.y1 == pytest.approx(0.5 * d.outer_diameter)
    for b in config.bearings:
        verts = patches[f"bearing {b.name}"].get_xy()
        assert verts[0][0] == pytest.approx(z[b.station - 1])  # the apex under the station
        assert verts[0][1] < 0
    texts = {t.get_gid(): t for t in ax.texts}
    if config.ports is not None:
        s, a = config.ports.sensor, config.ports.actuator
        assert texts[f"sensor s{s.station}{s.direction}"].xy[0] == pytest.approx(z[s.station - 1])
        assert texts[f"actuator f{a.station}{a.direction}"].xy[0] == pytest.approx(z[a.station - 1])
    assert_no_overlap([t for t in ax.texts if t.get_text()])
    assert name.replace("_truth", "") in ax.get_title()
    assert ax.get_legend() is not None and not boxes_overlap(ax.get_legend().get_window_extent(),
                                                            ax.get_window_extent(), pad=0.0)


def test_rotor_drawing_taper_and_layers() -> None:
    ax = rotor_fig("compressor_rig").axes[0]  # rotor_figure of configs/compressor_rig.yaml, shared (figure_checks)
    patches = {p.get_gid(): p for p in ax.patches}
    verts = patches["element 10"].get_path().vertices  # impeller fit: 90 -> 70 mm
    left = verts[np.isclose(verts[:, 0], 0.80)][:, 1]
    right = verts[np.isclose(verts[:, 0], 0.86)][:, 1]
    assert left.max() == pytest.approx(0.045) and right.max() == pytest.approx(0.035)
    assert left.min() == pytest.approx(-0.045) and right.min() == pytest.approx(-0.035)
    sleeve = patches["layer 9"].get_path().vertices  # 110 / 90 mm sleeve: two wall bands
    assert np.abs(sleeve[:, 1]).max() == pytest.approx(0.055) and np.abs(sleeve[:, 1]).min() == pytest.approx(0.045)
    assert "crack 10" in patches  # the damage element and the open-crack fault


def test_model_report_writes_the_rotor_drawing(tmp_path: Path) -> None:
    out = model_report(CONFIGS / "overhung_rig.yaml", 1500.0, out_dir=tmp_path, speed_unit="Hz")
    assert sorted(Path(f).name for f in out["files"]) == ["campbell.png", "mode_shapes.png", "rotor.png"]
    with pytest.raises(InputError, match="--speed-unit"):
        model_report(CONFIGS / "overhung_rig.yaml", 0.0, speed_unit="rad/s")
