"""`rotorcheck locate` end to end on the bundled crack-rig samples (issue 11): the open crack (element 4,
modulus factor 0.46: a 54 % loss) is located in element 4 with a loss interval holding 54 %, the far
elements are excluded with their frequencies named; a healthy repeat locates nothing; detect's report
carries the same section. Candidates limited to a few elements to keep the test short (the bench runs
every element: bench/results_location.md)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from rotorcheck.cli import EXIT_DAMAGE, EXIT_INPUT, EXIT_OK, main
from rotorcheck.resources import samples_dir
from tests.shared_runs import CliRun

S = samples_dir() / "crack_rig"


@pytest.fixture
def base0(validated_0rpm: CliRun, tmp_path: Path) -> Path:
    """A copy of the shared `fit-noise` + `validate --no-plots` folder of healthy_0rpm.h5."""
    return validated_0rpm.copy_to(tmp_path / "out")


def test_locate_the_open_crack_sample(located_open_crack: CliRun, tmp_path: Path) -> None:
    """`locate open_crack_0rpm.h5 --elements 1,4,9 --json` (the shared run, conftest.located_open_crack)."""
    doc = located_open_crack.json()
    assert located_open_crack.codes == (EXIT_OK, EXIT_OK, EXIT_DAMAGE)  # fit-noise, validate, locate
    assert doc["best_element"] == 4 and doc["healthy_excluded"] is True and doc["hypothesis"] == "open"
    c = {x["element"]: x for x in doc["candidates"]}
    lo, hi = c[4]["loss_interval"]
    assert lo <= 0.54 <= hi and c[4]["rank"] == 1
    mf = c[4]["modulus_factor_interval"]
    assert mf[0] <= 0.46 <= mf[1]
    for e in (1, 9):
        assert c[e]["status"] == "excluded" and c[e]["excluding_frequencies_hz"] and c[e]["rank"] is None
    out = located_open_crack.out
    assert (out / "location.json").exists() and (out / "location.png").exists()
    # nothing is overwritten without --force (in a copy: the shared folder stays as the run left it)
    out = located_open_crack.copy_to(tmp_path / "out")
    assert main(["locate", str(S / "open_crack_0rpm.h5"), "--out", str(out), "--elements", "4"]) == EXIT_INPUT


def test_locate_bad_elements_is_input_error(base0: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["locate", str(S / "open_crack_0rpm.h5"), "--out", str(base0), "--elements", "4,x",
                 "--force"]) == EXIT_INPUT
    assert "--elements" in capsys.readouterr().err
    assert main(["locate", str(S / "open_crack_0rpm.h5"), "--out", str(base0), "--elements", "42",
                 "--force", "--no-plots"]) == EXIT_INPUT


def test_healthy_repeat_locates_nothing(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    assert main(["fit-noise", str(S / "healthy_1000rpm.h5"), "--out", str(out)]) == EXIT_OK
    assert main(["validate", str(S / "healthy_1000rpm.h5"), "--out", str(out), "--no-plots"]) == EXIT_OK
    capsys.readouterr()
    code = main(["locate", str(S / "healthy_1000rpm_repeat.h5"), "--out", str(out), "--elements", "4",
                 "--json", "--no-plots"])
    doc = json.loads(capsys.readouterr().out)
    assert code == EXIT_OK and doc["best_element"] is None and doc["healthy_excluded"] is False
    assert doc["summary"].startswith("no damage to locate")
    assert all(x["rank"] is None for x in doc["candidates"])


def test_detect_report_carries_the_location(base0: Path) -> None:
    from rotorcheck import workflow
    from rotorcheck.baseline import read_baseline

    base = read_baseline(base0 / "baseline.h5")
    cfg, _, runs = workflow.load_rig_and_runs(S / "open_crack_0rpm.h5", None, base0 / "baseline.h5")
    outcome = workflow.detect(cfg, base, runs[0])
    # a damage verdict says where: the ranking (issue 30), the sample's crack element first, no certificate yet
    rep = outcome.report()
    assert outcome.verdict.verdict == "damage" and rep["location"]["certified"] is False
    assert rep["best_element"] == 4 and rep["location"]["best_element"] == 4
    assert "element 4" in rep["location"]["summary"]
    assert rep["location"]["ranking"]["elements"][0]["element"] == 4
    outcome.location = workflow.locate_damage(cfg, base, runs[0], elements=(4,))
    loc = outcome.report()["location"]
    assert loc["best_element"] == 4 and loc["candidates"][0]["loss_interval"][0] <= 0.54


def test_depth_of_loss_inverts_the_depth_relations() -> None:
    """depth_of_loss against its definition: the relation at the depth found gives the loss back (open and
    breathing crack relations of the crack rig's element 4, depths 2-50 %), beyond MAX_DEPTH None, no loss 0."""
    from rotorcheck.location import MAX_DEPTH, breathing_loss, depth_of_loss, open_loss

    for rel in (lambda d: open_loss(d, 0.0125, 0.04, 0.3), lambda d: breathing_loss(d, 0.0125, 0.02, 0.3)):
        for d in (0.02, 0.1, 0.27, 0.45, 0.5):
            found = depth_of_loss(rel(d), rel)
            assert found is not None and abs(found - d) < 1e-8, (d, found)
        assert depth_of_loss(rel(MAX_DEPTH) * 1.01, rel) is None
        assert depth_of_loss(0.0, rel) == 0.0


def test_a_loss_interval_beyond_the_relation_reads_as_at_least_its_deepest() -> None:
    """A certified loss interval wholly beyond the relation's deepest loss bounds the depth from below by
    MAX_DEPTH ("at least 50 %", not nothing); inside the range both ends invert the relation."""
    from rotorcheck.location import MAX_DEPTH, depth_interval, depth_text, open_loss

    def rel(d: float) -> float:
        return float(open_loss(d, 0.0125, 0.04, 0.3))

    top = rel(MAX_DEPTH)
    lo, hi = depth_interval(1.05 * top, 1.2 * top, rel)
    assert (lo, hi) == (MAX_DEPTH, None) and depth_text(lo, hi) == "at least 50 %"
    lo, hi = depth_interval(rel(0.2), 1.1 * top, rel)
    assert lo == pytest.approx(0.2, abs=1e-8) and hi is None and depth_text(lo, hi) == "at least 20 %"
    lo, hi = depth_interval(rel(0.2), rel(0.3), rel)
    assert (lo, hi) == (pytest.approx(0.2, abs=1e-8), pytest.approx(0.3, abs=1e-8)) and depth_text(lo, hi) == "20-30 %"


def test_a_best_fit_its_certificate_excludes_is_said_not_hidden() -> None:
    """The ranking's best fit (relative likelihood 1.00) excluded by its certificate (the pedestal truth with x/y
    probes: element 5, 40 % loss, excluded at 268 Hz, the pedestal's own mode): the result is 'ranked', not
    'located'; its answer stays the best fit (the exclusion rests on bounds the model broke), the summary names the
    frequencies, the consequence and the element the certificate keeps, location.json carries it; with the best
    fit consistent nothing is said."""
    from rotorcheck.location import CandidateResult, LocationResult
    from rotorcheck.ranking import ElementFit, Ranking

    nan = float("nan")
    fits = [ElementFit(5, 0.39, 126.0, 1.0, (0.0,), 1.0), ElementFit(6, 0.73, 252.0, 0.0, (0.0,), 1.0)]

    def result(status5: str) -> LocationResult:
        excluded = status5 == "excluded"
        cands = [CandidateResult(5, 0.4, 0.45, status5, None if excluded else 1,
                                 (nan, nan) if excluded else (0.3, 0.5), (None, None),
                                 (268.0, 49.7) if excluded else (), loss_estimate=0.39, likelihood=None if excluded
                                 else 1.0),
                 CandidateResult(6, 0.45, 0.47, "consistent", 1 if excluded else 2, (0.63, 0.8), (None, None), (),
                                 loss_estimate=0.73, likelihood=1.0 if excluded else 0.0)]
        return LocationResult("open", True, cands, ["s6.x<-s8.x"], 48, 3.0,
                              ranking=Ranking("open", fits, 400.0, 128, 64), damage=True)

    bad = result("excluded")
    assert bad.contradicted is not None and bad.contradicted.element == 5
    assert bad.kind == "ranked"
    assert bad.best is not None and bad.best.element == 5  # the answer stays the best fit
    assert bad.to_dict()["best_element"] == 5
    text = bad.summary()
    assert "the best fit is element 5" in text and "268.0, 49.7 Hz" in text
    assert "the certificate keeps, element 6 ranks first" in text
    assert "about 39.0 % (best fit; no certified interval: its certificate excludes it)" in text
    assert bad.to_dict()["contradicted_best_fit"] == {"element": 5, "excluding_frequencies_hz": [268.0, 49.7]}
    good = result("consistent")
    assert good.contradicted is None and good.kind == "located" and "best fit is" not in good.summary()
    assert "contradicted_best_fit" not in good.to_dict()


def test_a_refinement_that_excludes_the_best_ranked_makes_way_for_the_next(base0: Path, monkeypatch) -> None:
    """locate's refinement on the bundled open crack with the certificates scripted (consistent everywhere, but
    the refined budget excludes the best ranked, element 4): the next ranked consistent element is refined and
    named beside the answer, the best fit, element 4, which the headline says its certificate excludes."""
    import numpy as np

    import rotorcheck.location as location
    import rotorcheck.robust.severity as severity
    from rotorcheck import workflow
    from rotorcheck.baseline import read_baseline

    calls: list[tuple[str, int]] = []

    def scripted(model, pts, lo, hi, index, tol=0.01, slices=16, max_boxes=16, witnessed_at_lo=False, earlier=None):
        name = model.parameters[-1].name  # loss_<element>
        calls.append((name, max_boxes))
        if max_boxes == 48 and name == "loss_4":
            return severity.SeverityInterval("excluded", np.nan, np.nan, (np.nan, np.nan), (0,), 1, False)
        return severity.SeverityInterval("consistent", 0.1, 0.6, (0.2, 0.5), (), 1, True)

    monkeypatch.setattr(location, "severity_interval", scripted)  # locate's certificate (imported at module level)
    base = read_baseline(base0 / "baseline.h5")
    cfg, _, runs = workflow.load_rig_and_runs(S / "open_crack_0rpm.h5", None, base0 / "baseline.h5")
    loc = workflow.locate_damage(cfg, base, runs[0], elements=(3, 4, 5), damage=True)
    refined = [name for name, boxes in calls if boxes == 48]
    assert loc.ranking is not None and loc.ranking.fits[0].element == 4
    second = loc.ranking.fits[1].element
    assert refined == ["loss_4", f"loss_{second}"]
    assert loc.best is not None and loc.best.element == 4  # the answer stays the best fit, flagged
    assert loc.contradicted is not None and loc.contradicted.element == 4
    assert loc.ranked[0].element == second
    assert "the best fit is element 4" in loc.summary()
    assert f"the certificate keeps, element {second} ranks first" in loc.summary()


def test_the_breathing_depth_relation_reads_xy_probes_as_one_probe() -> None:
    """depth -> loss of a breathing crack (location._hb_relation) from x/y probes at two stations against the
    one from the direct pair alone (an independent route: no cross pair there): alike within 10 % at every depth,
    and a 5 % deep crack a loss below 1 %. The x force's y probes (which only the spin couples) are left out: with
    them the relation read a 5 % deep crack as a 42 % loss."""
    import numpy as np

    from rotorcheck.config import load_config
    from rotorcheck.location import HB_DEPTHS, _hb_relation
    from rotorcheck.ranking import loss_model
    from rotorcheck.resources import configs_dir
    from rotorcheck.robust.box_test import Points, point_receptances
    from rotorcheck.signatures import benign_box
    from rotorcheck.variability import benign_at

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    speed, element = 1000.0, 5
    box = benign_box(cfg, speed, benign_at(cfg, speed))
    model = loss_model(cfg, box, element, speed, "breathing")
    system = box.system
    f = np.linspace(35.0, 480.0, 24)
    pairs = [(system.dof(8, a, None), system.dof(st, b, None)) for a in ("x", "y") for st in (6, 2)
             for b in ("x", "y")]

    def points(chosen: list[tuple[int, int]]) -> Points:
        n = system.n_dof
        w = np.tile(2.0 * np.pi * f, len(chosen))
        b = np.concatenate([np.tile(np.eye(n)[i], (f.size, 1)) for i, _ in chosen])
        c = np.concatenate([np.tile(np.eye(n)[o], (f.size, 1)) for _, o in chosen])
        z = np.zeros(w.size)
        pts = Points(w, z.astype(complex), z.astype(complex), z.astype(complex), z, z, 3.0, z, 1.0, 1.0, z, z, b, c)
        return dataclasses.replace(pts, g0=point_receptances(model, pts, np.zeros(len(model.parameters))))

    one = _hb_relation(cfg, system, model, element, speed, points(pairs[:1]), None)
    xy = _hb_relation(cfg, system, model, element, speed, points(pairs), None)
    assert one(0.05) < 0.01 and xy(0.05) < 0.01
    for d in HB_DEPTHS:
        assert xy(d) == pytest.approx(one(d), rel=0.1, abs=0.005), d


def test_detects_diagnosis_certifies_the_same_interval_without_the_healthy_hypothesis(
        detected_breathing_1000rpm: CliRun) -> None:
    """detect's diagnosis of a damage verdict skips the healthy (no loss) hypothesis, whose witness at loss 0 only
    spared the best candidate's lower-end search: on the bundled breathing crack, where that hypothesis holds a
    witness (not excluded: no point is certified beyond benign change), element 4's certified loss interval is the
    same with and without it, and the result says the healthy hypothesis was not tested (None)."""
    import numpy as np

    from rotorcheck import workflow
    from rotorcheck.baseline import read_baseline
    from rotorcheck.workflow.locating import locate_run
    from rotorcheck.workflow.rigs import baseline_rig

    out = detected_breathing_1000rpm.out
    base = read_baseline(out / "baseline.h5")
    cfg, _, runs = workflow.load_rig_and_runs(S / "breathing_crack_1000rpm.h5", None, out / "baseline.h5")
    args = (baseline_rig(cfg, base), runs[0], np.asarray(base.healthy_frf), np.asarray(base.healthy_frf_var),
            base.speed_rpm)
    with_h = locate_run(*args, elements=(4,), certify=False, damage=None, certify_best=True)
    without = locate_run(*args, elements=(4,), certify=False, damage=True, certify_best=True)
    assert with_h.healthy_excluded is False and without.healthy_excluded is None
    a, b = (next(c for c in res.candidates if c.element == 4) for res in (with_h, without))
    assert a.status == b.status == "consistent"
    assert a.loss_interval == pytest.approx(b.loss_interval, abs=1e-12)
    assert a.loss_interval[0] == 0.0  # a witness at no loss: the lower end is the range's
