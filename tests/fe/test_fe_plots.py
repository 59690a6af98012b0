"""Campbell and mode-shape figures (Figure API) and the atomic PNG/PDF writer."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import campbell
from rotorcheck.report.campbell import campbell_figure, interpolated_shape, mode_shape_figure
from rotorcheck.report.figures import save_figure


def test_campbell_and_mode_shape_figures(crack_rig, tmp_path: Path) -> None:
    sys_ = build_system(crack_rig)
    camp = campbell(sys_, np.linspace(0, 10000, 11), 6)
    fig = campbell_figure(camp, rig_id=crack_rig.rig_id)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    colors = {line.get_color() for line in ax.get_lines()}
    assert {"tab:red", "tab:blue"} <= colors  # forward and backward distinguished
    written = save_figure(fig, tmp_path / "sub" / "campbell")
    assert [p.name for p in written] == ["campbell.png", "campbell.pdf"]
    assert written[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert written[1].read_bytes()[:5] == b"%PDF-"
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["campbell.pdf", "campbell.png"]
    fig2 = mode_shape_figure(sys_, 0.0, 3)
    assert len(fig2.axes) == 3  # the table's 3 lowest modes (a degenerate pair as its x and y planes)
    fig3 = mode_shape_figure(sys_, 0.0, config=crack_rig)
    assert len([a for a in fig3.axes if a.get_title(loc="left").startswith("mode")]) == crack_rig.analysis.n_modes
    save_figure(fig2, tmp_path / "modes.png")  # a suffix on the stem is replaced
    assert (tmp_path / "modes.pdf").exists()


def test_interpolated_shape_passes_through_nodes(crack_rig) -> None:
    sys_ = build_system(crack_rig)
    from rotorcheck.fe.modal import modes

    shape = modes(sys_, 0.0, 1).shapes[:, 0]
    z, w = interpolated_shape(sys_, shape, "x")
    for node, zn in enumerate(sys_.node_positions):
        k = np.argmin(np.abs(z - zn))
        assert abs(z[k] - zn) < 1e-12
        assert abs(w[k] - shape[4 * node]) < 1e-12


def test_no_pyplot_import() -> None:
    code = (
        "import sys, rotorcheck.report.campbell, rotorcheck.report.figures;"
        "sys.exit(int('matplotlib.pyplot' in sys.modules))"
    )
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0
