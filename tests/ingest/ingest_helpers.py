"""Shared helpers of the ingest tests: a small two-probe plant, its records and their channel maps.

The reference for every phasor is independent of the ingest code: the plant's FRF times the force
(a time-invariant plant) or the simulator's phasor path (:func:`rotorcheck.sim.simulator.simulate_fast`
without noise, shaft harmonics removed by :func:`rotorcheck.signal.lockin.fit_shaft_harmonics`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rotorcheck.ingest import parse_channel_map
from rotorcheck.ingest.channel_map import ChannelMap
from rotorcheck.sim.simulator import StepSettings, lti_plant
from rotorcheck.sim.time_records import RecordSpec, SimulatedRecord, channel_map_dict, simulate_record

FORCE_N = 10.0
FS_HZ = 5000.0  # not a multiple of any excitation frequency below
FREQS = np.array([31.7, 55.5, 123.4])
NOISE_M = 2e-7


def frf(f: float) -> np.ndarray:
    """Two receptances (m/N) of a 1-DOF-like plant, 80 Hz resonance."""
    w, wn = 2 * np.pi * f, 2 * np.pi * 80.0
    return np.array([1e-5 / (1 - (w / wn) ** 2 + 0.1j * w / wn), 2e-6 / (1 - (w / wn) ** 2 + 0.05j * w / wn)])


def truth(freqs: np.ndarray = FREQS) -> np.ndarray:
    """The noiseless output phasors (f, 2) m."""
    return FORCE_N * np.array([frf(f) for f in freqs])


def settings(n_periods: int = 32, noise: float = NOISE_M, settle: int = 8) -> StepSettings:
    return StepSettings(n_periods=n_periods, settle_periods=settle, samples_per_period=None,
                        force_amplitude=FORCE_N, output_noise_std=noise)


def small_record(seed: int = 1, freqs: np.ndarray = FREQS, n_periods: int = 32, noise: float = NOISE_M,
                 fs_hz: float = FS_HZ, **spec: Any) -> SimulatedRecord:
    sp = RecordSpec(fs_hz=fs_hz, probe_names=("p6x", "p2x"), **spec)
    return simulate_record(lti_plant(frf, 2), freqs, settings(n_periods, noise), rng=seed, spec=sp,
                           force_port=(8, "x"), probe_ports=[(6, "x"), (2, "x")])


def cmap_of(sim: SimulatedRecord, fmt: str = "hdf5", with_steps: bool = True, **analysis: Any) -> ChannelMap:
    return parse_channel_map(channel_map_dict(sim, "crack_rig", fmt, with_steps=with_steps, **analysis))


