"""Several inputs driven one at a time (x and y actuators): a version-2 run whose least-squares FRF
matrix matches the plant's within its stated variance, with the step table and with the steps (and
their patterns) found in the forces."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.stats

from rotorcheck.ingest import analyse, ingest_files
from rotorcheck.sim.simulator import lti_plant
from rotorcheck.sim.time_records import RecordSpec, simulate_record, write_record
from rotorcheck.sweep import read_sweep
from tests.ingest.ingest_helpers import FREQS, cmap_of, frf, settings


def frf_y(f: float) -> np.ndarray:
    """The second input's receptances (m/N): another mode at 140 Hz."""
    w, wn = 2 * np.pi * f, 2 * np.pi * 140.0
    return np.array([3e-6 / (1 - (w / wn) ** 2 + 0.08j * w / wn), 8e-6 / (1 - (w / wn) ** 2 + 0.08j * w / wn)])


@pytest.fixture(scope="module")
def sim():
    plants = [lti_plant(frf, 2), lti_plant(frf_y, 2)]
    spec = RecordSpec(fs_hz=5000.0, probe_names=("p6x", "p6y"))
    return simulate_record(plants, FREQS, settings(24), rng=5, spec=spec, force_port=[(8, "x"), (8, "y")],
                           probe_ports=[(6, "x"), (6, "y")])


@pytest.mark.parametrize("with_steps", [True, False])
def test_two_inputs_give_a_version_2_run(sim, with_steps: bool, tmp_path: Path) -> None:
    rec = write_record(sim, tmp_path / "r.h5")
    ingest_files([rec], cmap_of(sim, with_steps=with_steps), tmp_path / "out.h5")
    run = read_sweep(tmp_path / "out.h5").runs["0rpm"]
    assert run.n_exc == 2 and run.frf.shape == (3, 2, 2)
    np.testing.assert_allclose(run.frequency, FREQS, rtol=1e-6)
    assert np.all(run.n_periods_exc >= 22)
    h = np.stack([np.stack([frf(f), frf_y(f)], axis=1) for f in FREQS])  # (f, out, in)
    z = np.abs(run.frf - h) ** 2 / run.frf_var
    assert np.all(z < scipy.stats.f.ppf(1 - 1e-4 / z.size, 2, 2 * 23)), z


def test_missing_pattern_refused(sim) -> None:
    cmap = cmap_of(sim)
    from rotorcheck.errors import InputError

    steps = [s for k, s in enumerate(cmap.steps or []) if k != 3]  # 55.5 Hz lost its x pattern
    with pytest.raises(InputError, match="1 excitation pattern"):
        analyse([sim.record], cmap.model_copy(update={"steps": steps}))
