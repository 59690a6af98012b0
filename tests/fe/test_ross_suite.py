"""ROSS's own test-suite rotors as rotorcheck rig files (issue 20), against the numbers ROSS asserts.

ROSS (petrobras/ross, ``ross/tests/test_rotor_assembly.py`` and the doctests of
``ross/rotor_assembly.py``) is a second, independent implementation of the same Timoshenko rotor
model. Where ROSS's suite asserts numbers, they are copied below with their source; where it asserts
none (the 64-element cone, pedestals, bearing mass, the 4000 rpm and Euler-Bernoulli variants),
``tests/data/ross/ross_reference.json`` holds ROSS 2.3.0's values, written by
``tools/ross_reference.py`` (needs ROSS; not run here).

ROSS models 6 DOF per node; its axial and torsional modes (e.g. 650.407866 rad/s in the axial-force
and torque tests, 774.35 rad/s in rotor_example) are outside rotorcheck's lateral model, so the
comparisons take ROSS's lateral modes only. Shear coefficient: Cowper's, as ROSS's default
(``shear_method: cowper`` in the rig files; rotorcheck's own default is Hutchinson's).
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from rotorcheck.config import RigConfig, load_config, parse_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import receptance
from rotorcheck.fe.modal import modes, natural_frequencies_at_rest

DATA = Path(__file__).resolve().parents[1] / "data" / "ross"
REF = json.loads((DATA / "ross_reference.json").read_text())
RPM = 2.0 * np.pi / 60.0


def _base() -> dict[str, Any]:
    return yaml.safe_load((DATA / "ross_rotor_example.yaml").read_text())


def _wd(cfg: RigConfig, rpm: float, n: int = 6) -> np.ndarray:
    """Damped natural frequencies (rad/s) of the lowest n modes."""
    return 2.0 * np.pi * modes(build_system(cfg), rpm, n_modes=n).frequency_hz


def _loaded(kind: str) -> RigConfig:
    """ROSS's test_axial_force / test_torque rotor: rotor_example with kyy = kxx = 1e6 N/m, the second
    disc 0.35 m, and 100 kN axial force or 100 kN m torque on every element."""
    d = _base()
    for e in d["shaft"]:
        e[kind] = "100 kN" if kind == "axial_force" else "100 kN m"
    d["discs"][1]["outer_diameter"] = 0.35
    for b in d["bearings"]:
        b["kyy"] = 1.0e6
    return parse_config(d)


def test_rotor_example_matches_ross_doctest_and_reference() -> None:
    cfg = load_config(DATA / "ross_rotor_example.yaml")
    wd0 = _wd(cfg, 0.0)
    # ross/rotor_assembly.py rotor_example() doctest: np.round(modal.wd[:4]) == [92, 96, 275, 297]
    np.testing.assert_array_equal(np.round(wd0[:4]), [92.0, 96.0, 275.0, 297.0])
    np.testing.assert_allclose(wd0, REF["rotor_example_0rpm"]["wd"][:6], rtol=1e-9)
    np.testing.assert_allclose(_wd(cfg, 4000.0), REF["rotor_example_4000rpm"]["wd"][:6], rtol=1e-9)
    # ROSS's 774.35 rad/s mode is axial/torsional: not a lateral mode of rotorcheck's model
    assert not np.any(np.isclose(_wd(cfg, 0.0, 8), REF["rotor_example_0rpm"]["axial_torsional_wd"][0], rtol=1e-3))


@pytest.mark.parametrize("key", ["rotor_example_4000rpm", "pedestals_4000rpm", "axial_force_4000rpm",
                                 "torque_4000rpm"])
def test_whirl_directions_agree_with_ross(key: str) -> None:
    """Where ROSS calls a mode forward or backward, rotorcheck does too (ROSS's "mixed", per-node
    disagreement on near-planar orbits of anisotropic supports, is not a direction to compare; it even
    changes between ROSS runs of the same rotor)."""
    cfg = {"rotor_example": lambda: load_config(DATA / "ross_rotor_example.yaml"),
           "axial_force": lambda: _loaded("axial_force"), "torque": lambda: _loaded("torque"),
           "pedestals": lambda: _pedestals()}[key.rsplit("_", 1)[0]]()
    ours = modes(build_system(cfg), 4000.0, n_modes=6).whirl
    theirs = REF[key]["whirl"][:6]
    decided = [k for k, w in enumerate(theirs) if w in ("forward", "backward")]
    assert len(decided) >= 4
    assert [ours[k] for k in decided] == [theirs[k] for k in decided]


def test_euler_bernoulli_switches_match_ross() -> None:
    d = _base()
    d.update(shear=False, rotary_inertia=False, gyroscopic=False)
    d.pop("shear_method")  # unused without shear (the loader refuses a key it would ignore)
    wd = _wd(parse_config(d), 0.0)
    np.testing.assert_allclose(wd, REF["rotor_example_euler_bernoulli_0rpm"]["wd"][:6], rtol=1e-9)
    # and differs from the Timoshenko rotor by more than the tolerance (the switches act)
    assert np.abs(wd / np.asarray(REF["rotor_example_0rpm"]["wd"][:6]) - 1).max() > 1e-3


@pytest.mark.parametrize(
    "kind, expected",
    [
        # ross/tests/test_rotor_assembly.py test_axial_force, expected_wd at 4000 rpm (rad/s)
        ("axial_force", [93.416071, 95.2335, 267.475281, 309.918575, 634.40757, 650.407866]),
        # ... test_torque
        ("torque", [81.324905, 84.769077, 242.822862, 286.158147, 591.519983, 650.407866]),
    ],
)
def test_axial_force_and_torque_match_ross_test(kind: str, expected: list[float]) -> None:
    wd = _wd(_loaded(kind), 4000.0, 5)
    # 650.407866 is the axial/torsional mode of ROSS's 6-DOF model (tools/ross_reference.py classifies it
    # from its shape), outside the lateral model; the five lateral ones agree to ROSS's printed digits
    assert REF[f"{kind}_4000rpm"]["axial_torsional_wd"][0] == pytest.approx(650.407866, rel=1e-8)
    np.testing.assert_allclose(wd, expected[:5], rtol=1e-6)
    np.testing.assert_allclose(wd, REF[f"{kind}_4000rpm"]["wd"][:5], rtol=1e-9)
    unloaded = _wd(parse_config({**_loaded(kind).model_dump(by_alias=True, exclude_defaults=True),
                                 "shaft": [{**e, kind: 0.0} for e in _loaded(kind).model_dump(
                                     by_alias=True, exclude_defaults=True)["shaft"]]}), 4000.0, 5)
    # ROSS's issue note: first modes 8.6 % (tension stiffens) and 5 % (torque softens) from unloaded
    shift = wd[0] / unloaded[0] - 1
    assert (shift > 0.01) if kind == "axial_force" else (shift < -0.01)


def test_conical_rotor_matches_ross_test_at_4_and_64_tapered_elements() -> None:
    cfg = load_config(DATA / "ross_rotor_conical.yaml")
    wn4 = 2.0 * np.pi * modes(build_system(cfg), 0.0, n_modes=6).natural_frequency_hz
    # ross/tests/test_rotor_assembly.py test_rotor_conical_frequencies, expected_wn (rtol 1e-5 there)
    np.testing.assert_allclose(
        wn4, [1630.7509182, 1630.75091824, 9899.54379138, 9899.54396231, 21074.45440319, 21074.45440372],
        rtol=1e-6)
    # ROSS 2.3.0 itself (the test's values above are from an older ROSS, 1e-8 away): 1e-8 here; the
    # 1e20 N/m supports leave about 7e-9 of conditioning noise in both programs
    np.testing.assert_allclose(wn4, REF["conical_4_0rpm"]["wn"][:6], rtol=3e-8)
    # 64 elements: refine each tapered element into 16 (diameters interpolated linearly at each cut)
    d = yaml.safe_load((DATA / "ross_rotor_conical.yaml").read_text())
    for e in d["shaft"]:
        e["refine"] = 16
    wn64 = 2.0 * np.pi * modes(build_system(parse_config(d)), 0.0, n_modes=6).natural_frequency_hz
    np.testing.assert_allclose(wn64, REF["conical_64_0rpm"]["wn"][:6], rtol=3e-8)


def test_tapered_rig_converges_to_a_fine_staircase() -> None:
    """The cone (0.1 -> 0.01 m, shear on) at 4 -> 16 -> 64 tapered elements against the limit of a
    staircase of fine cylinders (Richardson over 256 and 512 steps; the staircase converges as h^2).
    The default element (exact static stiffness) is within 3e-4 at 16 elements, where 16 tapered
    elements beat a 64-step staircase; ROSS's (greenhill, one mid-section shear parameter) converges
    to the same limit, far more slowly on this strong taper (measured 4.8 / 1.8 / 0.21 %)."""
    d = yaml.safe_load((DATA / "ross_rotor_conical.yaml").read_text())
    d["bearings"] = [{"name": "b0", "station": 1, "kxx": 1e9, "kyy": 1e9},
                     {"name": "b1", "station": 5, "kxx": 1e9, "kyy": 1e9}]

    def staircase(n: int) -> np.ndarray:
        z = np.linspace(0.0, 0.5, n + 1)
        dm = 0.1 - 0.09 * (z[:-1] + z[1:]) / 2 / 0.5
        s = copy.deepcopy(d)
        s["stations"] = z.tolist()
        s["shaft"] = [{"start": k + 1, "end": k + 2, "material": "steel", "outer_diameter": float(x)}
                      for k, x in enumerate(dm)]
        s["bearings"][1]["station"] = n + 1
        return natural_frequencies_at_rest(build_system(parse_config(s)), 4)[::2]

    def tapered(n: int, formulation: str) -> np.ndarray:
        s = copy.deepcopy(d)
        s["tapered_element"] = formulation
        for e in s["shaft"]:
            e["refine"] = n // 4
        return natural_frequencies_at_rest(build_system(parse_config(s)), 4)[::2]

    s256, s512 = staircase(256), staircase(512)
    limit = s512 + (s512 - s256) / 3.0
    err = {(f, n): np.abs(tapered(n, f) / limit - 1).max() for f in ("exact", "greenhill") for n in (4, 16, 64)}
    assert err["exact", 16] < 3e-4 and err["exact", 64] < 5e-5 and err["exact", 64] < err["exact", 16]
    assert err["exact", 16] < np.abs(staircase(64) / limit - 1).max()
    assert err["greenhill", 4] > err["greenhill", 16] > err["greenhill", 64] and err["greenhill", 64] < 3e-3
    assert err["greenhill", 16] > 10 * err["exact", 16]


def _pedestals() -> RigConfig:
    """ROSS's test_global_index rotor: each bearing links the shaft to a 1 kg pedestal (a support node
    after the last station) that sits on a support to ground."""
    d = _base()
    d["bearings"] = [
        {"name": "bearing0", "station": 1, "n_link": 8, "kxx": 1e6, "kyy": 0.8e6},
        {"name": "bearing1", "station": 7, "n_link": 9, "kxx": 1e6, "kyy": 0.8e6},
        {"name": "support0", "station": 8, "kxx": 1e6, "kyy": 0.8e6},
        {"name": "support1", "station": 9, "kxx": 1e6, "kyy": 0.8e6},
    ]
    d["point_masses"] = [{"name": "pedestal0", "station": 8, "mass": 1.0},
                         {"name": "pedestal1", "station": 9, "mass": 1.0}]
    return parse_config(d)


@pytest.mark.parametrize("rpm", [0.0, 4000.0])
def test_pedestals_point_masses_and_linked_bearings_match_ross(rpm: float) -> None:
    cfg = _pedestals()
    assert build_system(cfg).n_dof == 4 * 7 + 2 * 2
    np.testing.assert_allclose(_wd(cfg, rpm), REF[f"pedestals_{rpm:.0f}rpm"]["wd"][:6], rtol=1e-9)
    # the pedestals soften the supports: every mode below rotor_example's
    assert np.all(_wd(cfg, rpm)[:4] < np.asarray(REF[f"rotor_example_{rpm:.0f}rpm"]["wd"][:4]))


def test_bearing_mass_matches_ross() -> None:
    """ROSS's fixture rotor2_bearing_mass: 2 elements, a disc, bearings with 20 g of mass (ROSS copies
    kxx to kyy and mxx to myy when not given; the rig file states both)."""
    d = _base()
    d["stations"] = [0.0, 0.25, 0.5]
    d["shaft"] = d["shaft"][:2]
    d["discs"] = [{"name": "disk0", "station": 2, "material": "steel", "width": 0.07, "inner_diameter": 0.05,
                   "outer_diameter": 0.28}]
    d["bearings"] = [{"name": f"b{k}", "station": st, "kxx": 1e6, "kyy": 1e6, "mxx": 0.02, "myy": 0.02}
                     for k, st in enumerate((1, 3))]
    np.testing.assert_allclose(_wd(parse_config(d), 0.0), REF["bearing_mass_0rpm"]["wd"][:6], rtol=1e-9)


def test_rayleigh_damping_rotor_matches_ross_frequency_response() -> None:
    """ross/tests/test_rotor_assembly.py test_proportional_damping: alpha = 1.6 1/s, beta = 1.7e-7 s on
    the rotor's M and K (no bearings: scope rotor), receptance x -> x at node 2 with the rotor
    running at the excitation frequency (ROSS's run_freq_response(speed_range=...)), 0-1400 rpm."""
    d = _base()
    d["discs"][1]["outer_diameter"] = 0.35
    d["damping"] = {"kind": "rayleigh", "alpha": 1.6, "beta": 1.7e-7, "scope": "rotor"}
    sys_ = build_system(parse_config(d))
    w = np.arange(0, 1401, 200) * RPM
    o = sys_.dof(3, "x")
    H = np.array([receptance(sys_, np.array([x / (2 * np.pi)]), x / RPM, o, o, method="direct")[0, 0, 0]
                  for x in w])
    amp = [0.000000e00, 1.495063e-06, 1.803282e-06, 2.818322e-06, 1.854149e-05, 2.545901e-06, 9.415274e-07,
           4.557404e-07]
    phase = [0.00e00, -0.004284, -0.010686, -0.026649, -0.268325, -3.089441, -3.111475, -3.114635]
    # ROSS prints 7 significant digits; ROSS's 0 at 0 rad/s is its own convention (the static
    # receptance is not zero: rotorcheck's equals the flexibility K^-1 there, checked below)
    np.testing.assert_allclose(np.abs(H[1:]), amp[1:], rtol=3e-7)
    np.testing.assert_allclose(np.angle(H[1:]), phase[1:], rtol=1e-6, atol=1e-6)
    K = sys_.matrices(0.0)[3]
    assert abs(H[0]) == pytest.approx(np.linalg.inv(K)[o, o], rel=1e-9)
    # scope matters: with the bearings in K (scope system) the damping, hence the peak, differs
    d["damping"]["scope"] = "system"
    sys2 = build_system(parse_config(d))
    H2 = receptance(sys2, np.array([w[4] / (2 * np.pi)]), w[4] / RPM, o, o, method="direct")[0, 0, 0]
    assert abs(abs(H2) / amp[4] - 1) > 30 * 3e-7  # 2e-5: the bearings add beta k = 0.17 N s/m


#: ross/tests/test_rotor_assembly.py test_modal_6dof (rotor_6dof: rotor_example whose six shaft
#: elements carry alpha = 1 1/s, beta = 1e-5 s): its lateral modes 2-5 (mode 1, 47.62 rad/s, is axial)
ROSS_6DOF_WN = [91.79647, 96.28891, 274.56591, 296.5005]
ROSS_6DOF_WD = [91.79656, 96.289, 274.56607, 296.50068]


def _shaft_element_damped(scope: str) -> RigConfig:
    d = _base()
    d["damping"] = {"kind": "rayleigh", "alpha": 1.0, "beta": 1e-5, "scope": scope}
    return parse_config(d)


def test_shaft_element_rayleigh_damping_matches_ross_modal_6dof() -> None:
    """ROSS's element damping (``ShaftElement(alpha=1, beta=1e-5)``: ``alpha M_e + beta K_e`` of each shaft
    element, discs undamped) is ``scope: shaft_elements``. ROSS prints 5 decimals (asserts 2): its two
    lists are our ``Im(lambda)`` and ``|lambda|`` to every printed digit with that scope, and the log
    dec ``2 pi zeta / sqrt(1 - zeta^2)`` of the first mode, 0.00883, lies in the interval the printed
    digits allow. ``scope: rotor`` (ROSS's rotor-level alpha, beta: the discs damped by alpha M too)
    gives a log dec of 0.0358 and misses ROSS's frequencies by 1.4e-3 rad/s."""
    md = modes(build_system(_shaft_element_damped("shaft_elements")), 0.0, n_modes=4)
    np.testing.assert_allclose(2 * np.pi * md.frequency_hz, ROSS_6DOF_WN, rtol=0, atol=5.5e-6)
    np.testing.assert_allclose(2 * np.pi * md.natural_frequency_hz, ROSS_6DOF_WD, rtol=0, atol=5.5e-6)
    zeta = md.damping_ratio[0]
    log_dec = 2 * np.pi * zeta / np.sqrt(1 - zeta**2)
    h = 0.5e-5  # half a unit of ROSS's last printed digit
    r_lo, r_hi = (ROSS_6DOF_WN[0] - h) / (ROSS_6DOF_WD[0] + h), (ROSS_6DOF_WN[0] + h) / (ROSS_6DOF_WD[0] - h)
    bounds = [2 * np.pi * np.sqrt(1 - r**2) / r for r in (r_hi, r_lo)]
    assert bounds[0] < log_dec < bounds[1]
    assert log_dec == pytest.approx(0.00883, abs=5e-6)
    rotor = modes(build_system(_shaft_element_damped("rotor")), 0.0, n_modes=4)
    zr = rotor.damping_ratio[0]
    assert 2 * np.pi * zr / np.sqrt(1 - zr**2) == pytest.approx(0.0358, abs=5e-5)
    assert abs(2 * np.pi * rotor.frequency_hz[0] - ROSS_6DOF_WN[0]) > 1e-3
