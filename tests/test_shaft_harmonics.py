"""Shaft harmonics (issue 30): grid points within the lock-in's resolution f/N of k x shaft speed (k = 1..4)
are flagged, named in a warning and kept out of every certified claim."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotorcheck.resources import configs_dir, samples_dir
from rotorcheck.robust.joint import joint_test
from rotorcheck.robust.measured import FrfEstimate, measured_detect
from rotorcheck.robust.noise import noise_bound_manual
from rotorcheck.signal.harmonics import DEFAULT_PERIODS, lockin_resolution_hz, shaft_harmonic_points
from rotorcheck.signal.lockin import tone_lockin
from rotorcheck.sweep import read_sweep
from rotorcheck.sweep.summary import summarize


def test_rule_closed_form_edges() -> None:
    """At 1500 rpm (25 Hz) with N = 32 periods, r = f/N: the point f = 25 k / (1 -+ c/N) sits c r(f) above
    (below) kX exactly, so c = 0.99 is flagged for order k and c = 1.01 is not; 1X-4X only."""
    n, shaft = 32, 25.0
    rows = []
    for k in range(1, 6):
        for c in (0.99, 1.01):
            rows += [(k, c, k * shaft / (1.0 - c / n)), (k, c, k * shaft / (1.0 + c / n))]
    f = np.array([r[2] for r in rows])
    order = np.argsort(f)
    f = f[order]
    res, assumed = lockin_resolution_hz(f, np.full(f.size, n))
    np.testing.assert_allclose(res, f / n)
    h = shaft_harmonic_points(f, 1500.0, res)
    want = np.array([k if (c < 1.0 and k <= 4) else 0 for k, c, _ in (rows[i] for i in order)])
    np.testing.assert_array_equal(h.order, want)
    np.testing.assert_allclose(np.abs(h.offset_hz[h.flagged]), 0.99 * f[h.flagged] / n, rtol=1e-12)
    assert not assumed and h.n_flagged == 8
    # the same points at standstill: nothing
    assert shaft_harmonic_points(f, 0.0, res).n_flagged == 0


def test_resolution_is_where_the_lockin_rejects_a_tone() -> None:
    """The rule's edge r = f/N is the first null of the N-period lock-in: a unit tone at f + f/N leaks
    nothing into the mean phasor (continuous integral, tone_lockin), one at f + f/(2N) leaks sinc(1/2) = 2/pi;
    the tone's negative-frequency image adds at most |sinc(2N)| = 1/(2 pi N) to either."""
    f, n = 40.0, 32
    image = 1.0 / (2.0 * np.pi * n)
    for delta, leak in ((f / n, 0.0), (f / (2 * n), 2.0 / np.pi)):
        mean = tone_lockin(np.array([f + delta]), np.array([1.0 + 0j]), f, 0.0, n).mean()
        assert abs(abs(mean) - leak) <= 1.01 * image


def test_missing_periods_use_the_default_and_say_so() -> None:
    f = np.array([20.0, 24.9, 30.0])
    res, assumed = lockin_resolution_hz(f, None)
    assert assumed
    np.testing.assert_allclose(res, f / DEFAULT_PERIODS)
    h = shaft_harmonic_points(f, 1500.0, res, assumed_periods=assumed)
    assert list(h.order) == [0, 1, 0]
    assert f"N = {DEFAULT_PERIODS} periods assumed" in h.warning()


def test_bundled_grid_at_1000_rpm() -> None:
    """64 periods per point: 49.66 Hz is 0.345 Hz from 3X = 50 Hz with r = 49.66/64 = 0.776 Hz (flagged);
    67.13 Hz is 0.460 Hz from 4X with r = 1.049 Hz (flagged); 34.37 Hz is 1.034 Hz from 2X with r = 0.537 Hz
    (not). info lists exactly those two."""
    sweep = read_sweep(samples_dir() / "crack_rig" / "healthy_1000rpm.h5")
    run = summarize(sweep)["runs"][0]
    pts = run["shaft_harmonic_points"]
    assert [(round(p["frequency_hz"], 2), p["order"]) for p in pts] == [(49.66, 3), (67.13, 4)]
    assert pts[0]["resolution_hz"] == pytest.approx(49.655172 / 64, rel=1e-6)
    assert pts[0]["offset_hz"] == pytest.approx(49.655172 - 50.0, rel=1e-5)
    assert "49.66 Hz (3X = 50 Hz" in run["shaft_harmonics_warning"]
    standstill = summarize(read_sweep(samples_dir() / "crack_rig" / "healthy_0rpm.h5"))["runs"][0]
    assert standstill["shaft_harmonic_points"] == [] and standstill["shaft_harmonics_warning"] == ""


def test_excluded_points_are_as_if_absent() -> None:
    """A second method: the joint test and the certified test with points excluded give what they give on
    the grid without those points (statistic, benign-free fit, family size, fault points)."""
    rng = np.random.default_rng(3)
    n, n_e = 40, 3
    var = rng.uniform(0.5, 2.0, n)
    S = rng.normal(size=(n_e, n)) + 1j * rng.normal(size=(n_e, n))
    r = 0.3 * S[1] + (rng.normal(size=n) + 1j * rng.normal(size=n)) * np.sqrt(var / 2)
    out = np.zeros(n, dtype=bool)
    out[[5, 6, 30]] = True
    r[out] += 50.0  # a large disturbance where the points are excluded
    a = joint_test(r, var, S, (1, 2, 3), exclude=out, draws=20_000)
    b = joint_test(r[~out], var[~out], S[:, ~out], (1, 2, 3), draws=20_000)
    assert a.statistic == pytest.approx(b.statistic, rel=1e-10)
    np.testing.assert_allclose(a.severity, b.severity, rtol=1e-10)
    assert (a.n_points, a.dof_h0, a.point_threshold) == (b.n_points, b.dof_h0, b.point_threshold)
    assert not np.any(a.remaining[out])

    t_h = rng.normal(size=(n, 1)) + 1j * rng.normal(size=(n, 1))
    v = np.full((n, 1), 1e-2)
    dof = np.full((n, 1), 62.0)
    t_new = t_h + 0.05 * (rng.normal(size=(n, 1)) + 1j * rng.normal(size=(n, 1)))
    t_new[out] += 10.0
    t_new[12] += 2.0  # a real fault point
    m = measured_detect(FrfEstimate(t_new, v, dof), FrfEstimate(t_h, v, dof), 0.99, exclude=out)
    s = measured_detect(FrfEstimate(t_new[~out], v[~out], dof[~out]), FrfEstimate(t_h[~out], v[~out], dof[~out]),
                        0.99)
    assert m.n_tests == s.n_tests == n - 3
    np.testing.assert_array_equal(m.fault[~out], s.fault)
    assert list(np.flatnonzero(m.fault)) == [12]
    assert set(m.status[out]) == {"excluded"} and np.all(np.isnan(m.p_value[out]))


@pytest.fixture(scope="module")
def unbalanced_rig(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """The overhung rig with 0.2 g m unbalance on the inner disc, its grid 10-400 Hz in 2.5 Hz steps (25 Hz
    on 1X at 1500 rpm, 32 periods), a healthy sweep and a healthy repeat, free-running start angles."""
    from rotorcheck.config import load_config
    from rotorcheck.sim.rig_sim import shaft_angle_from, simulate_rig
    from rotorcheck.sweep.hdf5io import write_sweep

    tmp = tmp_path_factory.mktemp("harmonics")
    text = (configs_dir() / "overhung_rig.yaml").read_text()
    rig = tmp / "rig.yaml"
    rig.write_text(text.replace("measurement:\n", "measurement:\n  unbalance:\n    - {station: 6, amount: 2.0e-4}\n"))
    cfg = load_config(rig)
    f = np.linspace(10.0, 400.0, 157)
    paths = []
    for name, seed in (("h", 1), ("r", 2)):
        write_sweep(simulate_rig(cfg, f, 1500.0, seed=seed, shaft_angle_rad=shaft_angle_from("random", seed)),
                    tmp / f"{name}.h5")
        paths.append(tmp / f"{name}.h5")
    return rig, paths[0], paths[1]


def _validate_detect(rig: Path, healthy: Path, repeat: Path):  # type: ignore[no-untyped-def]
    from rotorcheck.config import load_config
    from rotorcheck.workflow.detection import detect
    from rotorcheck.workflow.measured import load_run
    from rotorcheck.workflow.noise import fit_noise
    from rotorcheck.workflow.validation import validate

    cfg = load_config(rig)
    h, r = load_run(healthy, cfg), load_run(repeat, cfg)
    v = validate(cfg, [h], fit_noise(h))
    return v, detect(cfg, v.baseline, r)


def test_grid_on_1x_flagged_and_a_healthy_repeat_stays_healthy(unbalanced_rig: tuple[Path, Path, Path],
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """25 Hz (1X), 50 Hz (2X), 75 Hz (3X) and 97.5-102.5 Hz (4X, r = f/32 >= 3.05 Hz) are flagged in validate and
    detect; the repeat is healthy with no certified point and no benign parameter pushed beyond its range, and the
    warning names 25 Hz as 1X. Without the flags (orders = 0) the same repeat is called damage with 25 Hz
    certified beyond every benign change: the unbalance response, not the FRF."""
    v, o = _validate_detect(*unbalanced_rig)
    flagged = [25.0, 50.0, 75.0, 97.5, 100.0, 102.5]
    doc = v.typed_report(noise_bound_manual(1e-7), "b.h5").to_dict()
    assert [p["frequency_hz"] for p in doc["shaft_harmonic_points"]] == flagged
    f = v.runs[0].frequency_hz
    assert set(v.result.status[np.isin(f, flagged)]) == {"excluded"} and v.n_not_enclosed == 0
    rep = o.typed_report()
    assert [(p["frequency_hz"], p["order"]) for p in rep.shaft_harmonic_points or []] == list(
        zip(flagged, [1, 2, 3, 4, 4, 4]))
    assert rep.verdict == "healthy" and rep.n_fault_points == 0
    assert rep.n_certified_beyond_benign == 0 and rep.fault_beyond_benign_frequencies_hz == []
    assert not any(b["at_range_edge"] for b in rep.benign_parameters or [])
    assert set(np.asarray(rep.status)[np.isin(f, flagged)]) == {"excluded"}
    warning = next(n for n in rep.notes if "shaft harmonic" in n)
    assert "25 Hz (1X = 25 Hz, 0 Hz off)" in warning and "certified fault points" in warning

    import rotorcheck.workflow.measured as measured

    real = measured.shaft_harmonic_points
    monkeypatch.setattr(measured, "shaft_harmonic_points", lambda *a, **k: real(*a, **{**k, "orders": 0}))
    _, before = _validate_detect(*unbalanced_rig)
    old = before.typed_report()
    assert old.verdict == "damage" and 25.0 in (old.certified_beyond_benign_frequencies_hz or [])


def test_cli_info_validate_detect_warn(unbalanced_rig: tuple[Path, Path, Path], tmp_path: Path,
                                       capsys: pytest.CaptureFixture) -> None:
    """info, validate and detect each print the warning naming 25 Hz as 1X; validate's --json and
    report.json carry the points; validate's gamma line counts the 151 points left in the bound."""
    import json

    from rotorcheck.cli import EXIT_OK, main

    rig, healthy, repeat = unbalanced_rig
    out = tmp_path / "out"
    assert main(["info", str(healthy), "--json"]) == EXIT_OK
    cap = capsys.readouterr()
    assert "25 Hz (1X = 25 Hz, 0 Hz off)" in cap.err
    assert [p["order"] for p in json.loads(cap.out)["runs"][0]["shaft_harmonic_points"]] == [1, 2, 3, 4, 4, 4]
    assert main(["fit-noise", str(healthy), "--rig", str(rig), "--out", str(out)]) == EXIT_OK
    assert main(["validate", str(healthy), "--out", str(out), "--no-plots", "--json"]) == EXIT_OK
    cap = capsys.readouterr()
    assert "25 Hz (1X = 25 Hz, 0 Hz off)" in cap.err and "gamma over 151 points" in cap.err
    assert json.loads(cap.out)["shaft_harmonic_points"][0]["frequency_hz"] == 25.0
    assert main(["detect", str(repeat), "--out", str(out), "--no-plots", "--json"]) == EXIT_OK
    cap = capsys.readouterr()
    assert "HEALTHY" in cap.err and "25 Hz (1X = 25 Hz, 0 Hz off)" in cap.err
    doc = json.loads(cap.out)
    assert doc["shaft_harmonic_points"][0] == {"frequency_hz": 25.0, "order": 1, "harmonic_hz": 25.0,
                                               "offset_hz": 0.0, "resolution_hz": 25.0 / 32}


@pytest.mark.parametrize("name", ["healthy_1000rpm.h5", "healthy_2000rpm.h5"])
def test_flagged_points_are_where_the_scatter_says_so(name: str) -> None:
    """A second method: after the harmonics are fitted out of the per-period phasors, the points whose
    scatter exceeds the pooled noise (fit-noise's F test) are flagged points (1000 rpm: 49.66 and 67.13 Hz;
    2000 rpm: 67.13, 99.89 and 132.64 Hz of the flagged 67.13, 99.89, 132.64, 134.83 Hz)."""
    from rotorcheck.config import load_config
    from rotorcheck.workflow.measured import load_run, run_harmonics
    from rotorcheck.workflow.noise import fit_noise

    run = load_run(samples_dir() / "crack_rig" / name, load_config(configs_dir() / "crack_rig.yaml"))
    excess = fit_noise(run).details["excess_scatter_hz"]
    flagged = run.frequency_hz[run_harmonics([run]).flagged]
    assert excess and set(excess) <= set(flagged.tolist())
