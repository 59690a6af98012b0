"""Crack compliance from depth (strip method, rotorcheck.faults.compliance), the config rule and
with_crack_depth."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from faults_helpers import CONFIGS, RIG_CRACK, small_rotor

from rotorcheck.config import ConfigError, Crack, load_config, parse_config
from rotorcheck.faults.compliance import (
    MAX_DEPTH_RATIO,
    crack_compliances,
    mayes_davies_compliances,
    open_crack_modulus_factor,
    rotational_compliances,
    strip_compliances,
    tada_bending,
    tada_tension,
    with_crack_depth,
)
from rotorcheck.faults.crack import crack_stiffness, delta_i_ratio, rotating_reduction, timoshenko_plane_stiffness

TRUTH = CONFIGS / "crack_rig_truth.yaml"
# the dissertation's rig section: R = 8 mm, l = 20 mm, nu = 0.3 (eq. 5.25)
R, L, NU = 0.008, 0.020, 0.3

# Published tabulation: c55 (xi) and c44 (eta, perpendicular moment alone) of the dimensionless
# compliance c = cbar (1 - nu^2)/(E R^3), distributed with ROSS (petrobras/ross,
# ross/faults/data/PAPADOPOULOS.csv), indexed by depth / radius; 6 significant digits.
ROSS_C55 = {0.1: 0.0277722, 0.2: 0.144614, 0.4: 0.72488, 0.5: 1.22153, 0.8: 3.97355, 1.0: 7.79039}
ROSS_C44 = {0.1: 0.000425851, 0.2: 0.00474954, 0.4: 0.0545213, 0.5: 0.12323, 0.8: 0.827564, 1.0: 2.63318}


# --------------------------------------------------------------------------------------------
# the relation


def test_tada_factors_at_zero_depth_are_the_edge_crack_1_122() -> None:
    assert float(tada_bending(0.0)) == pytest.approx(1.122, abs=1e-12)
    assert float(tada_tension(0.0)) == pytest.approx(1.122, abs=1e-12)


def test_tada_tension_agrees_with_the_gross_srawley_polynomial() -> None:
    # independent fit, edge-cracked strip in tension, valid for s <= 0.6 (both quoted to ~0.5 %)
    s = np.linspace(0.0, 0.6, 61)
    poly = 1.12 - 0.231 * s + 10.55 * s**2 - 21.72 * s**3 + 30.39 * s**4
    assert np.max(np.abs(tada_tension(s) / poly - 1.0)) < 0.015


def test_reproduces_the_published_table() -> None:
    for a, ref in ROSS_C55.items():
        assert strip_compliances(a)[0] == pytest.approx(ref, rel=1e-5), a
    for a, ref in ROSS_C44.items():
        assert strip_compliances(a, eta="half_closed")[1] == pytest.approx(ref, rel=1e-5), a


def test_half_closed_eta_is_half_the_open_crack() -> None:
    for a in (0.05, 0.4, 1.0):
        c_open, c_half = strip_compliances(a)[1], strip_compliances(a, eta="half_closed")[1]
        assert c_half == pytest.approx(0.5 * c_open, rel=1e-14)
        assert strip_compliances(a)[0] == strip_compliances(a, eta="half_closed")[0]


def test_shallow_crack_limit() -> None:
    # strips of height 2R with F = 1.122, crack depth a - x^2/(2R), width 2 sqrt(2 a R):
    # cbar_xi -> (256 sqrt2 / (15 pi)) 1.122^2 alpha^(5/2), cbar_eta -> (512 sqrt2 / (105 pi)) 1.122^2 alpha^(7/2)
    k_xi = 256.0 * math.sqrt(2.0) / (15.0 * math.pi) * 1.122**2
    k_eta = 512.0 * math.sqrt(2.0) / (105.0 * math.pi) * 1.122**2
    for a in (1e-4, 1e-5):
        c_xi, c_eta = strip_compliances(a)
        assert c_xi / (k_xi * a**2.5) == pytest.approx(1.0, abs=2e-3 * a / 1e-4)
        assert c_eta / (k_eta * a**3.5) == pytest.approx(1.0, abs=2e-3 * a / 1e-4)
    # the scaling itself: a tenth of the depth, 10^2.5 (xi) and 10^3.5 (eta) times less compliant
    (x1, e1), (x2, e2) = strip_compliances(1e-5), strip_compliances(1e-4)
    assert x2 / x1 == pytest.approx(10**2.5, rel=1e-3)
    assert e2 / e1 == pytest.approx(10**3.5, rel=1e-3)


def test_monotone_in_depth_and_xi_dominates() -> None:
    a = np.linspace(0.01, MAX_DEPTH_RATIO, 60)
    c = np.array([strip_compliances(x) for x in a])
    assert np.all(np.diff(c[:, 0]) > 0) and np.all(np.diff(c[:, 1]) > 0)
    assert np.all(c[:, 0] > c[:, 1])


@pytest.mark.parametrize("a", [1e-3, 0.05, 0.3, 0.8, 0.999, 1.0])
def test_quadrature_converges(a: float) -> None:
    ref = np.array(strip_compliances(a, n=128))
    for n, tol in ((24, 1e-8), (48, 1e-10)):
        assert np.max(np.abs(np.array(strip_compliances(a, n=n)) / ref - 1.0)) < tol
    assert np.max(np.abs(np.array(strip_compliances(a, n=8)) / ref - 1.0)) < 5e-3


@pytest.mark.parametrize("a", [0.0, -0.1, 1.0001, 1.6, float("nan")])
def test_depth_outside_validity_is_an_error(a: float) -> None:
    with pytest.raises(ValueError, match="depth"):
        strip_compliances(a)


def test_normalisation_onto_eq_5_25() -> None:
    # F = (pi/4) cbar, equivalently: a section l, E I0 in series with the rotational compliance c
    # has I0 - dI with dI/I0 = x/(1+x), x = c E I0 / l (independent of E)
    e = 224.08e9
    i0 = math.pi * R**4 / 4.0
    c_xi, c_eta = rotational_compliances(0.8, R, e, NU)
    f_xi, f_eta = mayes_davies_compliances(0.8)
    for c, f in ((c_xi, f_xi), (c_eta, f_eta)):
        x = c * e * i0 / L
        i_eq = 1.0 / (1.0 / i0 + c * e / L)  # series flexibility
        assert 1.0 - i_eq / i0 == pytest.approx(x / (1 + x), rel=1e-12)
        assert delta_i_ratio(f, R, L, NU) == pytest.approx(x / (1 + x), rel=1e-12)


def test_dissertation_40_percent_cut() -> None:
    """alpha = 0.8: the dissertation's F = 3.0 / 0.47 give 52.2 % / 14.6 %; the strip method
    3.12 / 1.30 (open) or 0.65 (half-closed): 53.2 % and 32.1 % / 19.1 %."""
    f_xi, f_eta = mayes_davies_compliances(0.8)
    f_half = mayes_davies_compliances(0.8, eta="half_closed")[1]
    assert (round(f_xi, 3), round(f_eta, 3), round(f_half, 3)) == (3.121, 1.300, 0.650)
    assert f_xi == pytest.approx(3.0, rel=0.05)  # the xi values agree to 4 %
    d = [round(100 * delta_i_ratio(f, R, L, NU), 1) for f in (f_xi, f_eta, f_half)]
    assert d == [53.2, 32.1, 19.1]


# --------------------------------------------------------------------------------------------
# config rule


def _truth_dict() -> dict:
    return yaml.safe_load(TRUTH.read_text())


def test_truth_rig_gives_depth_only() -> None:
    crack = load_config(TRUTH).faults["breathing_crack"]
    assert isinstance(crack, Crack)
    assert crack.depth == 0.4 and crack.depth_ratio is None  # fraction of the diameter, the reports' convention
    assert crack.depth_over_radius == 0.8 and crack.compliance_xi is None and crack.compliance_eta is None
    assert crack_compliances(crack) == mayes_davies_compliances(0.8)


@pytest.mark.parametrize(
    ("update", "field"),
    [
        ({"compliance_xi": 3.0}, "compliance_xi"),
        ({"compliance_eta": 0.47}, "compliance_eta"),
        ({"compliance_xi": 3.0, "compliance_eta": 0.47}, "compliance_xi"),
        ({"depth": 0.6}, "depth"),
        ({"depth": None, "depth_ratio": 1.2}, "depth_ratio"),
        ({"depth_ratio": 0.8}, "depth_ratio"),  # both keys: refused, not one silently preferred
        ({"depth": None, "compliance_xi": 3.0}, "compliance_eta"),
        ({"depth": None}, "compliance_xi"),
        ({"section_length": None}, "section_length"),
    ],
)
def test_config_rule_names_the_field(update: dict, field: str) -> None:
    d = _truth_dict()
    crack = d["faults"]["breathing_crack"]
    for k, v in update.items():
        if v is None:
            crack.pop(k, None)
        else:
            crack[k] = v
    with pytest.raises(ConfigError, match=rf"faults\.breathing_crack\..*{field}:"):
        parse_config(d, "truth.yaml")


def test_config_accepts_explicit_compliances_and_gasch_depth() -> None:
    Crack(element=4, model="mayes_davies", compliance_xi=3.0, compliance_eta=0.47, section_length=0.02)
    Crack(element=4, model="gasch", depth_ratio=MAX_DEPTH_RATIO, section_length=0.02)


@pytest.mark.parametrize("model", ["open", "jun"])
def test_depth_ratio_is_refused_where_unused(model: str) -> None:
    kw: dict = {"modulus_factor": 0.5} if model == "open" else {"jun_b_xi": [1.0], "jun_b_eta": [1.0]}
    with pytest.raises(ValueError, match="depth_ratio: not used"):
        Crack(element=4, model=model, depth_ratio=0.5, **kw)


def test_the_older_depth_key_reads_as_twice_the_depth_and_is_noted() -> None:
    """``depth_ratio`` (depth / radius) is still read: the same crack, the same rig hash, and ``model`` notes it."""
    d = _truth_dict()
    crack = d["faults"]["breathing_crack"]
    crack.pop("depth")
    crack["depth_ratio"] = 0.8
    old, new = parse_config(d, "old.yaml"), load_config(TRUTH)
    assert old.faults["breathing_crack"].depth_over_radius == new.faults["breathing_crack"].depth_over_radius == 0.8
    assert crack_compliances(old.faults["breathing_crack"]) == crack_compliances(new.faults["breathing_crack"])
    assert old.sha256() == new.sha256()
    notes = [n for n in old.notes() if "depth_ratio" in n]
    assert len(notes) == 1 and "depth 0.4 of the diameter" in notes[0]
    assert not [n for n in new.notes() if "depth" in n]


def test_depth_crack_stiffness_equals_the_explicit_compliances() -> None:
    sys_ = small_rotor()
    f_xi, f_eta = mayes_davies_compliances(0.8)
    by_depth = RIG_CRACK.model_copy(update={"compliance_xi": None, "compliance_eta": None, "depth_ratio": 0.8})
    explicit = RIG_CRACK.model_copy(update={"compliance_xi": f_xi, "compliance_eta": f_eta})
    a, b = crack_stiffness(sys_, by_depth), crack_stiffness(sys_, explicit)
    assert (a.delta_xi, a.delta_eta) == (b.delta_xi, b.delta_eta)
    assert a.delta_xi == pytest.approx(0.5318, abs=1e-4) and a.delta_eta == pytest.approx(0.3212, abs=1e-4)
    th = np.linspace(0, 2 * np.pi, 7)
    np.testing.assert_array_equal(a.at_rotation(th), b.at_rotation(th))
    np.testing.assert_array_equal(rotating_reduction(by_depth, th, NU, R), rotating_reduction(explicit, th, NU, R))


# --------------------------------------------------------------------------------------------
# with_crack_depth


def test_with_crack_depth_breathing() -> None:
    truth = load_config(TRUTH)
    new = with_crack_depth(truth, "breathing_crack", 0.1)
    crack = new.faults["breathing_crack"]
    assert isinstance(crack, Crack)
    assert crack.depth == 0.1 and crack.depth_over_radius == pytest.approx(0.2) and crack.compliance_xi is None
    assert crack.section_length == 0.020 and crack.angle == 0.0 and crack.model == "mayes_davies"
    assert new.faults["open_crack"] == truth.faults["open_crack"]
    assert truth.faults["breathing_crack"].depth == 0.4  # the input is not touched
    assert new.shaft == truth.shaft and new.bearings == truth.bearings
    # explicit compliances are replaced by the depth on request
    explicit = Crack(element=4, model="gasch", compliance_xi=3.0, compliance_eta=0.47, section_length=0.02)
    rig = truth.model_copy(update={"faults": {"g": explicit}})
    g = with_crack_depth(rig, "g", 0.25).faults["g"]
    assert isinstance(g, Crack) and g.depth_over_radius == 0.5 and g.compliance_eta is None


def test_with_crack_depth_open_is_the_element_with_the_mean_compliance_added() -> None:
    truth = load_config(TRUTH)
    new = with_crack_depth(truth, "open_crack", 0.4)
    crack = new.faults["open_crack"]
    assert isinstance(crack, Crack) and crack.modulus_factor is not None
    el = truth.shaft[3]
    radius, length = 0.5 * el.outer_diameter, truth.stations[4] - truth.stations[3]
    mat = truth.materials[el.material]
    e, i0 = mat.youngs_modulus, math.pi * radius**4 / 4
    # tip rotation of the clamped element under an end moment: healthy + mean crack compliance
    c_xi, c_eta = rotational_compliances(0.8, radius, e, mat.nu)
    kga = 0.9 * mat.G * math.pi * radius**2
    k = timoshenko_plane_stiffness(crack.modulus_factor * e * i0, length, kga)
    rot = np.linalg.solve(k[2:, 2:], [0.0, 1.0])[1]
    assert rot == pytest.approx(length / (e * i0) + 0.5 * (c_xi + c_eta), rel=1e-10)
    assert crack.modulus_factor == pytest.approx(open_crack_modulus_factor(0.8, radius, length, mat.nu))
    # the xi plane alone would remove more, the eta plane less
    f_xi, f_eta = mayes_davies_compliances(0.8)
    x = radius / length * (1 - mat.nu**2)
    assert 1 / (1 + x * f_xi) < crack.modulus_factor < 1 / (1 + x * f_eta)


@pytest.mark.parametrize("d", [0.0, 1.0, -0.1, 1.5, float("nan")])
def test_with_crack_depth_needs_a_fraction_of_the_diameter(d: float) -> None:
    with pytest.raises(ValueError, match=r"fraction of the diameter in \(0, 1\)"):
        with_crack_depth(load_config(TRUTH), "breathing_crack", d)


def test_with_crack_depth_beyond_validity() -> None:
    truth = load_config(TRUTH)
    with_crack_depth(truth, "breathing_crack", 0.5)
    with pytest.raises(ValueError, match="beyond the strip relation's validity"):
        with_crack_depth(truth, "breathing_crack", 0.6)


def test_with_crack_depth_unknown_or_jun() -> None:
    truth = load_config(TRUTH)
    with pytest.raises(ValueError, match="not a crack of this rig"):
        with_crack_depth(truth, "nope", 0.1)
    jun = Crack(element=4, model="jun", jun_b_xi=[1.0, -0.1], jun_b_eta=[1.0])
    rig = truth.model_copy(update={"faults": {"j": jun}})
    with pytest.raises(ValueError, match="not a function of depth"):
        with_crack_depth(rig, "j", 0.1)
