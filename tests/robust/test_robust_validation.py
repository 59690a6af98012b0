"""Validation (gamma_h), detection (fault points) and the sweep verdict."""

from __future__ import annotations

import numpy as np
import pytest

from rotorcheck.robust import closed_form as cf
from rotorcheck.robust import detect, lft, noise_bound_manual, validate, verdict


def rotor_like(seed: int, n: int = 120) -> dict[str, np.ndarray]:
    """Two-mode receptance truth, a model with a few % error, forces 1-10 N, noise inside V."""
    rng = np.random.default_rng(seed)
    fr = np.geomspace(30, 600, n)
    w = 2 * np.pi * fr

    def rec(fn: np.ndarray, z: np.ndarray, A: np.ndarray) -> np.ndarray:
        wr = 2 * np.pi * fn
        return np.sum(A / (wr**2 - w[:, None] ** 2 + 2j * z * wr * w[:, None]), axis=1)

    truth = rec(np.array([54.0, 173.0]), np.array([0.01, 0.015]), np.array([0.1, 0.3]))
    model = rec(np.array([54.0, 175.0]), np.array([0.011, 0.015]), np.array([0.1, 0.29]))
    W = rng.uniform(1, 10, n) * np.exp(2j * np.pi * rng.uniform(size=n))
    V = 2e-8
    return {"fr": fr, "truth": truth, "model": model, "W": W, "V": V, "rng": rng}


def bounded_noise(rng: np.random.Generator, n: int, V: float) -> np.ndarray:
    """Noise uniform in the disk of radius 0.95 V (so |v| <= V holds by construction)."""
    return 0.95 * V * np.sqrt(rng.uniform(size=n)) * np.exp(2j * np.pi * rng.uniform(size=n))


def test_validate_data_and_system_vs_closed_forms_and_several_sweeps() -> None:
    d = rotor_like(0)
    rng, V = d["rng"], d["V"]
    Zt1 = d["truth"] * d["W"] + bounded_noise(rng, d["W"].size, V)
    Zt2 = d["truth"] * d["W"] + bounded_noise(rng, d["W"].size, V)
    me = lft.additive_me(d["model"])
    v1 = validate(me, d["W"], Zt1, noise_bound_manual(V), enclose="data")
    ref1 = cf.gamma_required_additive(d["model"], d["W"], Zt1, V)
    assert v1.enclosed
    np.testing.assert_allclose(v1.gamma, ref1, rtol=1e-6)
    assert np.all(v1.gamma >= v1.gamma_lower)
    vs = validate(me, d["W"], Zt1, V, enclose="system")
    np.testing.assert_allclose(vs.gamma, cf.gamma_enclose_additive(d["model"], d["W"], Zt1, V),
                               rtol=1e-12)
    both = validate(me, [d["W"], d["W"]], [Zt1, Zt2], V, enclose="data")
    ref2 = cf.gamma_required_additive(d["model"], d["W"], Zt2, V)
    np.testing.assert_allclose(both.gamma, np.maximum(ref1, ref2), rtol=1e-6)
    assert len(both.per_sweep) == 2


def test_detection_matches_closed_form_decisions_and_repeat_sweep_false_alarms() -> None:
    d = rotor_like(1)
    rng, V, W = d["rng"], d["V"], d["W"]
    n = W.size
    me = lft.additive_me(d["model"])
    Zh = d["truth"] * W + bounded_noise(rng, n, V)
    val_data = validate(me, W, Zh, V, enclose="data")
    val_sys = validate(me, W, Zh, V, enclose="system")
    # damaged: first mode 3 % lower
    w = 2 * np.pi * d["fr"]
    dmg = d["truth"] + 0.1 / ((2 * np.pi * 54.0) ** 2 - w**2 + 2j * 0.01 * 2 * np.pi * 54 * w) - \
        0.1 / ((2 * np.pi * 52.4) ** 2 - w**2 + 2j * 0.01 * 2 * np.pi * 52.4 * w)
    Zd = dmg * W + bounded_noise(rng, n, V)
    det = detect(me, W, Zd, V, val_data.gamma)
    need = cf.gamma_required_additive(d["model"], W, Zd, V)
    ref_fault = need > val_data.gamma * (1 + 1e-6)
    clear = np.abs(need - val_data.gamma) > 1e-5 * val_data.gamma  # away from the tie
    assert np.array_equal(det.fault[clear], ref_fault[clear])
    assert set(np.unique(det.status)) <= {"ok", "fault"}
    np.testing.assert_allclose(det.gamma_required, need, rtol=1e-6)
    assert det.n_fault > 10
    # repeat healthy sweep with fresh bounded noise: 'system' never alarms, 'data' does
    Zr = d["truth"] * W + bounded_noise(rng, n, V)
    fa_data = detect(me, W, Zr, V, val_data.gamma).n_fault
    fa_sys = detect(me, W, Zr, V, val_sys.gamma).n_fault
    print(f"\nrepeat healthy sweep false alarms: enclose='data' {fa_data}/{n}, "
          f"enclose='system' {fa_sys}/{n}")
    assert fa_sys == 0
    assert fa_data > 0


def test_detection_failure_injection_and_unexplainable() -> None:
    d = rotor_like(2, n=30)
    rng, V, W = d["rng"], d["V"], d["W"]
    me = lft.additive_me(d["model"])
    Zh = d["truth"] * W + bounded_noise(rng, W.size, V)
    gh = validate(me, W, Zh, V).gamma
    Zd = 1.3 * Zh
    det = detect(me, W, Zd, V, gh, fail_at=[4])
    assert det.status[4] == "solver_failed" and not det.fault[4]
    assert np.isnan(det.gamma_required[4])
    assert np.all(det.status[np.arange(30) != 4] != "solver_failed")
    v = verdict(det.fault, det.status)
    assert v.verdict == "damage"  # certified fault points count despite the failed point
    # baseline failure at one point
    val = validate(me, W, Zh, V, fail_at=[7])
    assert val.status[7] == "solver_failed" and np.isnan(val.gamma[7]) and not val.enclosed
    det2 = detect(me, W, Zh, V, val.gamma)
    assert det2.status[7] == "no_baseline"
    assert verdict(det2.fault, det2.status, val.status).verdict == "inconclusive"
    # the uncertainty cannot move the output: unexplainable, counted as a fault
    me0 = me.copy()
    me0[:, 0, 1] = 0.0
    det3 = detect(me0, W, Zd, V, gh)
    outside = np.abs(Zd - d["model"] * W) > V
    assert np.all(det3.status[outside] == "unexplainable") and np.all(det3.fault[outside])


@pytest.mark.parametrize(
    ("fault_idx", "status_bad", "healthy_bad", "expected"),
    [
        ([], [], [], "healthy"),
        ([10], [], [], "healthy"),
        ([10, 50], [], [], "healthy"),
        ([10, 11], [], [], "damage"),  # a run of two adjacent fault points
        ([10, 50, 90], [], [], "damage"),  # three points (2 % of 100 is 2)
        ([10], [40], [], "inconclusive"),
        ([], [], [3], "inconclusive"),
        ([10, 11], [40], [3], "damage"),
    ],
)
def test_verdict_rule(fault_idx: list[int], status_bad: list[int], healthy_bad: list[int],
                      expected: str) -> None:
    n = 100
    fault = np.zeros(n, bool)
    fault[fault_idx] = True
    status = np.where(fault, "fault", "ok").astype("<U13")
    status[status_bad] = "solver_failed"
    hs = np.full(n, "ok", dtype="<U13")
    hs[healthy_bad] = "unexplainable"
    v = verdict(fault, status, hs)
    assert v.verdict == expected, v.reason
    assert v.n_fault == len(fault_idx)


def test_verdict_fraction_threshold_for_long_sweeps() -> None:
    n = 1000  # 2 % of 1000 = 20 points needed when isolated
    fault = np.zeros(n, bool)
    fault[::100] = True  # 10 isolated points
    status = np.where(fault, "fault", "ok")
    v = verdict(fault, status)
    assert v.verdict == "healthy" and v.threshold == 20
    fault[::50] = True  # 20 isolated points
    assert verdict(fault, np.where(fault, "fault", "ok")).verdict == "damage"
