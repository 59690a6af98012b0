"""The simulated truth rig against the nominal model: the published pattern of model error.

Regression checks of a designed config (configs/crack_rig_truth.yaml, header comment). The
dissertation (4.3 / 4.5 / 5.4) reports for the 8 x -> 6 x receptance: mode 1 matches, mode 2 off by
1.14 %, mode 3 by 3.56 %, the first anti-resonance too high in the model, the model most accurate at
low frequency, and past mode 2 the measured magnitude stays above the model's.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_fe_crack_rig import first_antiresonance, plane_frequencies

from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import critical_speeds
from rotorcheck.nominal import nominal_model

GRID_HZ = np.linspace(30.0, 600.0, 262)  # the sweep grid of the bundled samples


def _band(lo: float, hi: float) -> np.ndarray:
    return (GRID_HZ >= lo) & (GRID_HZ <= hi)


@pytest.fixture(scope="module")
def systems(crack_rig, crack_rig_truth):
    return build_system(crack_rig), build_system(crack_rig_truth)


@pytest.fixture(scope="module", params=[0.0, 1000.0], ids=["0rpm", "1000rpm"])
def receptances(request, crack_rig, crack_rig_truth, systems):
    """(nominal, truth) receptance 8 x -> 6 x on the grid at the speed (m/N)."""
    speed = request.param
    sn, st = systems
    hn = nominal_model(crack_rig, GRID_HZ, speed, system=sn).frf
    ht = nominal_model(crack_rig_truth, GRID_HZ, speed, system=st).frf
    return hn, ht


def test_ports_are_the_same(crack_rig, crack_rig_truth) -> None:
    assert crack_rig_truth.ports == crack_rig.ports
    assert crack_rig_truth.damage == crack_rig.damage
    assert crack_rig_truth.stations == crack_rig.stations


def test_data_above_model_past_mode_2(receptances) -> None:
    """(a) |H_truth| > |H_nominal| at >= 90 % of the points 180-495 Hz (YAML: 95 %, median ratio 1.04)."""
    hn, ht = receptances
    hi = _band(180.0, 495.0)
    ratio = np.abs(ht[hi]) / np.abs(hn[hi])
    assert np.mean(ratio > 1.0) >= 0.90, np.mean(ratio > 1.0)
    assert np.mean(ratio > 1.0) == pytest.approx(0.951, abs=0.01)
    assert 1.02 < np.median(ratio) < 1.07, np.median(ratio)
    # the points below are the few just past the truth's lower mode 2, none from 200 Hz on
    assert np.all(ratio[GRID_HZ[hi] >= 200.0] > 1.0)


def test_model_most_accurate_at_low_frequency(receptances) -> None:
    """(b) median |H_t - H_n| / |H_n|: 30-45 Hz at most 2 %, below both 60-100 Hz and 180-495 Hz."""
    hn, ht = receptances
    rel = np.abs(ht - hn) / np.abs(hn)
    low, mid, high = (float(np.median(rel[_band(a, b)])) for a, b in ((30, 45), (60, 100), (180, 495)))
    assert low < 0.02, low
    assert low < mid and low < high, (low, mid, high)
    np.testing.assert_allclose([low, mid, high], [0.0045, 0.067, 0.043], atol=0.002)  # YAML comment


def test_frequency_pattern_as_published(systems) -> None:
    """(c) mode 1 within 0.5 %, mode 2 -0.7..-1.5 %, mode 3 -2.5..-4.5 %, anti-resonance -2..-5 %."""
    sn, st = systems
    d = plane_frequencies(st)[:3] / plane_frequencies(sn)[:3] - 1
    assert abs(d[0]) < 0.005, d
    assert -0.015 < d[1] < -0.007, d
    assert -0.045 < d[2] < -0.025, d
    ar = first_antiresonance(st) / first_antiresonance(sn) - 1
    assert -0.05 < ar < -0.02, ar
    cn, ct = critical_speeds(sn, 10000.0), critical_speeds(st, 10000.0)
    assert len(ct) == 1
    assert abs(ct[0] / cn[0] - 1) < 0.02, (ct, cn)
