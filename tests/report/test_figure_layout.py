"""Issue 31: the drawings' labels apart and inside the figure, checked on the rendered text boxes.

Every text the Agg canvas draws (tick labels, axis labels, titles, legends, annotations, colour bars) is
collected with its box in display pixels after ``canvas.draw()``; no two of them may overlap and none may
reach beyond the figure. The figures: the rotor drawing of every bundled rotor rig, the detectability figure
with many ports at neighbouring stations (labels at stations 6, 7 and 8 collided before), the location
figure, the mode shapes under the drawing and the breathing-crack stiffness figure (its title was cut at the
right edge). Each is built with every warning an error (matplotlib warned "Ignoring fixed x limits ...").
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from rotorcheck.config import RigConfig, load_config
from rotorcheck.detectability import Detectability, ElementDetectability
from rotorcheck.location import CandidateResult, LocationResult
from rotorcheck.resources import configs_dir
from tests.report.figure_checks import drawn_texts, mode_shapes_fig, overlapping_texts, rotor_fig, texts_outside

RIGS = ("crack_rig", "overhung_rig", "compressor_rig", "crack_rig_truth")


def _detectability(cfg: RigConfig, sensors: tuple[str, ...], actuators: tuple[str, ...]) -> Detectability:
    """A detectability result with depths stated here (the figure's layout is under test, not the numbers);
    element 9 not seen (grey)."""
    z = np.asarray(cfg.stations, dtype=float)
    els = [ElementDetectability(e, float(z[e - 1]), float(z[e]), 0.05, 0.01, 0.008,
                                None if e == 9 else 0.02 * e, 0.01, 0.009) for e in range(1, z.size)]
    return Detectability(cfg.rig_id, 1000.0, 0.01, sensors, actuators, "stated noise: output sigma 2e-09 m",
                         True, els, 1.0)


def _location(cfg: RigConfig) -> LocationResult:
    """Five consistent neighbours, the first three ranked (their labels stack over adjacent bars)."""
    z = np.asarray(cfg.stations, dtype=float)
    cons = (2, 3, 4, 5, 6)
    cands = [CandidateResult(element=e, z_start_m=float(z[e - 1]), z_end_m=float(z[e]),
                             status="consistent" if e in cons else "excluded",
                             rank=cons.index(e) + 1 if e in cons else None,
                             loss_interval=(0.05 + 0.03 * e, 0.3 + 0.05 * e) if e in cons else (np.nan, np.nan),
                             depth_interval=(0.2, 0.3), excluding_frequencies_hz=(50.0,),
                             loss_estimate=0.2 + 0.04 * e if e in cons else None)
             for e in range(1, z.size)]
    return LocationResult(hypothesis="open", healthy_excluded=True, candidates=cands, channels=["s6.x<-s8.x"],
                          points_used=100, z=3.0)


def _rotor(name: str) -> Figure:
    return rotor_fig(name)  # rotor_figure of the bundled config, shared with test_model_figures.py (figure_checks)


@cache
def _detectability_many_ports() -> Figure:
    """Built once for the two tests that check it (every warning an error while building, as in the first)."""
    from rotorcheck.report.plots import detectability_figure

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return detectability_figure(cfg, _detectability(cfg, ("6x", "6y", "7x", "2x", "2y"), ("8x", "8y", "7y")))


def _location_figure() -> Figure:
    from rotorcheck.report.plots import location_figure

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    loc = _location(cfg)
    return location_figure(cfg, loc, f"open_crack_0rpm.h5: {loc.summary()}")


def _mode_shapes() -> Figure:
    return mode_shapes_fig("compressor_rig", 6000.0)  # shared with test_model_figures.py (figure_checks)


def _crack_stiffness() -> Figure:
    from rotorcheck.config import Crack
    from rotorcheck.report.crack_plots import stiffness_change_figure

    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    crack = cfg.faults["breathing_crack"]
    assert isinstance(crack, Crack)
    return stiffness_change_figure(crack, title="crack_rig breathing crack stiffness over one revolution: "
                                   "mayes_davies crack in element 4")


FIGURES: dict[str, Callable[[], Figure]] = {
    **{f"rotor {name}": (lambda n=name: _rotor(n)) for name in RIGS},  # type: ignore[misc]
    "detectability, 8 ports at stations 2 and 6-8": _detectability_many_ports,
    "location, 3 ranked neighbours": _location_figure,
    "mode shapes under the drawing": _mode_shapes,
    "crack stiffness": _crack_stiffness,
}


@pytest.mark.parametrize("name", list(FIGURES))
def test_texts_do_not_overlap_and_stay_inside(name: str, tmp_path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = FIGURES[name]()
        fig.savefig(tmp_path / "fig.png", dpi=150)
        boxes = drawn_texts(fig)  # drawn after saving: at the figure's own dpi, as the checks below see it
    assert len(boxes) > 10  # tick labels, axis labels, titles, legend, annotations: the check sees them
    assert overlapping_texts(fig, boxes) == [], name
    assert texts_outside(fig, boxes=boxes) == [], name


def test_port_labels_sit_above_their_ports_inside_the_drawing() -> None:
    """The stacked port labels of the detectability figure: each over its own station (x of its arrow's tip
    within the label's box), above the drawing's top, inside the axes."""
    from rotorcheck.report.rotor_drawing import drawing_extent, text_extent

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    fig = _detectability_many_ports()
    drawn_texts(fig)
    ax = fig.axes[0]
    box = ax.get_window_extent()
    ports = [t for t in ax.texts if str(t.get_gid()).split(" ")[0] in ("sensor", "actuator", "damage")]
    assert len(ports) == 9  # 5 sensors, 3 actuators, the damage port
    top = ax.transData.transform((0.0, drawing_extent(cfg)))[1]
    for t in ports:
        b = text_extent(t)
        tip = ax.transData.transform(t.xy)
        assert b.x0 <= tip[0] <= b.x1 or abs(0.5 * (b.x0 + b.x1) - tip[0]) < b.width  # over its port (or nudged in)
        assert b.y0 > top and b.y1 <= box.y1 and b.x0 >= box.x0 and b.x1 <= box.x1
        assert t.xy[0] == pytest.approx(cfg.stations[int(t.get_text()[1:-1]) - 1])
