"""Issue 16: a baseline is verified on read against the content digest rotorcheck wrote into it; each edit
of the list in the issue (gamma scaled, the noise bound scaled, gamma as strings or complex, the status
removed, the input phasors zeroed, an unknown uncertainty name, an edited sweep hash, the digest removed)
is exit 2 naming the baseline and what changed, no traceback, no report written; an untouched baseline
still detects the crack."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np
import pytest

from rotorcheck.baseline import DIGEST_ATTR, read_baseline
from rotorcheck.cli import EXIT_DAMAGE, EXIT_INPUT, EXIT_OK, main
from rotorcheck.errors import InputError
from rotorcheck.report.reports import REPORT_FILES
from rotorcheck.resources import samples_dir
from tests.shared_runs import CliRun

CR = samples_dir() / "crack_rig"


def _replace(name: str, value: Callable[[np.ndarray], np.ndarray]) -> Callable[[h5py.File], None]:
    def edit(h5: h5py.File) -> None:
        new = value(h5[name][()])
        del h5[name]
        h5.create_dataset(name, data=new)
    return edit


def _attr(name: str, value: object) -> Callable[[h5py.File], None]:
    def edit(h5: h5py.File) -> None:
        h5.attrs[name] = value
    return edit


def _delete(name: str) -> Callable[[h5py.File], None]:
    def edit(h5: h5py.File) -> None:
        if name.startswith("@"):
            del h5.attrs[name[1:]]
        else:
            del h5[name]
    return edit


EDITS: dict[str, tuple[Callable[[h5py.File], None], str]] = {
    "gamma x 1e6": (_replace("gamma", lambda g: g * 1e6), "gamma"),
    "gamma as complex": (_replace("gamma", lambda g: g.astype(complex)), "gamma"),
    "gamma as strings": (_replace("gamma", lambda g: np.array([str(x) for x in g], dtype="S")), "gamma"),
    "gamma status removed": (_delete("gamma_status"), "gamma_status"),
    "input phasors zeroed": (_replace("input_phasor", lambda w: np.zeros_like(w)), "input_phasor"),
    "noise bound x 1e3": (lambda h5: h5.attrs.__setitem__("noise_bound_m", h5.attrs["noise_bound_m"] * 1e3),
                          "@noise_bound_m"),
    "unknown uncertainty name": (_attr("uncertainty", "nonsense"), "@uncertainty"),
    "sweep hash edited": (_attr("sweep_sha256", "0" * 64), "@sweep_sha256"),
    "digest removed": (_delete(f"@{DIGEST_ATTR}"), f"@{DIGEST_ATTR}"),
    "schema_version a string": (_attr("schema_version", "one"), "@schema_version"),
}


@pytest.fixture(scope="module")
def validated(validated_0rpm: CliRun) -> Path:
    """The shared `fit-noise` + `validate --no-plots` of healthy_0rpm.h5 (read only: the tests copy it)."""
    assert validated_0rpm.codes == (EXIT_OK, EXIT_OK)
    return validated_0rpm.out / "baseline.h5"


def test_an_untouched_baseline_reads_and_detects(validated: Path, tmp_path: Path) -> None:
    assert read_baseline(validated).validated
    out = tmp_path / "out"
    out.mkdir()
    shutil.copy(validated, out / "baseline.h5")
    assert main(["detect", str(CR / "open_crack_0rpm.h5"), "--out", str(out), "--no-plots"]) == EXIT_DAMAGE


@pytest.mark.parametrize("case", list(EDITS))
def test_an_edited_baseline_is_refused_naming_what_changed(case: str, validated: Path, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    out.mkdir()
    base = out / "baseline.h5"
    shutil.copy(validated, base)
    edit, field = EDITS[case]
    with h5py.File(base, "r+") as h5:
        edit(h5)
    with pytest.raises(InputError) as exc:
        read_baseline(base)
    assert exc.value.file == str(base)
    if case != "gamma as strings":  # a string gamma fails the shape/type checks first, also by field
        assert field in exc.value.field or field in exc.value.message, str(exc.value)
    capsys.readouterr()
    assert main(["detect", str(CR / "open_crack_0rpm.h5"), "--out", str(out), "--no-plots"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert str(base) in err and "Traceback" not in err
    assert not any((out / name).exists() for name in REPORT_FILES)


def test_a_manual_noise_bound_survives_validate_force_and_a_foreign_fit_needs_a_flag(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Issue 16's silent result changers: validate --force kept refitting over fit-noise --method manual; a
    bound fitted on one sweep validated another without a word."""
    out = tmp_path / "out"
    h = str(CR / "healthy_1000rpm.h5")
    assert main(["fit-noise", h, "--out", str(out), "--method", "manual", "--value", "0.05e-6"]) == EXIT_OK
    assert main(["validate", h, "--out", str(out), "--no-plots"]) == EXIT_OK
    assert read_baseline(out / "baseline.h5").noise_bound_m == pytest.approx(0.05e-6)
    assert main(["validate", h, "--out", str(out), "--no-plots", "--force"]) == EXIT_OK
    b = read_baseline(out / "baseline.h5")
    assert b.noise_method == "manual" and b.noise_bound_m == pytest.approx(0.05e-6)
    other = tmp_path / "o2"
    assert main(["fit-noise", h, "--out", str(other)]) == EXIT_OK
    capsys.readouterr()
    repeat = str(CR / "healthy_1000rpm_repeat.h5")
    assert main(["validate", repeat, "--out", str(other), "--no-plots"]) == EXIT_INPUT
    assert "fitted on another sweep" in capsys.readouterr().err
    assert main(["validate", repeat, "--out", str(other), "--no-plots", "--reuse-noise", "--force", "--json"]) \
        == EXIT_OK
    import json

    fitted_on = read_baseline(other / "baseline.h5").provenance.noise_fitted_on_sweep
    assert fitted_on and json.loads(capsys.readouterr().out)["noise_fitted_on_sweep"] == fitted_on


def test_a_native_panic_outside_a_solver_is_exit_2(monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture) -> None:
    """Issue 16: Clarabel's PanicException derives from BaseException; wherever one escapes, the CLI
    still exits 2 with a message (solver calls themselves report it per point)."""
    import rotorcheck.workflow as wf

    class PanicException(BaseException):
        pass

    def panic(*args: object, **kw: object) -> None:
        raise PanicException("rust panicked")

    monkeypatch.setattr(wf, "load_rig_and_runs", panic)
    assert main(["fit-noise", str(CR / "healthy_0rpm.h5")]) == EXIT_INPUT
    assert "PanicException" in capsys.readouterr().err


def test_a_channel_table_in_another_order_is_read_by_its_labels(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture) -> None:
    """Issue 16: the same channels with their rows in another order are matched to the baseline's pairs by
    label (not refused, not misread). Noise-free sweeps (the nominal rig sets no noise): after alignment each
    pair's FRF equals the other order's and the model's receptance at its labels."""
    from rotorcheck import workflow
    from rotorcheck.config import Port, load_config
    from rotorcheck.nominal import ChannelPair, pair_receptance
    from rotorcheck.resources import configs_dir

    rig_path = configs_dir() / "crack_rig.yaml"
    common = ["--rig", str(rig_path), "--speed", "1000", "--points", "30", "--periods", "8", "--actuator", "8x",
              "--actuator", "8y"]
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert main(["simulate", str(a), *common, "--sensor", "6x", "--sensor", "6y", "--sensor", "2x"]) == EXIT_OK
    assert main(["simulate", str(b), *common, "--sensor", "6x", "--sensor", "2x", "--sensor", "6y"]) == EXIT_OK
    rig = load_config(rig_path)
    ra, rb = workflow.load_run(a, rig), workflow.load_run(b, rig)
    assert workflow.pair_keys(ra) != workflow.pair_keys(rb)
    al = workflow.aligned_pairs(rb, workflow.pair_keys(ra))
    assert workflow.pair_keys(al) == workflow.pair_keys(ra)
    assert al.frf_pairs is not None and ra.frf_pairs is not None
    np.testing.assert_allclose(al.frf_pairs, ra.frf_pairs, rtol=1e-12, atol=1e-12 * np.abs(ra.frf_pairs).max())
    pairs = [ChannelPair(Port(station=int(o[1]), direction=o[-1]), Port(station=int(i[1]), direction=i[-1]), "")
             for o, i in workflow.pair_keys(al)]  # type: ignore[arg-type]
    G = pair_receptance(rig, al.frequency_hz, 1000.0, pairs)
    np.testing.assert_allclose(al.frf_pairs, G, rtol=1e-9, atol=1e-12 * np.abs(G).max())
    # with noise (the truth rig): a baseline of one order takes a sweep of the other (refused before)
    truth = configs_dir() / "crack_rig_truth.yaml"
    noisy = ["--rig", str(truth), *common[2:], "--seed", "3"]
    assert main(["simulate", str(a), *noisy, "--sensor", "6x", "--sensor", "6y", "--sensor", "2x", "--force"]) == 0
    assert main(["simulate", str(b), *noisy, "--sensor", "6x", "--sensor", "2x", "--sensor", "6y", "--force"]) == 0
    out = tmp_path / "out"
    assert main(["validate", str(a), "--out", str(out), "--no-plots", "--rig", str(truth)]) == EXIT_OK
    capsys.readouterr()
    assert main(["detect", str(b), "--out", str(out), "--no-plots"]) in (EXIT_OK, EXIT_DAMAGE)
    assert "differ from the baseline" not in capsys.readouterr().err


def test_info_says_when_the_rig_id_is_not_a_bundled_rig(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    import json

    from rotorcheck.resources import configs_dir

    p = tmp_path / "s.h5"
    assert main(["simulate", str(p), "--rig", str(configs_dir() / "overhung_rig.yaml"), "--points", "5"]) == 0
    with h5py.File(p, "r+") as h5:
        h5.attrs["rig_id"] = "my_own_rig"
    capsys.readouterr()
    assert main(["info", str(p), "--json"]) == EXIT_OK
    out = capsys.readouterr()
    assert json.loads(out.out)["rig_bundled"] is False and "not a bundled rig" in out.err
    assert main(["info", str(CR / "healthy_0rpm.h5"), "--json"]) == EXIT_OK
    assert json.loads(capsys.readouterr().out)["rig_bundled"] is True
