"""What a rig, its sensors and its noise can detect (issue 19), against independent references: the
closed-form likelihood-ratio limit, limits.md's noise formula, a Monte Carlo of the joint test itself,
and the rule that more channels can only help."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rotorcheck.cli import EXIT_INPUT, EXIT_OK, main
from rotorcheck.config import Port, RigConfig, load_config
from rotorcheck.detectability import detectability, stated_noise_variance, z_upper
from rotorcheck.nominal import ChannelPair, primary_pair
from rotorcheck.resources import configs_dir
from rotorcheck.robust.joint import POWER_Z, joint_test
from rotorcheck.signatures import crack_signatures, io_frf

F = np.linspace(30.0, 600.0, 131)
V = stated_noise_variance(2e-7, 64, 64, 1.0)


@pytest.fixture(scope="module")
def rig() -> RigConfig:
    return load_config(configs_dir() / "crack_rig.yaml")


def _noise_only(cfg: RigConfig) -> RigConfig:
    return cfg.model_copy(update={"variability": []})


def test_stated_noise_variance_is_limits_md_figure() -> None:
    # limits.md: "v = 4 sigma^2 / (M N) = 3.9e-17 m^2 per point at 1x" (sigma 2e-7 m, 64 x 64 samples, 1 N)
    assert V == pytest.approx(3.9e-17, rel=2e-3)


def test_one_candidate_detector_equals_the_closed_form_limit(rig: RigConfig) -> None:
    """With one candidate element the joint test's threshold is z_(1-alpha)^2 (one-sided normal squared),
    so its 90 % detectable loss equals the likelihood-ratio limit (z_(1-alpha) + z_0.9) / ||s||_w; the
    test's threshold comes from its Monte Carlo, the limit from the normal quantile."""
    var = np.full(F.size, V)
    d = detectability(_noise_only(rig), F, 1000.0, var, var, [primary_pair(rig)], elements=[4], candidates=[4])
    e = next(x for x in d.elements if x.element == 4)
    assert e.open_loss_min_noise_only == pytest.approx(e.limit_open_loss_noise_only, rel=0.015)
    th = io_frf(rig, F, 1000.0)
    _, S = crack_signatures(rig, F, 1000.0, th, [4], modal=False)  # the model's own FRF: re-solved, as there
    norm = np.sqrt(np.sum(2.0 * np.abs(S[0]) ** 2 / (2 * V)))
    assert e.limit_open_loss_noise_only == pytest.approx((z_upper(0.01) + POWER_Z) / norm, rel=1e-9)
    assert e.open_loss_min == e.open_loss_min_noise_only  # no benign ranges: the same
    assert any("no benign variability" in n for n in d.notes)


def test_noise_only_prediction_holds_in_a_monte_carlo_of_the_joint_test(rig: RigConfig) -> None:
    """Draw both sweeps' noise at the stated variance onto a crack of the predicted loss in element 4 and
    run the joint test (every candidate element) 300 times: about 90 % detected; at 1/1.5 of it, far fewer."""
    cfg = _noise_only(rig)
    var = np.full(F.size, V)
    d = detectability(cfg, F, 1000.0, var, var, [primary_pair(cfg)])
    a = next(x for x in d.elements if x.element == 4).open_loss_min_noise_only
    assert a is not None
    th = io_frf(cfg, F, 1000.0)
    els, S = crack_signatures(cfg, F, 1000.0, th)
    s4 = S[els.index(4)]
    rng = np.random.default_rng(19)
    tot = 2 * V

    def rate(loss: float, n: int = 300) -> float:
        hits = 0
        for _ in range(n):
            noise = np.array([1.0, 1j]) @ rng.normal(scale=np.sqrt(tot / 2), size=(2, F.size))
            hits += joint_test(loss * s4 + noise, np.full(F.size, tot), S, els, draws=20_000).damage
        return hits / n

    assert 0.85 <= rate(a) <= 0.95
    assert rate(a / 1.5) < 0.75


def test_benign_ranges_cost_detectability_and_more_channels_help(rig: RigConfig) -> None:
    from rotorcheck.workflow import KAPPA_NOMINAL, benign_model

    var = np.full(F.size, V)
    th = io_frf(rig, F, 1000.0)
    bm = benign_model(rig, F, 1000.0, th, KAPPA_NOMINAL)
    d = detectability(rig, F, 1000.0, var, var, [primary_pair(rig)], th, 0.01, bm, elements=[3, 4], workers=1)
    for e in d.elements:
        assert e.open_loss_min is not None and e.open_loss_min_noise_only is not None
        assert e.open_loss_min > 10 * e.open_loss_min_noise_only  # limits.md 3: benign change, not noise, limits
        # (None: no depth up to 50 % finds it with 90 % power)
        assert e.breathing_depth_min is None or e.breathing_depth_min > e.breathing_depth_min_noise_only
    # x and y probes at two stations see more than one probe: every element's limit drops
    act = rig.io_ports("test").actuator
    probes = [Port(station=6, direction="x"), Port(station=6, direction="y"), Port(station=2, direction="x"),
              Port(station=2, direction="y")]
    pairs = [ChannelPair(p, act, "") for p in probes]
    cfg = _noise_only(rig)
    one = detectability(cfg, F, 1000.0, var, var, [primary_pair(cfg)])
    four = detectability(cfg, F, 1000.0, np.full((F.size, 4), V), np.full((F.size, 4), V), pairs)
    for a, b in zip(one.elements, four.elements):
        if a.limit_open_loss_noise_only is not None:
            assert b.limit_open_loss_noise_only is not None
            assert b.limit_open_loss_noise_only <= a.limit_open_loss_noise_only * (1 + 1e-9)
    assert four.sensors == ("s6.x", "s6.y", "s2.x", "s2.y")


def test_detectability_cli(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    quiet = tmp_path / "rig.yaml"
    text = (configs_dir() / "crack_rig.yaml").read_text()
    quiet.write_text(text[: text.index("variability:")])  # noise only: fast
    out = tmp_path / "out"
    args = ["detectability", str(quiet), "--noise-std", "2e-7", "--speed", "1000", "--elements", "3,4", "--out",
            str(out), "--json"]
    assert main(args) == EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    assert {"speed_rpm", "false_alarm", "sensors", "elements"} <= set(doc)
    assert doc["speed_rpm"] == 1000.0 and doc["sensors"] == ["s6.x"]
    keys = {"element", "z_start_m", "z_end_m", "open_loss_min", "open_loss_min_noise_only", "breathing_depth_min",
            "breathing_depth_min_noise_only", "limit_breathing_depth_noise_only"}
    assert [e["element"] for e in doc["elements"]] == [3, 4] and keys <= set(doc["elements"][0])
    assert (out / "detectability.png").exists()
    assert main(args) == EXIT_INPUT  # exists, no --force
    capsys.readouterr()
    assert main(["detectability", str(quiet), "--out", str(tmp_path / "o2")]) == EXIT_INPUT  # no noise stated
    assert "output_noise_std" in capsys.readouterr().err


def test_sensor_sets_are_ranked_exhaustively_then_greedily(rig: RigConfig) -> None:
    """Every set of up to 2 of 3 ports is scored once (3 + 3); the ranking is sorted by the worst element;
    the best pair watches its worst element at least as well as the best single probe (LR: more data); with
    the exhaustive limit at 0 the greedy search evaluates 3 + 2 sets and ends on a 2-port set."""
    from rotorcheck.detectability import rank_sensor_sets, score_sensor_set

    cfg = _noise_only(rig)
    act = [cfg.io_ports("test").actuator]
    cand = [Port(station=6, direction="x"), Port(station=2, direction="x"), Port(station=4, direction="x")]
    ranked, method, seen = rank_sensor_sets(cfg, F, 1000.0, V, cand, act, 2, lambda p, t: None, workers=1)
    assert method == "exhaustive" and len(ranked) == 6
    keys = [s.key() for s in ranked]
    assert keys == sorted(keys)
    singles = [s for s in ranked if len(s.sensors) == 1]
    assert ranked[0].key() <= min(s.key() for s in singles)
    alone = score_sensor_set(cfg, F, 1000.0, V, [cand[0]], act, lambda p, t: None, 0.01, seen)
    assert alone.key() == next(s for s in singles if s.sensors == ("s6.x",)).key()
    greedy, method, _ = rank_sensor_sets(cfg, F, 1000.0, V, cand, act, 2, lambda p, t: None, exhaustive_limit=0,
                                         workers=1)
    assert method == "greedy" and len(greedy) == 5 and len(greedy[0].sensors) == 2


def test_a_stacked_healthy_frf_is_read_pair_after_pair(rig: RigConfig) -> None:
    """The benign prediction of several channel pairs is the same whether the healthy FRF comes as (f, P)
    or stacked (pair after pair): a row-major reshape of the stacked vector interleaved the pairs (a defect
    that made x/y probes look immune to benign change)."""
    from rotorcheck.signatures import benign_prediction, stacked

    act = rig.io_ports("test").actuator
    pairs = [ChannelPair(Port(station=s, direction=d), act, "") for s in (6, 2) for d in "xy"]
    th = io_frf(rig, F, 1000.0, pairs)
    # the model re-solved (modal=False): exact against the brute-force solve below; the modal anchor's own
    # accuracy is tests/test_modal_anchor.py's
    a = benign_prediction(rig, F, 1000.0, th, pairs=pairs, modal=False).predict(np.array([0.01, 0.0, 0.0, 0.0, 0.0]))
    b = benign_prediction(rig, F, 1000.0, stacked(th), pairs=pairs, modal=False).predict(
        np.array([0.01, 0.0, 0.0, 0.0, 0.0]))
    np.testing.assert_array_equal(a, b)
    am = benign_prediction(rig, F, 1000.0, th, pairs=pairs).predict(np.array([0.01, 0.0, 0.0, 0.0, 0.0]))
    bm = benign_prediction(rig, F, 1000.0, stacked(th), pairs=pairs).predict(np.array([0.01, 0.0, 0.0, 0.0, 0.0]))
    np.testing.assert_array_equal(am, bm)
    # E +1 %: the largest change is on the pair that responds most (6x), as the re-solved model says
    g = io_frf(rig.model_copy(update={"materials": {k: m.model_copy(update={
        "youngs_modulus": 1.01 * m.youngs_modulus, "shear_modulus": 1.01 * (m.shear_modulus or 0) or None})
        for k, m in rig.materials.items()}}), F, 1000.0, pairs)
    np.testing.assert_allclose(a, stacked(g - th), rtol=1e-6, atol=1e-6 * np.abs(th).max())


def test_sensor_ranking_with_only_blind_candidates_is_an_input_error_not_a_crash() -> None:
    """y probes of an x force at standstill see no element (the planes decouple): said as the option's error,
    never a ValueError from an empty max (a set of them among others scores as undetectable)."""
    from rotorcheck.config import load_config
    from rotorcheck.errors import InputError
    from rotorcheck.workflow import sensor_ranking_for_rig

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    with pytest.raises(InputError, match="--candidate-sensors: no candidate sensor sees any shaft element"):
        sensor_ranking_for_rig(cfg, ["2y", "6y"], 1, speed_rpm=0.0, noise_std_m=2e-7)


def test_channels_that_see_no_element_give_undetectable_rows_not_a_crash() -> None:
    """Two y probes of an x force at standstill: the planes decouple, the receptances are exactly 0, no element
    changes them; every element reported undetectable, with the reason in the notes."""
    from rotorcheck.nominal import parse_port
    from rotorcheck.signatures import io_frf

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    f = np.linspace(30.0, 600.0, 40)
    pairs = [ChannelPair(parse_port(s, "--sensor"), parse_port("8x", "--actuator"), "") for s in ("2y", "6y")]
    th = io_frf(cfg, f, 0.0, pairs)
    assert np.all(th == 0.0)
    var = np.full(th.shape, 1e-17)
    det = detectability(cfg, f, 0.0, var, var, pairs, th, 0.01, None, [3, 4], workers=1, model_frf=th)
    assert [(r.element, r.open_loss_min, r.breathing_depth_min_noise_only) for r in det.elements] == [
        (3, None, None), (4, None, None)]
    assert any("see no shaft element" in n for n in det.notes)


def _with_sensor(cfg: RigConfig, sensor: Port) -> RigConfig:
    """``cfg`` whose own sensor (the primary pair's output) is ``sensor``: the same mechanics."""
    assert cfg.ports is not None
    return cfg.model_copy(update={"ports": cfg.ports.model_copy(update={"sensor": sensor})})


def test_a_single_channel_other_than_the_rigs_own_is_scored_as_that_channel(rig: RigConfig) -> None:
    """One channel pair that is not the rig's own is that pair (a defect scored every single pair as the rig's
    own s6.x): its figures equal those of a rig whose own sensor it is (the primary path, nominal model) and
    the rig's own pair's equal those of a rig that sees it as another pair (the several-pair path); the two
    channels differ (s2.x sits beside a bearing: 20-80x larger limits)."""
    cfg = _noise_only(rig)
    act = cfg.io_ports("test").actuator
    s2, s6 = Port(station=2, direction="x"), Port(station=6, direction="x")
    var = np.full(F.size, V)
    as_other = detectability(cfg, F, 1000.0, var, var, [ChannelPair(s2, act, "")])
    as_own = detectability(_with_sensor(cfg, s2), F, 1000.0, var, var, [primary_pair(_with_sensor(cfg, s2))])
    own = detectability(cfg, F, 1000.0, var, var, [primary_pair(cfg)])
    own_as_other = detectability(_with_sensor(cfg, s2), F, 1000.0, var, var, [ChannelPair(s6, act, "")])
    for a, b in ((as_other, as_own), (own, own_as_other)):
        assert [e.element for e in a.elements] == [e.element for e in b.elements]
        for x, y in zip(a.elements, b.elements):
            for key in ("open_loss_min_noise_only", "limit_open_loss_noise_only"):
                u, v = getattr(x, key), getattr(y, key)
                assert (u is None) == (v is None) and (u is None or u == pytest.approx(v, rel=1e-9))
    e4 = {d.sensors: next(e for e in d.elements if e.element == 4) for d in (own, as_other)}
    limit_6, limit_2 = e4[("s6.x",)].limit_open_loss_noise_only, e4[("s2.x",)].limit_open_loss_noise_only
    assert limit_6 is not None and limit_2 is not None and limit_2 > 20 * limit_6


def test_single_sensor_sets_are_ranked_by_their_own_channel(rig: RigConfig) -> None:
    """The sensor ranking with the benign ranges: the candidate sets s2.x and s6.x score differently (they
    scored alike when a single pair was taken as the rig's own), and each as the same set does on a rig whose
    own sensor it is (the rig's current set, scored by the primary path)."""
    from rotorcheck.workflow import sensor_ranking_for_rig

    got = sensor_ranking_for_rig(rig, ["2x", "6x"], 1, speed_rpm=0.0, noise_std_m=2e-7)
    by = {tuple(s["sensors"]): s for s in got["best"]}
    assert set(by) == {("s2.x",), ("s6.x",)}
    assert by[("s2.x",)]["worst_open_loss_min"] != pytest.approx(by[("s6.x",)]["worst_open_loss_min"], rel=0.05)
    assert got["current"] == by[("s6.x",)]  # the rig's own sensor, by the primary path
    other = sensor_ranking_for_rig(_with_sensor(rig, Port(station=2, direction="x")), ["6x"], 1, speed_rpm=0.0,
                                   noise_std_m=2e-7)
    for key in ("worst_open_loss_min", "worst_breathing_depth_min"):
        for a, b in ((other["current"], by[("s2.x",)]), (other["best"][0], by[("s6.x",)])):
            assert (a[key] is None) == (b[key] is None) and (a[key] is None or a[key] == pytest.approx(b[key],
                                                                                                      rel=1e-6))
