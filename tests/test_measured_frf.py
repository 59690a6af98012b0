"""The typed measured FRF (issue 28): (frequency, pairs) with variance, dof, labels; its exports agree with
the sweep file read directly with h5py."""

from __future__ import annotations

import doctest

import h5py
import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.resources import configs_dir, samples_dir
from rotorcheck.workflow import frf as frf_module


def test_the_docstring_example_runs() -> None:
    failed, tried = doctest.testmod(frf_module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert tried > 0 and failed == 0


def test_one_pair_against_the_file_read_directly() -> None:
    rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
    path = samples_dir() / "crack_rig" / "healthy_0rpm.h5"
    m = workflow.load_run(path, rig).measured_frf()
    with h5py.File(path, "r") as h5:
        run = h5["runs"][next(iter(h5["runs"]))]
        f = run["frequency"][()]
        x, y, v = run["input_phasor"][()][:, 0], run["output_phasor"][()][:, 0], run["output_var"][()][:, 0]
        n = run["n_periods"][()]
    keep = (f >= rig.analysis.band_hz[0] - 1e-9) & (f <= rig.analysis.band_hz[1] + 1e-9)
    np.testing.assert_allclose(m.frequency_hz, f[keep])
    np.testing.assert_allclose(m.frf[:, 0], (y / x)[keep], rtol=1e-12)
    np.testing.assert_allclose(m.var[:, 0], (v / np.abs(x) ** 2)[keep], rtol=1e-12)  # var of Y/X, X exact
    np.testing.assert_allclose(m.dof[:, 0], (2.0 * (n - 1))[keep])  # real dof of a complex mean over N periods
    assert m.channels == ["s6.x<-s8.x"] and m.speed_rpm == 0.0


def test_xy_pairs_export_to_pandas_and_xarray() -> None:
    pytest.importorskip("xarray")
    rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
    m = workflow.load_run(samples_dir() / "crack_rig_xy" / "healthy_0rpm.h5", rig).measured_frf()
    nf, npair = m.frf.shape
    assert npair == len(m.channels) > 1 and m.channels[0] == "s6.x<-s8.x"
    df = m.to_pandas()
    assert len(df) == nf * npair
    row = df[(df.channel == m.channels[1])].iloc[7]
    assert row.re + 1j * row.im == pytest.approx(m.frf[7, 1], rel=1e-15)
    assert row.phase_deg == pytest.approx(np.degrees(np.angle(m.frf[7, 1])))
    ds = m.to_xarray()
    assert list(ds.channel.values) == m.channels
    assert ds.frf.attrs["units"] == "m/N" and ds.frequency.attrs["units"] == "Hz"
    np.testing.assert_array_equal(ds.frf.sel(channel=m.channels[2]).values, m.frf[:, 2])


def test_plot_draws_every_pair() -> None:
    rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
    m = workflow.load_run(samples_dir() / "crack_rig_xy" / "healthy_0rpm.h5", rig).measured_frf()
    fig = m.plot()
    mag = fig.axes[0]
    assert len(mag.get_lines()) == len(m.channels)
    np.testing.assert_allclose(mag.get_lines()[0].get_ydata(), np.abs(m.frf[:, 0]))
