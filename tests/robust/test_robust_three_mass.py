"""The three-mass ECP 210a example (dissertation section 3.4, rigs.md section 2), built by hand.

Force in / displacement out at mass 1, damage port at mass 3 (k3 = 386 -> kd = 350 N/m), parametric
uncertainty on m1 (delta in kg), V = 0, 200 log-spaced points 0.5-8 Hz.
"""

from __future__ import annotations

import numpy as np
import pytest
from robust_helpers import K3, KD, M1, three_mass_Z

from rotorcheck.robust import damage_dynamics, damage_set, detect, lft, validate

FREQ = np.geomspace(0.5, 8.0, 200)
W = np.ones(200, dtype=complex)  # 1 N
H_HEALTHY = np.linalg.inv(three_mass_Z(FREQ))[:, 0, 0]
H_DAMAGED = np.linalg.inv(three_mass_Z(FREQ, k3=KD))[:, 0, 0]


def trial(m1e: float) -> dict[str, object]:
    Ze = three_mass_Z(FREQ, m1=m1e)
    L, R = lft.mass_factor(2 * np.pi * FREQ, 0, 3)
    e1 = np.eye(3)[:, [0]]
    me = lft.parametric_me(Ze, L, R, e1, e1.T)
    val = validate(me, W, H_HEALTHY * W, 0.0, enclose="data")
    det = detect(me, W, H_DAMAGED * W, 0.0, val.gamma)
    meE = lft.engineering_me(Ze, L, R, 2, 0, 0)
    ds = damage_set(meE, H_DAMAGED, val.gamma)
    E11, E12, E21, E22 = (x[:, 0, 0] for x in lft.engineering_system(Ze, 2, 0, 0))
    D0 = damage_dynamics(E11, E12, E21, E22, H_DAMAGED)
    return {"val": val, "det": det, "set": ds, "D0": D0}


@pytest.fixture(scope="module")
def trials() -> dict[str, dict[str, object]]:
    return {"t1": trial(2.6), "t2": trial(2.75), "t3": trial(M1)}


def test_healthy_gamma_is_the_mass_error(trials: dict[str, dict[str, object]]) -> None:
    """SISO, V = 0, one complex scalar: the data pins delta, so gamma_h = |m1 - m1e| exactly."""
    for name, m1e in (("t1", 2.6), ("t2", 2.75)):
        val = trials[name]["val"]
        assert np.all(val.status == "ok")
        np.testing.assert_allclose(val.gamma, abs(M1 - m1e), rtol=1e-9)
    assert np.all(trials["t3"]["val"].gamma == 0)


def test_trial3_identifies_36_N_per_m_everywhere(trials: dict[str, dict[str, object]]) -> None:
    D0 = trials["t3"]["D0"]
    assert np.max(np.abs(D0 - (K3 - KD)) / (K3 - KD)) < 1e-9
    assert np.max(np.abs(D0.imag)) < 1e-9 * (K3 - KD)
    ds = trials["t3"]["set"]
    assert np.all(ds.kind == "point")


def test_detection_counts(trials: dict[str, dict[str, object]]) -> None:
    n1 = trials["t1"]["det"].n_fault
    n2 = trials["t2"]["det"].n_fault
    n3 = trials["t3"]["det"].n_fault
    f1 = FREQ[~trials["t1"]["det"].fault]
    print(f"\nthree-mass faults (of 200): trial 1 {n1}, trial 2 {n2}, trial 3 {n3}; trial 1 "
          f"not invalidated {f1.min():.2f}-{f1.max():.2f} Hz ({f1.size} points)")
    assert n1 > 150 and n2 > 150  # most points invalidated
    assert n2 >= n1
    assert n3 == 200  # perfect model: every point that differs from the healthy data
    st = trials["t1"]["det"].status
    assert set(np.unique(st)) <= {"ok", "fault"}


def test_identified_bounds(trials: dict[str, dict[str, object]]) -> None:
    D_true = np.full(200, K3 - KD, dtype=complex)
    s1, s2 = trials["t1"]["set"], trials["t2"]["set"]
    # the truth lies in both sets at every frequency (on the edge: enclose='data' puts the true
    # mass error on |delta| = gamma_h)
    assert np.all(s1.contains(D_true, rtol=1e-8))
    assert np.all(s2.contains(D_true, rtol=1e-8))
    # trial 2's bound is narrower than trial 1's at most frequencies
    both = (s1.kind == "disk") & (s2.kind == "disk")
    narrower = np.count_nonzero(s2.radius[both] < s1.radius[both]) + np.count_nonzero(
        (s1.kind != "disk") & (s2.kind == "disk"))
    ratio = np.median(s2.radius[both] / s1.radius[both])
    print(f"\ntrial 2 bound narrower at {narrower}/200 points, median radius ratio {ratio:.2f}")
    assert narrower > 150
    # nominal identified dynamics of trial 1/2 differ from 36 (model error), trial 3 does not
    assert np.median(np.abs(trials["t1"]["D0"] - 36)) > np.median(np.abs(trials["t2"]["D0"] - 36))
