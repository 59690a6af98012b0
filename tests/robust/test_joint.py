"""The joint GLR test (rotorcheck.robust.joint) against closed forms and Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom, chi2, norm

from rotorcheck.robust.joint import GOF_SHARE, BenignModel, ModelForm, change_scale, joint_test

N = 60


def _signatures(rng: np.random.Generator, k: int) -> np.ndarray:
    base = rng.standard_normal(N) + 1j * rng.standard_normal(N)
    # correlated candidates (neighbouring elements look alike)
    return np.array([base + 0.7 * (rng.standard_normal(N) + 1j * rng.standard_normal(N)) for _ in range(k)])


def _noise(rng: np.random.Generator, var: np.ndarray) -> np.ndarray:
    return np.sqrt(var / 2) * (rng.standard_normal(var.size) + 1j * rng.standard_normal(var.size))


def test_single_candidate_is_the_one_sided_normal_closed_form() -> None:
    """No nuisance, one element: T = max(0, z)^2 with z = Re<s, r>_W / ||s||_W, the severity z / ||s||_W,
    the GLR's p = P(chi2_1 >= T) / 2 and its threshold at (1 - GOF_SHARE) of the rate; all recomputed here by
    hand."""
    rng = np.random.default_rng(1)
    var = rng.uniform(0.5, 2.0, N)
    s = _signatures(rng, 1)
    r = 0.3 * s[0] + _noise(rng, var)
    res = joint_test(r, var, s, [4], draws=400_000)
    wgt = 2.0 / var
    norm_s = np.sqrt(np.sum(wgt * np.abs(s[0]) ** 2))
    z = np.sum(wgt * (s[0].conj() * r).real) / norm_s
    assert res.statistic == pytest.approx(max(z, 0.0) ** 2, rel=1e-10)
    assert res.severity[0] == pytest.approx(z / norm_s, rel=1e-10)
    assert res.severity_se[0] == pytest.approx(1.0 / norm_s, rel=1e-10)
    assert res.glr_p_value == pytest.approx(0.5 * chi2.sf(res.statistic, 1), abs=3e-3)
    # the GLR spends (1 - GOF_SHARE) of 1 %: a one-sided normal at 0.9 %, z = 2.366, T = 5.60 (Monte Carlo: the
    # quantile's standard error at 400,000 draws is 2 z / phi(z) sqrt(a (1 - a) / n) = 0.028; 4 of them allowed)
    z_glr = norm.isf((1.0 - GOF_SHARE) * 0.01)
    assert z_glr == pytest.approx(2.3656, abs=1e-4)
    assert res.threshold == pytest.approx(z_glr**2, abs=0.11)
    # detectable loss: (z_0.991 + z_0.9) / ||s||_W
    assert res.detectable[0] == pytest.approx((z_glr + 1.2815515655446004) / norm_s, rel=7e-3)


def test_false_alarm_rate_with_benign_nuisance_by_monte_carlo() -> None:
    """H0 with a benign change inside its box (two real parameters, nonlinear) and noise: the stated rate
    holds within binomial scatter (600 sweeps at a 5 % rate)."""
    rng = np.random.default_rng(7)
    var = rng.uniform(0.5, 2.0, N)
    S = _signatures(rng, 4)
    B = rng.standard_normal((2, N)) + 1j * rng.standard_normal((2, N))

    def predict(theta: np.ndarray) -> np.ndarray:
        return theta[0] * B[0] + theta[1] * B[1] + 0.2 * theta[0] ** 2 * B[1]

    benign = BenignModel(predict, np.array([-1.0, -1.0]), np.array([1.0, 1.0]), ("a", "b"), 0.0, 1e-6)
    n, alpha = 600, 0.05
    hits = 0
    for _ in range(n):
        theta = rng.uniform(-0.6, 0.6, 2)
        r = predict(theta) + _noise(rng, var)
        hits += joint_test(r, var, S, [1, 2, 3, 4], benign, false_alarm=alpha, draws=20_000).damage
    lo, hi = binom.ppf([0.0005, 0.9995], n, alpha)
    assert lo <= hits <= hi, hits


def test_goodness_of_fit_is_the_chi_square_tail_and_shares_the_rate() -> None:
    """No nuisance: H0's chi2 is the whitened residual norm sum 2 |r|^2 / var on 2 N dof, its p-value the
    chi-square tail (scipy.stats, a second implementation), and the sweep's p-value the Bonferroni combination
    min(p_GLR / (1 - GOF_SHARE), p_fit / GOF_SHARE, 1)."""
    rng = np.random.default_rng(21)
    var = rng.uniform(0.5, 2.0, N)
    S = _signatures(rng, 3)
    for scale in (1.0, 1.3, 1.6):  # noise only, then noise larger than stated: the fit's p falls, the GLR's not
        r = np.sqrt(scale) * _noise(rng, var)
        res = joint_test(r, var, S, [1, 2, 3], draws=20_000)
        c2 = float(np.sum(2.0 * np.abs(r) ** 2 / var))
        assert res.chi2_h0 == pytest.approx(c2, rel=1e-12) and res.fit_dof == 2 * N
        assert res.fit_p_value == pytest.approx(chi2.sf(c2, 2 * N), rel=1e-9)
        assert res.p_value == pytest.approx(min(1.0, res.glr_p_value / (1 - GOF_SHARE), res.fit_p_value / GOF_SHARE))
        assert res.damage == (res.p_value < 0.01)


def test_a_large_change_no_signature_explains_is_damage_by_the_fit() -> None:
    """A change of the opposite sign to every crack signature (a stiffening, 5x a signature: what a loss far
    beyond the first-order signature can look like to it) gives T = 0, yet H0 fits it with chi2 far beyond its
    dof: damage, decided by the fit; the same change at 1/20 of the size is not."""
    rng = np.random.default_rng(22)
    var = np.ones(N)
    S = _signatures(rng, 3)
    big = joint_test(-5.0 * S[0] + _noise(rng, var), var, S, [1, 2, 3], draws=20_000)
    assert big.statistic == 0.0 and big.glr_p_value > 0.5
    assert big.damage and big.decided_by_fit and big.fit_p_value < 1e-12
    small = joint_test(-0.25 * S[0] + _noise(rng, var), var, S, [1, 2, 3], draws=20_000)
    assert not small.damage and not small.decided_by_fit


def test_goodness_of_fit_is_conservative_with_a_nuisance_and_a_model_form_prior() -> None:
    """H0 drawn as stated (benign parameters inside their box, model-form coefficients from their Gaussian prior,
    noise): the fit's p-value is uniform or larger (its dof count takes the prior's rows as unfitted, a
    conservative count): P(p_fit <= u) <= u within binomial scatter at u = 0.05, 0.2, 0.5 (400 sweeps)."""
    rng = np.random.default_rng(23)
    var = rng.uniform(0.5, 2.0, N)
    S = _signatures(rng, 2)
    B = rng.standard_normal((2, N)) + 1j * rng.standard_normal((2, N))
    V = 0.3 * (rng.standard_normal((6, N)) + 1j * rng.standard_normal((6, N)))
    scale = np.full(6, 1.0)
    benign = BenignModel(lambda t: t[0] * B[0] + t[1] * B[1], np.array([-1.0, -1.0]), np.array([1.0, 1.0]), ("a", "b"),
                         0.0, 1e-6, form=ModelForm(V, scale, "test"))
    n = 400
    p = np.array([joint_test(rng.uniform(-0.8, 0.8, 2) @ B + rng.normal(0.0, scale) @ V + _noise(rng, var), var, S,
                             [1, 2], benign, draws=5_000).fit_p_value for _ in range(n)])
    for u in (0.05, 0.2, 0.5):
        assert np.count_nonzero(p <= u) <= binom.ppf(0.9995, n, u), (u, np.count_nonzero(p <= u))
    # and not uselessly so: the p-values are not all near 1 (a dof far too large would put them there)
    assert np.count_nonzero(p <= 0.5) >= binom.ppf(0.0005, n, 0.25)


def test_power_at_the_stated_detectable_loss() -> None:
    """A loss of exactly ``detectable`` is found with about 90 % probability (no nuisance)."""
    rng = np.random.default_rng(3)
    var = rng.uniform(0.5, 2.0, N)
    S = _signatures(rng, 3)
    a = joint_test(np.zeros(N), var, S, [1, 2, 3], draws=100_000).detectable[1]
    n = 400
    hits = sum(joint_test(a * S[1] + _noise(rng, var), var, S, [1, 2, 3], draws=20_000).damage for _ in range(n))
    lo, hi = binom.ppf([0.0005, 0.9995], n, 0.9)
    assert lo <= hits <= hi, hits


def test_bounded_nuisance_cannot_absorb_a_change_beyond_its_range() -> None:
    """A change along a benign direction but 4x its range is damage; inside the range it is not; the
    fitted parameter is reported at the range edge."""
    rng = np.random.default_rng(5)
    var = np.ones(N)
    S = _signatures(rng, 2)
    B = S[0] + 0.3 * (rng.standard_normal(N) + 1j * rng.standard_normal(N))  # a crack looks like benign change
    benign = BenignModel(lambda t: t[0] * B, np.array([-1.0]), np.array([1.0]), ("e",), 0.0, 1e-6)
    inside = joint_test(0.8 * B + _noise(rng, var), var, S, [1, 2], benign)
    beyond = joint_test(4.0 * B + _noise(rng, var), var, S, [1, 2], benign)
    assert not inside.damage and abs(inside.theta[0] - 0.8) < 0.05
    assert beyond.damage and beyond.theta_at_bound[0]
    free = BenignModel(lambda t: t[0] * B, np.array([-10.0]), np.array([10.0]), ("e",), 0.0, 1e-6)
    assert not joint_test(4.0 * B + _noise(rng, var), var, S, [1, 2], free).damage


def test_a_parameter_at_its_range_end_is_beyond_it_only_when_the_data_push_it() -> None:
    """Two benign directions, noiseless data: ``a`` drifted to 1.5x its range end, ``b`` along a direction the
    data do not see (B_b = 0: any value fits), held at an end by a start there. The edge evidence of ``a`` is the
    closed form ||(1.5 - 1) B_a||_W^2 minus what the other directions take, well above 3.84: beyond the range;
    ``b``'s is 0: at the end but not beyond (its standard error infinite: nothing bounds it), and notes that say
    which is which."""
    rng = np.random.default_rng(11)
    var = np.ones(N)
    S = _signatures(rng, 2)
    Ba = rng.standard_normal(N) + 1j * rng.standard_normal(N)
    Ba = Ba * np.sqrt(400.0 / (2.0 * np.sum(np.abs(Ba) ** 2)))  # whitened squared norm (2 |B|^2 / var) 400 per unit a
    Bb = np.zeros(N, dtype=complex)
    benign = BenignModel(lambda t: t[0] * Ba + t[1] * Bb, np.array([-1.0, 0.0]), np.array([1.0, 1.0]), ("a", "b"),
                         0.0, 1e-6)
    res = joint_test(1.5 * Ba, var, S, [1, 2], benign)
    assert res.theta_at_bound[0] and res.theta[0] == pytest.approx(1.0)
    # what freeing a removes: the part of 0.5 B_a the crack-free nuisance could not take (here all of it)
    assert res.theta_edge_chi2 is not None
    assert res.theta_edge_chi2[0] == pytest.approx(0.25 * 400.0, rel=1e-6)
    assert res.theta_beyond_range[0]
    # b: at an end (it starts there: its range is [0, 1]) with no evidence beyond it
    assert res.theta_at_bound[1] and res.theta_edge_chi2[1] == pytest.approx(0.0, abs=1e-9)
    assert not res.theta_beyond_range[1] and res.theta_se[1] == np.inf
    assert any("push beyond their range: a" in n for n in res.notes)
    assert any("do not fix" in n and n.endswith(": b") for n in res.notes)


def test_a_change_the_benign_model_does_not_predict_is_no_excuse_for_itself() -> None:
    """With a model-error allowance (kappa = 2.5), a crack-shaped change a s_1 on top of a benign change
    inside its range, noiseless: the evidence keeps growing nearly as a^2 (10.3, 33.3, 91.3 for a = 0.5,
    1, 2: less than 4x per doubling because the bounded fit takes part of the change and the allowance
    follows it), where an allowance that also scaled with the observed change capped it (7.1, 8.6, 7.9);
    the allowance is kappa times the predicted benign change (windowed) only."""
    rng = np.random.default_rng(8)
    var = np.ones(N)
    S = _signatures(rng, 1)
    B = rng.standard_normal(N) + 1j * rng.standard_normal(N)
    benign = BenignModel(lambda t: t[0] * B, np.array([-1.0]), np.array([1.0]), ("e",), 2.5, 1e-6)
    e = np.zeros(N)  # noiseless: the statistic is then the signal's part alone
    t = [joint_test(0.5 * B + a * S[0] + e, var, S, [1], benign).statistic for a in (0.5, 1.0, 2.0)]
    assert t[0] > 3.0 and t[1] / t[0] > 2.5 and t[2] / t[1] > 2.5
    res = joint_test(0.5 * B + 2.0 * S[0] + e, var, S, [1], benign)
    np.testing.assert_allclose(res.model_error, 2.5 * change_scale(res.theta[0] * B), rtol=1e-12)


def test_change_scale_is_a_windowed_maximum() -> None:
    rng = np.random.default_rng(2)
    b = rng.standard_normal(30) + 1j * rng.standard_normal(30)
    got = change_scale(b, 2)
    ref = [max(np.abs(b)[max(0, k - 2): k + 3]) for k in range(30)]
    np.testing.assert_allclose(got, ref)


def test_change_scale_never_exceeds_the_benign_envelope() -> None:
    rng = np.random.default_rng(4)
    b = 3 * rng.standard_normal(30)
    env = rng.uniform(0.5, 3.0, 30)
    np.testing.assert_allclose(change_scale(b, 0, envelope=env), np.minimum(np.abs(b), env))


def test_points_left_unexplained_hold_their_family_rate_and_find_an_outlier() -> None:
    """Per-point remainder after the H0 fit: chi2 with 2 dof per point, Sidak over the points: pure noise
    flags a sweep at the stated rate (Monte Carlo, 400 sweeps at 5 %); a planted 8-sigma point is found."""
    rng = np.random.default_rng(9)
    var = rng.uniform(0.5, 2.0, N)
    S = _signatures(rng, 2)
    alpha, n = 0.05, 400
    res = [joint_test(_noise(rng, var), var, S, [1, 2], false_alarm=alpha, draws=2_000) for _ in range(n)]
    assert res[0].point_threshold == pytest.approx(-2 * np.log(1 - (1 - alpha) ** (1 / N)), rel=1e-12)
    hits = sum(bool(r.remaining.any()) for r in res)
    lo, hi = binom.ppf([0.0005, 0.9995], n, alpha)
    assert lo <= hits <= hi, hits
    r = _noise(rng, var)
    r[17] += 8.0 * np.sqrt(var[17])
    assert joint_test(r, var, S, [1, 2], draws=2_000).remaining[17]


def test_a_benign_model_at_some_points_is_the_test_with_the_others_left_out() -> None:
    """``BenignModel.at(idx)`` (prediction, envelope and model-form prior at those points only) against a second
    route: the full model with the other points excluded (weight 0 everywhere). Same statistic and fit."""
    from rotorcheck.robust.joint import BenignModel, ModelForm, joint_test

    rng = np.random.default_rng(7)
    n = 40
    shape = np.exp(1j * np.linspace(0, 3, n)) / (1 + np.linspace(0, 2, n))
    crack = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    bm = BenignModel(lambda th: th[0] * shape, np.array([-1.0]), np.array([1.0]), ("e",), 0.0,
                     form=ModelForm(np.array([np.ones(n, dtype=complex), 1j * np.linspace(0, 1, n)]),
                                    np.array([0.05, 0.02]), "two directions"),
                     envelope=np.abs(shape))
    r = 0.3 * shape + 0.04 * crack + 0.01 * (rng.standard_normal(n) + 1j * rng.standard_normal(n))
    var = np.full(n, 2e-4)
    idx = np.flatnonzero(np.arange(n) % 3 != 0)
    out = np.ones(n, dtype=bool)
    out[idx] = False
    a = joint_test(r[idx], var[idx], crack[None, idx], [4], bm.at(idx), draws=2000)
    b = joint_test(r, var, crack[None, :], [4], bm, draws=2000, exclude=out)
    assert a.statistic == pytest.approx(b.statistic, rel=1e-6)
    assert a.theta == pytest.approx(b.theta, rel=1e-6)


def test_the_verdict_says_which_part_of_the_rule_decided() -> None:
    """The sweep verdict (workflow.detectors.joint.joint_verdict) of a change the GLR finds names T against its
    threshold; of one only the fit refutes, H0's chi2 on its dof and that no small loss of one element explains it;
    a healthy one gives both figures."""
    from rotorcheck.robust.validation import Verdict
    from rotorcheck.workflow.detectors.joint import joint_verdict

    rng = np.random.default_rng(24)
    var = np.ones(N)
    S = _signatures(rng, 2)
    points = Verdict("healthy", "", N, 0, 0, 0, 1)
    by_glr = joint_test(1.5 * S[0] + _noise(rng, var), var, S, [1, 2], draws=20_000)
    by_fit = joint_test(-5.0 * S[0] + _noise(rng, var), var, S, [1, 2], draws=20_000)
    healthy = joint_test(_noise(rng, var), var, S, [1, 2], draws=20_000)
    assert by_glr.damage and not by_glr.decided_by_fit and by_fit.decided_by_fit and not healthy.damage
    v = joint_verdict(by_glr, points)
    assert v.verdict == "damage" and f"T = {by_glr.statistic:.4g} > {by_glr.threshold:.4g}" in v.reason
    v = joint_verdict(by_fit, points)
    assert v.verdict == "damage" and f"chi2 = {by_fit.chi2_h0:.5g} on {by_fit.fit_dof} dof" in v.reason
    assert "no small loss of one element explains the rest" in v.reason
    v = joint_verdict(healthy, points)
    assert v.verdict == "healthy" and "<=" in v.reason and f"on {healthy.fit_dof} dof" in v.reason
