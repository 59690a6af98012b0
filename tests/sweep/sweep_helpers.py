"""Helpers for the sweep tests: a small valid sweep and the three-mass ECP system."""

from __future__ import annotations

import numpy as np

from rotorcheck.sweep.format import Channel, Run, Sweep

CHANNELS = [
    Channel("F8x", "input", 8, "x", "force", "N"),
    Channel("d6x", "output", 6, "x", "displacement", "m"),
    Channel("d6y", "output", 6, "y", "displacement", "m"),
]


def make_sweep(n_f: int = 262, seed: int = 1, periods: bool = False) -> Sweep:
    """A valid two-run sweep with random (but consistent) phasors; arbitrary, uneven grid."""
    rng = np.random.default_rng(seed)
    runs = {}
    for run_id, speed, nf in (("healthy_1000rpm", 1000.0, n_f), ("healthy_0rpm", 0.0, n_f // 2)):
        f = np.sort(30.0 + 570.0 * rng.random(nf))
        n_per = 64
        x = np.exp(2j * np.pi * rng.random((nf, n_per, 3)))
        x[:, :, 1:] *= 1e-6
        x += (rng.standard_normal((nf, n_per, 3)) + 1j * rng.standard_normal((nf, n_per, 3))) * 1e-8
        mean = x.mean(axis=1)
        var = (np.abs(x - mean[:, None, :]) ** 2).sum(axis=1)[:, 1:] / (n_per * (n_per - 1))
        runs[run_id] = Run.from_phasors(
            run_id,
            speed,
            f,
            mean[:, :1],
            mean[:, 1:],
            var,
            n_per,
            period_phasor=x if periods else None,
            notes="test run" if speed > 0 else "",
        )
    return Sweep("crack_rig", "simulated", "tests/sweep", "2024-05-01T12:00:00Z", list(CHANNELS), runs)


def v2_sweep() -> Sweep:
    """A run of two patterns (inputs F8x, F8y driven one at a time, 4 periods kept) and an FRF-only run."""
    rng = np.random.default_rng(7)
    chans = [*CHANNELS, CHANNELS[0].__class__("F8y", "input", 8, "y", "force", "N")]
    nf, p = 12, 4
    f = np.linspace(20.0, 130.0, nf)
    u = np.zeros((nf, 2, 2), complex)
    u[:, 0, 0], u[:, 1, 1] = 1.0 + 0.5j, 0.8 - 0.1j
    per = (rng.standard_normal((nf, 2, p, 4)) + 1j * rng.standard_normal((nf, 2, p, 4))) * 1e-6
    per[:, :, :, 0] = u[:, :, None, 0]
    per[:, :, :, 3] = u[:, :, None, 1]
    y = per[:, :, :, 1:3].mean(axis=2)
    var = (np.abs(per[:, :, :, 1:3] - y[:, :, None]) ** 2).sum(axis=2) / (p * (p - 1))
    multi = Run.from_patterns("two_shakers", 600.0, f, u, y, var, p, period_phasor=per)
    fo = Run.frf_only("analyser", 0.0, f[:7], multi.frf[:7], multi.frf_variance()[:7], noise_source="measured")
    return Sweep("crack_rig", "measured", "test", "2026-01-01T00:00:00Z", chans,
                 {"two_shakers": multi, "analyser": fo})


def three_mass() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ECP 210a three-mass chain (rigs.md section 2): m1-m2-m3-ground, M, C, K in SI."""
    m1, m2, m3 = 2.8113, 2.6396, 2.6074
    k1, k2, k3 = 842.3, 806.5, 386.0
    c1, c2, c3 = 5.992, 1.9467, 10.7375

    def chain(a: float, b: float, c: float) -> np.ndarray:
        return np.array([[a, -a, 0.0], [-a, a + b, -b], [0.0, -b, b + c]])

    return np.diag([m1, m2, m3]), chain(c1, c2, c3), chain(k1, k2, k3)


def state_space_frf(
    m: np.ndarray, c: np.ndarray, k: np.ndarray, b: np.ndarray, cout: np.ndarray, f_hz: float
) -> np.ndarray:
    """Independent FRF route: C (j w I - A)^-1 B of the first-order form."""
    n = m.shape[0]
    minv = np.linalg.inv(m)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    bb = np.concatenate([np.zeros(n), minv @ b])
    cc = np.hstack([cout, np.zeros((cout.shape[0], n))])
    w = 2 * np.pi * f_hz
    return cc @ np.linalg.solve(1j * w * np.eye(2 * n) - a, bb)
