"""Campbell tracking through a crossing, whirl labels along branches, root-found critical speeds."""

from __future__ import annotations

import numpy as np
import pytest
from test_fe_rotor_closed_forms import A_R, IP_R, IT_R, K_R, M_R, rigid_rotor, rigid_rotor_closed_form

from rotorcheck.fe.modal import RPM_TO_RAD_S, campbell, critical_speeds

TWO_PI = 2 * np.pi
SPEEDS = np.linspace(0.0, 12000.0, 25)


def test_tracking_follows_a_branch_through_a_crossing() -> None:
    """The forward conical mode starts below the (speed independent) cylindrical pair and crosses
    it near 6406 rpm; sorting by frequency would swap the branches there, tracking must not."""
    sys_ = rigid_rotor()
    camp = campbell(sys_, SPEEDS, n_modes=4)
    ref = np.array([rigid_rotor_closed_form(s * RPM_TO_RAD_S) for s in SPEEDS]) / TWO_PI  # (s, 3)
    cyl, back, fwd = ref[:, 0], ref[:, 1], ref[:, 2]
    # the crossing really happens inside the range
    cross = (IT_R * (2 * K_R / M_R) - 2 * K_R * A_R**2) / (IP_R * np.sqrt(2 * K_R / M_R)) / RPM_TO_RAD_S
    assert 6000 < cross < 7000 and fwd[0] < cyl[0] and fwd[-1] > cyl[-1]
    f = camp.frequency_hz
    # branch order at rest: conical pair (B then F), cylindrical pair (B then F)
    np.testing.assert_allclose(f[:, 0], back, rtol=1e-7)
    np.testing.assert_allclose(f[:, 1], fwd, rtol=1e-7)
    np.testing.assert_allclose(f[:, 2], cyl, rtol=1e-7)
    np.testing.assert_allclose(f[:, 3], cyl, rtol=1e-7)
    # whirl labels are constant along each branch
    labels = camp.whirl
    assert set(labels[:, 0]) == {"backward"} and set(labels[:, 1]) == {"forward"}
    assert set(labels[:, 2]) == {"backward"} and set(labels[:, 3]) == {"forward"}
    assert camp.min_mac.min() > 0.999
    # sorting by frequency would have mixed them: the sorted second-lowest differs after the crossing
    sorted_f = np.sort(f, axis=1)
    assert not np.allclose(sorted_f[:, 1], f[:, 1])


def test_critical_speeds_are_root_found() -> None:
    """Forward criticals of the rigid rotor: conical (It - Ip) w^2 = 2 k a^2, cylindrical w^2 = 2k/m.

    The grid (25 or 7 speeds) is far coarser than the accuracy asserted.
    """
    sys_ = rigid_rotor()
    conical = np.sqrt(2 * K_R * A_R**2 / (IT_R - IP_R)) / RPM_TO_RAD_S
    cylindrical = np.sqrt(2 * K_R / M_R) / RPM_TO_RAD_S
    for n_grid in (25, 7):
        crit = critical_speeds(sys_, 12000.0, n_grid=n_grid)
        np.testing.assert_allclose(crit, [conical, cylindrical], rtol=1e-7)
    # 2X: half the speeds
    crit2 = critical_speeds(sys_, 12000.0, order=2)
    w_con2 = np.sqrt(2 * K_R * A_R**2 / (IT_R - IP_R / 2))  # It w^2 - Ip (w/2) w = kt
    np.testing.assert_allclose(crit2, [w_con2 / 2 / RPM_TO_RAD_S, cylindrical / 2], rtol=1e-7)


def test_backward_modes_are_not_critical() -> None:
    """A backward branch crossing 1X is not reported (only forward modes are critical)."""
    sys_ = rigid_rotor()
    camp = campbell(sys_, SPEEDS, n_modes=4)
    assert len(camp.critical_speeds_rpm) == 2
    assert all(camp.branch_whirl[b] == "forward" for b in camp.critical_branch)


@pytest.mark.parametrize("n_modes", [2, 6])
def test_campbell_shapes(n_modes: int) -> None:
    camp = campbell(rigid_rotor(), SPEEDS[:5], n_modes=n_modes)
    k = min(n_modes, 4)
    assert camp.frequency_hz.shape == (5, k) and camp.damping_ratio.shape == (5, k)
