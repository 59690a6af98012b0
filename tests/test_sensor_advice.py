"""The sensor set that would locate a damage not locatable with the sensors measured (issue 30): a 10 % loss in
element 4 at standstill, one probe (6x), is not locatable (simulated on the nominal rig with the truth rig's
noise, 80 points); the advice names a larger set, and that set, simulated, locates it; the advice's figures
against independent routes (detectability for the set; the set's own model solved alone)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from rotorcheck import workflow
from rotorcheck.config import Crack, Port, RigConfig, load_config
from rotorcheck.detectability import detectability, linearized
from rotorcheck.nominal import ChannelPair, parse_port
from rotorcheck.resources import configs_dir
from rotorcheck.sensor_advice import Hypothesis, candidate_model, describe_ports
from rotorcheck.sim.rig_sim import simulate_rig, simulate_rig_patterns, step_settings
from rotorcheck.workflow import KAPPA_NOMINAL, benign_model

GRID = np.linspace(30.0, 600.0, 80)
ACT = Port(station=8, direction="x")


@pytest.fixture(scope="module")
def rigs() -> tuple[RigConfig, RigConfig, RigConfig]:
    """(nominal rig, the same with the truth rig's measurement noise, that with a 10 % loss in element 4)."""
    cfg = load_config(configs_dir() / "crack_rig.yaml")
    sim = cfg.model_copy(update={"measurement": load_config(configs_dir() / "crack_rig_truth.yaml").measurement})
    crack = sim.model_copy(update={"faults": {**sim.faults, "loc": Crack(element=4, model="open", modulus_factor=0.9)}})
    return cfg, sim, crack


def _runs(rigs: tuple[RigConfig, RigConfig, RigConfig], sensors: list[Port] | None) -> tuple[Any, Any]:
    cfg, sim, crack = rigs
    st = step_settings(sim, keep_periods=False)
    if sensors is None:
        h = simulate_rig(sim, GRID, 0.0, seed=11, settings=st)
        n = simulate_rig(crack, GRID, 0.0, "loc", 12, settings=st)
    else:
        h = simulate_rig_patterns(sim, GRID, [ACT], sensors, 0.0, seed=11, settings=st)
        n = simulate_rig_patterns(crack, GRID, [ACT], sensors, 0.0, fault="loc", seed=12, settings=st)
    return workflow.measured_run(h, cfg), workflow.measured_run(n, cfg)


@pytest.fixture(scope="module")
def one_probe(rigs: tuple[RigConfig, RigConfig, RigConfig]) -> tuple[Any, Any, Any]:
    """(location inputs, new run, location) of the one-probe case: the ranking only, damage known."""
    healthy, new = _runs(rigs, None)
    est = workflow.healthy_estimate([healthy])
    inp = workflow.locating.location_inputs(rigs[0], new, est.frf, est.var, 0.0)
    res = workflow.locate_run(rigs[0], new, est.frf, est.var, 0.0, certify=False, damage=True)
    return inp, new, res


def test_not_locatable_with_one_probe_names_a_set_that_locates_it(rigs: tuple[RigConfig, RigConfig, RigConfig],
                                                                  one_probe: tuple[Any, Any, Any]) -> None:
    """The advice is in the summary and the JSON; its set, simulated with those channels (same seeds), ranks
    element 4 first and locates it (relative likelihood at least 0.5)."""
    _, _, res = one_probe
    assert res.kind == "not locatable" and res.ranked[0].element == 4
    detail = res.sensor_advice_detail
    assert detail is not None and detail["best"] is not None and detail["best"]["located"]
    assert not detail["current"]["located"]  # the measured probe is predicted not to locate it either
    assert detail["hypotheses"] == [{"element": 4, "loss": pytest.approx(res.ranked[0].loss_estimate)}]
    sensors = detail["best"]["sensors"]
    assert sensors[0] == "s6.x" and len(sensors) > 1
    assert res.sensor_advice in res.summary() and "would locate" in res.sensor_advice
    assert res.to_dict()["sensor_advice_detail"] == detail
    healthy, new = _runs(rigs, [parse_port(s, "--sensor") for s in sensors])
    est = workflow.healthy_estimate([healthy])
    more = workflow.locate_run(rigs[0], new, est.frf, est.var, 0.0, certify=False, damage=True)
    assert more.kind in ("located", "ranked") and more.ranked[0].element == 4
    assert more.kind == "located" and not more.sensor_advice


def test_the_advice_quotes_detectability_for_its_set(rigs: tuple[RigConfig, RigConfig, RigConfig],
                                                     one_probe: tuple[Any, Any, Any]) -> None:
    """The advice's detectable loss equals rotorcheck.detectability's for the advised set, its noise and benign
    model built here from the run (median variance over the pairs, the model's receptance as the healthy FRF)."""
    cfg = rigs[0]
    inp, _, res = one_probe
    detail = res.sensor_advice_detail
    assert detail is not None
    pairs = [ChannelPair(parse_port(s, "--sensor"), ACT, "") for s in detail["best"]["sensors"]]
    vn = np.tile(np.median(inp.change.var_new, axis=1)[:, None], (1, len(pairs)))
    vh = np.tile(np.median(inp.change.var_h, axis=1)[:, None], (1, len(pairs)))
    th = workflow.prediction.io_frf(cfg, GRID, 0.0, pairs)
    bm = benign_model(cfg, GRID, 0.0, th, KAPPA_NOMINAL, 0.0, None, pairs, modal=False)  # as the advice does
    assert bm is not None
    det = detectability(cfg, GRID, 0.0, vn, vh, pairs, None, 0.01, linearized(bm), [4], workers=1)
    want = det.elements[0].open_loss_min
    assert want is not None and detail["detectable_element"] == 4
    assert detail["detectable_loss"] == pytest.approx(want, rel=1e-9)
    assert f"{100 * want:.2g} %" in res.sensor_advice


def test_a_set_is_predicted_alike_from_every_candidate_or_from_its_own_channels(
        rigs: tuple[RigConfig, RigConfig, RigConfig]) -> None:
    """The prediction of a set read as columns of every candidate pair's model equals the one from a model of
    that set's pairs alone (solved on its own: another stacking of pairs and points; the benign model's points
    taken point after point instead of pair after pair fails it); one probe differs from another."""
    cfg = rigs[0]
    var = np.full(GRID.size, 1e-16)

    def model(ports: list[Port]) -> Any:
        return candidate_model(cfg, GRID, 0.0, ports, [ACT], var,
                               lambda pairs, th: benign_model(cfg, GRID, 0.0, th, KAPPA_NOMINAL, 0.0, None, pairs,
                                                              modal=False))

    every = [Port(station=s, direction="x") for s in (6, 2, 3, 9)]
    big = model(every)
    alone = model([every[2], every[0]])
    for hyp in (Hypothesis(4, 0.05), Hypothesis(6, 0.1)):
        a, b = big.predict((2, 0), hyp), alone.predict((0, 1), hyp)
        # 1e-3: an element only the other probes see keeps its round-off signature in these columns (T ~ 1e-4)
        assert a == pytest.approx(b, rel=1e-3)
    assert big.predict((0,), Hypothesis(4, 0.05)) != pytest.approx(big.predict((1,), Hypothesis(4, 0.05)), rel=1e-3)


def test_ports_in_words() -> None:
    assert describe_ports(("s6.x", "s6.y", "s2.x", "s2.y")) == "x and y probes at stations 2 and 6"
    assert describe_ports(("s6.x", "s3.x")) == "x probes at stations 3 and 6"
    assert describe_ports(("s6.x", "s2.y")) == "a y probe at station 2 and an x probe at station 6"
    assert describe_ports(tuple(f"s{k}.{d}" for k in range(1, 11) for d in "xy")) == "x and y probes at stations 1-10"


def test_the_advice_is_in_the_conclusion_of_every_rendering(rigs: tuple[RigConfig, RigConfig, RigConfig],
                                                            one_probe: tuple[Any, Any, Any]) -> None:
    """A damage report (a 50 % loss in element 7, detected) carrying the not-locatable location of the one-probe
    case: the conclusion names the advised set and its added probes in Next; report.json, report.md and
    report.html carry the same sentence and numbers (tests/report/test_report_parity.py's parsers)."""
    import dataclasses

    from rotorcheck.report.content import conclusion
    from rotorcheck.report.html import render_detection_html
    from rotorcheck.report.reports import render_markdown
    from tests.report.test_report_parity import html_text, numbers

    cfg, sim, _ = rigs
    res = one_probe[2]
    st = step_settings(sim, keep_periods=False)
    healthy = workflow.measured_run(simulate_rig(sim, GRID, 0.0, seed=11, settings=st), cfg)
    crack = sim.model_copy(update={"faults": {**sim.faults, "loc": Crack(element=7, model="open", modulus_factor=0.5)}})
    new = workflow.measured_run(simulate_rig(crack, GRID, 0.0, "loc", 12, settings=st), cfg)
    val = workflow.validate(cfg, [healthy], workflow.fit_noise(healthy), enclose="measured")
    rep = workflow.detect(cfg, val.baseline, new).typed_report()
    assert rep.verdict == "damage"
    rep = dataclasses.replace(rep, location=res)
    rep.conclusion = conclusion(rep)
    added = [s for s in res.sensor_advice_detail["best"]["sensors"] if s != "s6.x"]
    assert res.sensor_advice in rep.conclusion and "not locatable with these sensors" in rep.conclusion
    assert f"Next: add the probes {', '.join(added)} named above and sweep again" in rep.conclusion
    doc = rep.to_dict()
    assert doc["location"]["sensor_advice"] == res.sensor_advice and doc["location"]["kind"] == "not locatable"
    md, html = render_markdown(rep, []), html_text(render_detection_html(rep, []))
    assert md.split("## Conclusion", 1)[1].strip().startswith(rep.conclusion)
    assert " ".join(res.sensor_advice.split()) in " ".join(html.split())
    md_lines = [ln for ln in md.splitlines() if "sha256" not in ln]
    assert not numbers("\n".join(md_lines)) - numbers(html)
