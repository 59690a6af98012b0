"""Crack figures (Fig. 56-58): built with the Figure API, plotted data checked."""

from __future__ import annotations

import io

import numpy as np
from faults_helpers import RIG_CRACK

from rotorcheck.config import UnbalanceMass
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.report.crack_plots import (
    crack_figures,
    orbit_figure,
    spectrum_figure,
    stiffness_change_figure,
)


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def test_stiffness_figure_fig56() -> None:
    fig = stiffness_change_figure(RIG_CRACK)
    ax = fig.axes[0]
    xi, eta = (line.get_ydata() for line in ax.lines[:2])
    deg = ax.lines[0].get_xdata()
    assert xi[0] == 1.0 and eta[0] == 1.0  # closed at 0 deg
    i = int(np.argmin(xi))
    assert deg[i] == 180.0
    assert round(float(xi.min()), 3) == 0.478 and round(float(eta.min()), 3) == 0.854
    assert _png(fig).startswith(b"\x89PNG")


def test_orbit_and_spectrum_figures_plot_their_data() -> None:
    t = np.linspace(0, 2 * np.pi, 50)
    xy = 5e-6 * np.c_[np.cos(t), np.sin(t)]
    fig = orbit_figure({"healthy": xy, "cracked": 1.1 * xy})
    assert np.allclose(fig.axes[0].lines[0].get_xdata(), 1e6 * xy[:, 0])
    panels = [
        {"title": "a", "speed_rpm": 1000.0, "orders": [1, 2], "amp": [7e-6, 3e-7], "scale": "log"},
        {"title": "b", "speed_rpm": 750.0, "orders": [1, 2], "amp": np.array([[4e-6, 4e-6], [1e-7, 2e-7]]),
         "scale": "linear"},
    ]
    fig = spectrum_figure(panels)
    main = [ax for ax in fig.axes if ax.get_ylabel()]
    assert len(main) == 2
    assert main[0].get_yscale() == "log" and "log scale" in main[0].get_ylabel()
    assert "linear scale" in main[1].get_ylabel()
    assert [t.get_text() for t in main[0].get_xticklabels()] == ["1X", "2X"]
    assert np.allclose(main[1].lines[1].get_ydata(), [4.0, 0.2])
    assert _png(fig).startswith(b"\x89PNG")


def test_crack_figures_from_the_rig(rig_system: MechanicalSystem) -> None:
    ub = [UnbalanceMass(station=3, amount=0.2e-3, phase=-np.pi / 2)]
    out = crack_figures(rig_system, RIG_CRACK, ub)
    data = out["data"]
    healthy = data["healthy, 1000 rpm"]["amp"]
    cracked = data["cracked, 1000 rpm"]["amp"]
    assert np.all(healthy[1:] <= 1e-12 * healthy[0])
    assert np.all(cracked[1:3] > 0.01 * cracked[0])
    assert len([ax for ax in out["spectrum"].axes if ax.get_ylabel()]) == 2  # one panel per speed
    assert [ax.get_title() for ax in out["orbit"].axes] == ["1000 rpm", "750 rpm"]
    for key in ("stiffness", "orbit", "spectrum"):
        assert _png(out[key]).startswith(b"\x89PNG")
