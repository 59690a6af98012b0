"""Monte Carlo coverage of the ingested ``output_var`` against the exact phasors, over >= 200 records.

Standing still: each record is a fresh noise draw of the same short sweep; ``|mean - truth|^2 /
output_var`` follows F(2, 2(N-1)), so the 95 % quantile must cover 95 % of the points (binomial
tolerance). Turning (1000 rpm, keyphasor, large 1X and 2X synchronous tones and a start angle that
changes from record to record): the harmonics are fitted out with the keyphasor's angle; the
reference is the plant's FRF times the force (the harmonics must not leak into the phasor), the
degrees of freedom those of the fit (from the run notes).
"""

from __future__ import annotations

import re

import numpy as np
import scipy.stats

from rotorcheck.ingest import analyse
from rotorcheck.sim.simulator import Tone, lti_plant
from rotorcheck.sim.time_records import RecordSpec, simulate_record
from tests.ingest.ingest_helpers import cmap_of, frf, settings, small_record, truth

LEVEL = 0.95


def _z(run, ref: np.ndarray) -> np.ndarray:
    return (np.abs(run.output_phasor - ref) ** 2 / run.output_var).ravel()


def test_coverage_at_rest() -> None:
    freqs = np.array([31.7, 123.4])
    n = 12
    zs = []
    for seed in range(200):
        sim = small_record(seed=1000 + seed, freqs=freqs, n_periods=n)
        run = analyse([sim.record], cmap_of(sim)).sweep.runs["0rpm"]
        assert np.array_equal(run.n_periods, [n, n])
        zs.append(_z(run, truth(freqs)))
    z = np.concatenate(zs)
    q = scipy.stats.f.ppf(LEVEL, 2, 2 * (n - 1))
    cover = float(np.mean(z <= q))
    tol = 3.5 * np.sqrt(LEVEL * (1 - LEVEL) / z.size)
    print(f"coverage at rest: {cover:.4f} over {z.size} points (target {LEVEL})")
    assert abs(cover - LEVEL) < tol, cover


def test_coverage_turning_with_keyphasor() -> None:
    freqs = np.array([40.3, 97.1])
    n, speed = 28, 1000.0
    shaft = speed / 60.0
    plant = lti_plant(frf, 2)
    # synchronous responses far above the noise (1 um and 0.3 um against 0.2 um/sample noise)
    dist = [Tone(shaft, np.array([1e-6, 5e-7])), Tone(2 * shaft, np.array([3e-7j, 2e-7]))]
    zs, dofs = [], []
    for seed in range(200):
        rng = np.random.default_rng(5000 + seed)
        theta0 = float(rng.uniform(0, 2 * np.pi))
        # the tones turn with the shaft: start angle theta0 multiplies order k by exp(j k theta0)
        turned = [Tone(d.freq_hz, d.amplitude * np.exp(1j * k * theta0)) for k, d in enumerate(dist, start=1)]
        sim = simulate_record(plant, freqs, settings(n, settle=4), turned, rng, RecordSpec(
            fs_hz=5000.0, probe_names=("p6x", "p2x")), speed, theta0, (8, "x"), [(6, "x"), (2, "x")])
        res = analyse([sim.record], cmap_of(sim, shaft_orders=2))
        run = res.sweep.runs["1000rpm"]
        assert abs(run.speed_rpm - speed) < 1e-6 * speed
        zs.append(_z(run, truth(freqs)))
        dofs.append(int(re.search(r"real dof >= (\d+)", run.notes).group(1)))
    z = np.concatenate(zs)
    q = scipy.stats.f.ppf(LEVEL, 2, min(dofs))
    cover = float(np.mean(z <= q))
    tol = 3.5 * np.sqrt(LEVEL * (1 - LEVEL) / z.size)
    print(f"coverage turning: {cover:.4f} over {z.size} points (target {LEVEL}, dof {min(dofs)})")
    assert abs(cover - LEVEL) < tol, cover
