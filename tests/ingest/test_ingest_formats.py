"""Each format: written by the simulator, ingested, phasors against the plant's exact phasors.

The ingested mean differs from the truth by noise only: ``|mean - truth|^2 / output_var`` follows
F(2, 2(N-1)) (complex circular Gaussian), so every point must stay below its 0.999 quantile / sqrt
of the family (a handful of points: a loose but independent check); ``n_periods`` equals the
simulator's; the force phasor is the simulator's force exactly (no force noise).
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.stats

from rotorcheck.ingest import ingest_files, parquet_available
from rotorcheck.sim.simulator import lti_plant, simulate_fast
from rotorcheck.sim.time_records import record_suffix, write_record
from rotorcheck.sweep import read_sweep
from tests.ingest.ingest_helpers import FREQS, cmap_of, frf, settings, small_record, truth

FORMATS = ["mat", "mat73", "tdms", "wav", "csv", "uff", "hdf5",
           pytest.param("parquet", marks=pytest.mark.skipif(not parquet_available(),
                                                             reason="pyarrow not installed: Parquet is optional"))]


@pytest.fixture(scope="module")
def sim():
    return small_record(seed=7)


@pytest.mark.parametrize("fmt", FORMATS)
def test_format_round_trip(tmp_path: Path, sim, fmt: str) -> None:
    rec = write_record(sim, tmp_path / f"rec{record_suffix(fmt)}", fmt)
    out = tmp_path / "sweep.h5"
    res = ingest_files([rec], cmap_of(sim, fmt), out)
    sweep = read_sweep(out)
    run = sweep.runs["0rpm"]
    assert np.array_equal(run.frequency, FREQS)
    # the simulator's own phasor path, noiseless: the reference phasors and periods
    path = simulate_fast(lti_plant(frf, 2), FREQS, settings(32, noise=0.0))
    np.testing.assert_allclose(path.output_phasor, truth(), rtol=1e-12)  # (it is the plant's FRF x force)
    assert np.array_equal(run.n_periods, path.n_periods)
    tol = 1e-6 if fmt == "wav" else 1e-9  # WAV stores float32
    np.testing.assert_allclose(run.input_phasor[:, 0], path.input_phasor[:, 0], rtol=tol)
    z = np.abs(run.output_phasor - path.output_phasor) ** 2 / run.output_var
    limit = scipy.stats.f.ppf(1 - 1e-3 / z.size, 2, 2 * (sim.n_periods[0] - 1))
    assert np.all(z < limit), z
    # the variance is the noise's: 4 sigma^2 / L per period, / N for the mean (L = floor(fs/f))
    expect = 4 * 2e-7**2 / np.floor(5000.0 / FREQS) / sim.n_periods[0]
    ratio = run.output_var / expect[:, None]
    assert np.all((ratio > 0.4) & (ratio < 2.0)), ratio
    with h5py.File(out) as h5:
        assert h5.attrs["source"] == "measured"
        assert str(rec) in h5.attrs["ingest_sources"]
        assert "sha256" in h5.attrs["ingest_sources"] and "settle_periods" in h5.attrs["ingest_settings"]
        assert '"p6x"' in h5.attrs["ingest_channel_map"] or fmt == "wav"
    assert res.summary["n_steps"] == 3
