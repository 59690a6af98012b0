"""The modal anchor (rotorcheck.modal_anchor) against independent references: the FE receptance solved
directly, the model re-solved at a changed parameter (brute force), a modal fit of a re-solved FRF (a second
route to a residue's sensitivity), and the truth rig (physics the model does not share)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from rotorcheck.config import RigConfig, load_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.modal_anchor import fe_modes, fit_anchor, modal_frf
from rotorcheck.nominal import primary_pair
from rotorcheck.resources import configs_dir
from rotorcheck.signatures import benign_prediction, crack_signatures, io_frf, stacked, with_element_loss
from rotorcheck.variability import benign_at, with_benign

F = np.linspace(30.0, 600.0, 131)
W = 2.0 * np.pi * F


@pytest.fixture(scope="module")
def rig() -> RigConfig:
    return load_config(configs_dir() / "crack_rig.yaml")


@pytest.fixture(scope="module")
def truth() -> RigConfig:
    cfg = load_config(configs_dir() / "crack_rig_truth.yaml")
    return cfg.model_copy(update={"variability": load_config(configs_dir() / "crack_rig.yaml").variability})


def _dofs(cfg: RigConfig) -> list[tuple[int, int]]:
    s = build_system(cfg)
    p = primary_pair(cfg)
    return [(s.port_dof(p.input), s.port_dof(p.output))]


@pytest.mark.parametrize("speed", [0.0, 1000.0])
def test_the_modes_sum_to_the_receptance_solved_directly(rig: RigConfig, speed: float) -> None:
    """sum_r R_r / (jw - lambda_r) + conj over every mode (real poles once, repeated poles by their block residue)
    equals the FE receptance solved at each frequency, to 1e-6 of its peak."""
    m = fe_modes(build_system(rig), speed, _dofs(rig))
    g = io_frf(rig, F, speed)
    h = modal_frf(m.poles, m.residues, m.real, W)[:, 0]
    assert np.max(np.abs(h - g)) < 1e-6 * np.max(np.abs(g))


def test_the_fit_of_the_models_own_frf_returns_its_poles(rig: RigConfig) -> None:
    """Fitting the model's own noiseless FRF gives back the model's in-band poles (5e-6 relative) and a misfit
    below 1e-5."""
    for speed in (0.0, 1000.0):
        a = fit_anchor(build_system(rig), speed, _dofs(rig), F, io_frf(rig, F, speed)[:, None])
        assert a is not None and a.misfit < 1e-5
        assert np.max(np.abs(a.poles / a.fe_poles - 1.0)) < 5e-6


@pytest.mark.parametrize("speed, values", [
    (0.0, {"youngs_modulus": -0.02}),
    (0.0, {"bearing_stiffness.me": 0.03, "sensor_gain": 0.01}),
    (1000.0, {"youngs_modulus": 0.015, "bearing_stiffness.nme": -0.03, "speed": 20.0}),
])
def test_a_benign_change_predicted_on_the_models_own_frf_matches_the_model_re_solved(
        rig: RigConfig, speed: float, values: dict[str, float]) -> None:
    """On the model's own FRF the anchored prediction is the model's change: against the model re-solved at the
    values (brute force), what is left is below 1.5 % of the change (measured 0.07, 0.98 and 0.12 %: the poles move
    exactly; residues and the other modes to first order). E -2 % moves the modes by about a half-power bandwidth:
    the FRF's own first-order expansion misses far more."""
    params = benign_at(rig, speed)
    th = io_frf(rig, F, speed)
    pred = benign_prediction(rig, F, speed, th, params)
    assert pred.cheap  # the modal anchor, not the re-solve
    theta = np.array([values.get(p.name, 0.0) for p in params])
    cfg, d_rpm, g_s, g_a = with_benign(rig, values)
    truth = g_s * g_a * io_frf(cfg, F, speed + d_rpm) - th
    left = np.linalg.norm(pred.predict(theta) - truth) / np.linalg.norm(truth)
    assert left < 1.5e-2
    # the first-order expansion of the FRF misses far more of a large E change (the reason for exact poles)
    if "youngs_modulus" in values and abs(values["youngs_modulus"]) >= 0.02:
        cfg1 = with_benign(rig, {"youngs_modulus": 1e-4})[0]
        linear = (io_frf(cfg1, F, speed) - th) / 1e-4 * values["youngs_modulus"]
        assert np.linalg.norm(linear - truth) / np.linalg.norm(truth) > 20 * left


def test_crack_signature_is_the_derivative_of_the_re_solved_model(rig: RigConfig) -> None:
    """Each element's modal signature against a finite difference of the re-solved model (1e-4 loss): the same
    to 0.5 % (a second method: no modal model in the reference)."""
    for speed in (0.0, 1000.0):
        th = io_frf(rig, F, speed)
        els, S = crack_signatures(rig, F, speed, th)
        for k, e in enumerate(els):
            fd = (io_frf(with_element_loss(rig, e, 1e-4), F, speed) - th) / 1e-4
            assert np.linalg.norm(S[k] - fd) / np.linalg.norm(fd) < 5e-3, (speed, e)


def test_a_repeated_poles_residue_is_the_blocks(rig: RigConfig) -> None:
    """x and y modes of the isotropic model coincide: member by member their left and right eigenvectors are not
    bi-orthogonal, so each member's own residue is meaningless; the block's residue change with a 1 % loss of
    element 2 equals the one a modal fit of the re-solved FRF finds (an independent route) to 2 %."""
    sys0 = build_system(rig)
    a0 = fit_anchor(sys0, 0.0, _dofs(rig), F, io_frf(rig, F, 0.0)[:, None])
    changed = with_element_loss(rig, 2, 0.01)
    a1 = fit_anchor(build_system(changed), 0.0, _dofs(rig), F, io_frf(changed, F, 0.0)[:, None])
    assert a0 is not None and a1 is not None
    from rotorcheck.modal_anchor import sensitivity
    sens = sensitivity(a0, fe_modes(build_system(with_element_loss(rig, 2, 1e-5)), 0.0, _dofs(rig)), 1e-5)
    assert sens is not None
    order = [int(np.argmin(np.abs(a1.poles - p))) for p in a0.poles]
    by_fit = (a1.residues[order, 0] / a0.residues[:, 0] - 1.0) / 0.01
    by_block = sens.d_res[:, 0] / a0.residues[:, 0]
    big = np.abs(by_fit) > 0.05
    np.testing.assert_allclose(by_block[big], by_fit[big], rtol=0.02)


def test_on_the_truth_rig_the_anchor_explains_far_more_of_a_benign_change(rig: RigConfig, truth: RigConfig) -> None:
    """Physics the model does not share: the truth rig (supports, hub, coupling) drifted inside the ranges, its
    change fitted by the benign parameters. The modal anchor (on the truth's healthy FRF) leaves at most a fifth of
    what the model's own ratio leaves, and E is read within 0.15 % of its true value."""
    from scipy import optimize

    speed = 0.0
    params = benign_at(rig, speed)
    th = io_frf(truth, F, speed)
    values = {"youngs_modulus": -0.015, "bearing_stiffness.nme": 0.02, "bearing_stiffness.me": -0.01,
              "sensor_gain": 0.004}
    cfg, _, g_s, g_a = with_benign(truth, values)
    change = g_s * g_a * io_frf(cfg, F, speed) - th
    lo = np.array([p.lo for p in params])
    hi = np.array([p.hi for p in params])
    left = {}
    for modal in (True, False):
        pred = benign_prediction(rig, F, speed, th, params, modal=modal)
        best = None
        for e0 in np.linspace(lo[0], hi[0], 9):  # the E valley first (both predictions alike)
            x0 = np.zeros(len(params))
            x0[0] = e0
            fit = optimize.least_squares(lambda x, p=pred: stacked(np.concatenate([
                (change - p.predict(x)).real, (change - p.predict(x)).imag])) / np.abs(change).max(),
                x0, bounds=(lo, hi), x_scale=hi - lo)
            if best is None or fit.cost < best.cost:
                best = fit
        assert best is not None
        left[modal] = float(np.sqrt(2 * best.cost))
        if modal:
            assert abs(best.x[0] - values["youngs_modulus"]) < 1.5e-3
    assert left[True] < 0.2 * left[False]


def test_a_whirl_pair_split_wider_than_the_models_is_fitted_split(rig: RigConfig) -> None:
    """A machine whose forward and backward whirl of a mode sit 1 % apart (the model's 3.5e-4) and more damped:
    an FRF made of the model's modes with that pair moved (by construction, its poles known) is fitted with the
    pair split, each pole within 2e-4 of the truth, misfit below 1e-4."""
    sysm = build_system(rig)
    m = fe_modes(sysm, 1000.0, _dofs(rig))
    f_hz = m.poles.imag / (2 * np.pi)
    pair = np.flatnonzero(np.abs(f_hz - 54.4) < 0.5)
    assert pair.size == 2  # the first bending mode's forward and backward whirl
    poles = m.poles.copy()
    for k, shift in zip(pair[np.argsort(f_hz[pair])], (-0.005, 0.005)):
        wn = abs(m.poles[k]) * (1.0 + shift)
        poles[k] = wn * (-0.008 + 1j * np.sqrt(1.0 - 0.008**2))
    T = modal_frf(poles, m.residues, m.real, W)
    a = fit_anchor(sysm, 1000.0, _dofs(rig), F, T)
    assert a is not None and a.misfit < 1e-4
    got = np.sort_complex(a.poles[np.abs(a.poles.imag / (2 * np.pi) - 54.4) < 1.0])
    want = np.sort_complex(poles[pair])
    assert got.size == 2 and np.max(np.abs(got / want - 1.0)) < 2e-4


def test_the_bearing_damper_machine_at_speed_is_fitted_with_its_whirl_pairs_split(rig: RigConfig, monkeypatch) -> None:
    """The truth rig with physical bearing dampers (300 N s/m, no modal damping; the bench's ``dampers`` variant)
    at 1000 rpm, its noiseless FRF: started at the model's poles only, the fit stays with both whirl members of
    the 54 and 171 Hz modes together and leaves 0.012 of the data (its prior was widened 6x, and 4 of 30 healthy
    drifted sweeps were called damage); with the split starts it leaves below 1e-3 and the pairs sit apart
    (54.39 / 54.96 Hz on the other truths)."""
    import yaml

    import rotorcheck.modal_anchor as ma
    from rotorcheck.config import parse_config

    raw = yaml.safe_load((configs_dir() / "crack_rig_truth.yaml").read_text())
    raw["damping"] = {"kind": "rayleigh", "alpha": 0.0, "beta": 2e-6, "scope": "rotor"}
    for b in raw["bearings"]:
        b["cxx"] = b["cyy"] = 300.0
    machine = parse_config(raw, "dampers")
    f = np.linspace(30.0, 600.0, 262)
    T = io_frf(machine, f, 1000.0)[:, None]
    sysm = build_system(rig)
    a = fit_anchor(sysm, 1000.0, _dofs(rig), f, T)
    assert a is not None and a.misfit < 1e-3
    low = np.sort(a.poles.imag[np.abs(a.poles.imag / (2 * np.pi) - 54.5) < 1.5] / (2 * np.pi))
    assert low.size == 2 and low[1] - low[0] > 0.3
    monkeypatch.setattr(ma, "SPLIT_STARTS", ())
    stuck = fit_anchor(sysm, 1000.0, _dofs(rig), f, T)
    assert stuck is not None and stuck.misfit > 5e-3


def _xy_dofs(cfg: RigConfig) -> list[tuple[int, int]]:
    """Force at station 8 in x and in y, probes at stations 6 and 2 in x and y: every output against every input."""
    s = build_system(cfg)
    return [(s.dof(8, a, None), s.dof(st, b, None)) for a in ("x", "y") for st in (6, 2) for b in ("x", "y")]


def _direct_frf(cfg: RigConfig, dofs: list[tuple[int, int]], speed: float = 0.0) -> np.ndarray:
    """(f, P) m/N: the receptance of each (input, output) DOF pair at ``speed`` rpm (default at rest, the gyroscopic
    term with it) by a direct solve at every frequency."""
    from rotorcheck.fe.system import RPM_TO_RAD_S

    M, C, G, K = build_system(cfg).matrices(speed)
    D = C + speed * RPM_TO_RAD_S * G
    return np.array([[np.linalg.solve(K - x**2 * M + 1j * x * D, np.eye(K.shape[0])[:, a])[b] for a, b in dofs]
                     for x in W])


def _unrefused(*args: object) -> Any:
    """:func:`fit_anchor` of ``args`` with :data:`rotorcheck.modal_anchor.MAX_MISFIT` lifted, to read the misfit of a
    fit the rule would refuse."""
    import rotorcheck.modal_anchor as ma

    keep = ma.MAX_MISFIT
    ma.MAX_MISFIT = 10.0
    try:
        return fit_anchor(*args)  # type: ignore[arg-type]
    finally:
        ma.MAX_MISFIT = keep


def _aniso(cfg: RigConfig, factor: float) -> RigConfig:
    """The rig with every bearing's y stiffness ``factor`` times its x stiffness (the planes' modes apart)."""
    bearings = [b.model_copy(update={"kyy": factor * b.kxx}) for b in cfg.bearings]
    return cfg.model_copy(update={"bearings": bearings})


def test_modes_plane_by_plane_are_the_whole_systems(rig: RigConfig) -> None:
    """At rest the planes are uncoupled and each plane's modes are its own (FEModes.plane): with the planes apart
    (y bearings 1.3x stiffer: no repeated pole) they equal the whole system's eigen-decomposition (a second route)
    pole by pole and residue by residue; with the isotropic rig every mode is heard only at its own plane's pairs and
    the modes sum to the receptance of every pair (the cross pairs' zero included)."""
    from rotorcheck.fe.system import RPM_TO_RAD_S
    from rotorcheck.modal_anchor import _modes

    aniso = _aniso(rig, 1.3)
    system = build_system(aniso)
    dofs = _xy_dofs(aniso)
    planes = fe_modes(system, 0.0, dofs)
    assert planes.plane is not None and set(planes.plane.tolist()) == {0, 1}
    M, C, G, K = system.matrices(0.0)
    whole = _modes(M, C + 0.0 * RPM_TO_RAD_S * G, K, dofs)
    assert planes.poles.size == whole.poles.size
    for p in planes.poles:
        assert np.min(np.abs(whole.poles - p)) <= 1e-9 * abs(p)
        # modes the two planes share (insensitive to the bearings) are one repeated pole of the whole system, whose
        # residue is the block's: compare the residues summed over a pole
        mine = np.abs(planes.poles - p) <= 1e-6 * abs(p)
        theirs = np.abs(whole.poles - p) <= 1e-6 * abs(p)
        a, b = planes.residues[mine].sum(axis=0), whole.residues[theirs].sum(axis=0)
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-6 * np.abs(b).max())
    iso = fe_modes(build_system(rig), 0.0, dofs)
    assert iso.plane is not None
    for q in range(len(dofs)):
        heard = np.flatnonzero(np.abs(iso.residues[:, q]) > 0)
        assert heard.size == 0 or len(set(iso.plane[heard].tolist())) == 1
    direct = _direct_frf(rig, dofs)
    h = modal_frf(iso.poles, iso.residues, iso.real, W)
    assert np.max(np.abs(h - direct)) < 1e-6 * np.max(np.abs(direct))


def test_xy_probes_on_a_machine_whose_planes_differ_are_fitted_plane_by_plane(rig: RigConfig) -> None:
    """The isotropic model against x/y data of a machine whose y bearings are 2 % stiffer (its x and y modes
    apart): the modal fit keeps x and y modes apart, one pole per plane near each of the machine's, and explains
    the data to 1e-3 (one pole shared by both planes, as the model's repeated pole, left 100 % of it)."""
    dofs = _xy_dofs(rig)
    truth = _aniso(rig, 1.02)
    anchor = fit_anchor(build_system(rig), 0.0, dofs, F, _direct_frf(truth, dofs))
    assert anchor is not None and anchor.misfit < 1e-3
    true_poles = fe_modes(build_system(truth), 0.0, dofs).poles
    inside = true_poles[(true_poles.imag > W.min()) & (true_poles.imag < W.max())]
    assert anchor.poles.size == inside.size == 6  # 3 modes in the band, per plane
    for p in inside:
        assert np.min(np.abs(anchor.poles - p)) < 1e-4 * abs(p)


def test_a_quiet_pairs_noise_is_no_model_error_but_a_model_error_stays_one(rig: RigConfig) -> None:
    """x/y data of a machine whose planes differ (y bearings 2 % stiffer), with noise of one rms level at every
    pair, so that the quiet station-2 pairs are noisy relative to their size. Without the variance the fit's misfit
    is that noise (above MAX_MISFIT: refused); with it (a second route: Monte Carlo noise of known variance) the
    misfit is what lies beyond the noise: about 0, accepted, and the poles within 0.3 % of the machine's. A real
    model error (a mode the model lacks, ten noise levels at its peak: what fitted poles and residues cannot absorb)
    keeps a misfit well above that with the variance given."""
    from rotorcheck.modal_anchor import MAX_MISFIT

    dofs = _xy_dofs(rig)
    machine = _aniso(rig, 1.02)
    clean = _direct_frf(machine, dofs)
    rng = np.random.default_rng(3)
    sigma = 0.03 * np.max(np.abs(clean[:, 2]))  # 3 % of the station-2 x pair's largest value, at every pair
    var = np.full(clean.shape, sigma**2)
    noisy = clean + sigma / np.sqrt(2.0) * (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape))
    system = build_system(rig)
    plain = _unrefused(system, 0.0, dofs, F, noisy)
    aware = _unrefused(system, 0.0, dofs, F, noisy, var)
    assert plain is not None and aware is not None
    assert plain.misfit > MAX_MISFIT  # the noise read as misfit
    assert aware.misfit < 0.1 * MAX_MISFIT
    assert fit_anchor(system, 0.0, dofs, F, noisy, var) is not None
    true_poles = fe_modes(build_system(machine), 0.0, dofs).poles
    for p in aware.poles:
        assert np.min(np.abs(true_poles - p)) < 3e-3 * abs(p)
    # a model error beyond the noise: a mode the model lacks (300 Hz, 2 % damping) at every pair it hears, as large
    # as the noise at its peak at the quiet pairs: the misfit with the variance is about its share of the data
    lam = 2.0 * np.pi * 300.0 * (-0.02 + 1j * np.sqrt(1.0 - 0.02**2))
    peak = np.abs(1.0 / (1j * lam.imag - lam) + 1.0 / (1j * lam.imag - np.conj(lam)))
    heard = np.max(np.abs(clean), axis=0) > 1e-9 * np.max(np.abs(clean))
    extra = modal_frf(np.array([lam]), (10.0 * sigma / peak * heard)[None, :].astype(complex), np.array([False]), W)
    off = _unrefused(system, 0.0, dofs, F, noisy + extra, var)
    assert off is not None and off.misfit > 10.0 * max(aware.misfit, 1e-6)


def test_several_pairs_of_a_spinning_rotor_keep_the_plain_misfit(rig: RigConfig) -> None:
    """At 1000 rpm the planes couple (one set of modes): with several pairs the variance changes neither the fit nor
    its misfit (the noise is not taken out: the isotropic model's circular whirl modes are no description of an
    anisotropic machine's elliptical ones); with one pair it does take the noise out (a smaller misfit)."""
    system = build_system(rig)
    dofs = _xy_dofs(rig)
    T = _direct_frf(rig, dofs, 1000.0)
    rng = np.random.default_rng(5)
    sigma = 0.01 * np.max(np.abs(T[:, 2]))
    noisy = T + sigma / np.sqrt(2.0) * (rng.standard_normal(T.shape) + 1j * rng.standard_normal(T.shape))
    var = np.full(T.shape, sigma**2)
    plain = _unrefused(system, 1000.0, dofs, F, noisy)
    given = _unrefused(system, 1000.0, dofs, F, noisy, var)
    one_plain = _unrefused(system, 1000.0, dofs[2:3], F, noisy[:, 2:3])
    one_given = _unrefused(system, 1000.0, dofs[2:3], F, noisy[:, 2:3], var[:, 2:3])
    assert plain is not None and given is not None and plain.misfit == given.misfit > 0
    np.testing.assert_array_equal(plain.poles, given.poles)
    assert one_plain is not None and one_given is not None and one_given.misfit < one_plain.misfit


def test_projection_pair_by_pair_with_the_modes_each_hears() -> None:
    """The modal fit's linear part (modal_anchor._project) for pairs that hear different modes, solved once per set
    of modes, against one least squares per pair written out here: the same residues, constants and residual."""
    from rotorcheck.modal_anchor import _project

    rng = np.random.default_rng(3)
    lam = np.array([-2.0 + 100j, -3.0 + 180j, -4.0 + 260j])
    w = np.linspace(50.0, 320.0, 90)
    target = rng.standard_normal((90, 5)) + 1j * rng.standard_normal((90, 5))
    scale = rng.uniform(0.5, 2.0, 5)
    use = np.array([[1, 1, 0, 1, 0], [0, 1, 1, 0, 1], [1, 1, 1, 1, 0]], dtype=bool)
    coef, resid = _project(lam, w, target, scale, use)
    jw = 1j * w[:, None]
    basis = np.column_stack([1 / (jw - lam) + 1 / (jw - lam.conj()), 1j / (jw - lam) - 1j / (jw - lam.conj()),
                             np.ones_like(w), 1 / w**2])
    A = np.vstack([basis.real, basis.imag])
    for q in range(5):
        y = np.r_[(target[:, q] / scale[q]).real, (target[:, q] / scale[q]).imag]
        heard = np.flatnonzero(use[:, q])
        cols = np.r_[heard, heard + 3, 6, 7]
        ref = np.zeros(8)
        ref[cols] = np.linalg.lstsq(A[:, cols], y, rcond=None)[0]
        np.testing.assert_allclose(coef[:, q], ref, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(resid.reshape(180, 5)[:, q], y - A @ ref, rtol=1e-9, atol=1e-12)
