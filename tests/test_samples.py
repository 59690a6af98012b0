"""The bundled sample sweeps (data_samples/) are exactly what the code makes, are valid, and match the
file names that cli.md promises."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from rotorcheck.sweep import compare_sweeps, read_sweep
from tools import samples

REPO = Path(__file__).resolve().parents[1]
SAMPLE_DIR = REPO / "data_samples"
CONFIG_DIR = REPO / "configs"

# cli.md, "Bundled files (names are a contract ...)", copied verbatim
CLI_MD_CONFIGS = (
    "crack_rig.yaml",
    "crack_rig_truth.yaml",
    "three_mass_trial1.yaml",
    "three_mass_trial2.yaml",
    "three_mass_trial3.yaml",
    "three_mass_truth.yaml",
)
CLI_MD_SAMPLES = (
    "crack_rig/healthy_0rpm.h5",
    "crack_rig/open_crack_0rpm.h5",
    "crack_rig/healthy_1000rpm.h5",
    "crack_rig/breathing_crack_1000rpm.h5",
    "crack_rig/healthy_1000rpm_repeat.h5",
    "three_mass/healthy.h5",
    "three_mass/damaged.h5",
)
#: beyond the contract: the free-running (random start angle) healthy pair at 2000 rpm (issue 9)
EXTRA_SAMPLES = ("crack_rig/healthy_2000rpm.h5", "crack_rig/healthy_2000rpm_repeat.h5",
                 # issue 12: x/y probes at stations 6 and 2, forces in x and y at station 8
                 "crack_rig_xy/healthy_0rpm.h5", "crack_rig_xy/open_crack_0rpm.h5", "crack_rig_xy/healthy_1000rpm.h5",
                 "crack_rig_xy/breathing_crack_1000rpm.h5", "crack_rig_xy/healthy_1000rpm_repeat.h5",
                 # round ten: the sidebands f + k x speed (format version 3)
                 "crack_rig_sidebands/healthy_1000rpm.h5", "crack_rig_sidebands/breathing_crack_10pct_1000rpm.h5")

# what each bundled file must hold: (speed rpm, grid, seed named in the run notes, fault)
EXPECTED = {
    "crack_rig/healthy_0rpm.h5": (0.0, samples.GRID_0RPM, 101, None),
    "crack_rig/open_crack_0rpm.h5": (0.0, samples.GRID_0RPM, 102, "open_crack"),
    "crack_rig/healthy_1000rpm.h5": (1000.0, samples.GRID_1000RPM, 108, None),
    "crack_rig/breathing_crack_1000rpm.h5": (1000.0, samples.GRID_1000RPM, 104, "breathing_crack"),
    "crack_rig/healthy_1000rpm_repeat.h5": (1000.0, samples.GRID_1000RPM, 105, None),
    "crack_rig/healthy_2000rpm.h5": (2000.0, samples.GRID_1000RPM, 106, None),
    "crack_rig/healthy_2000rpm_repeat.h5": (2000.0, samples.GRID_1000RPM, 107, None),
    "crack_rig_xy/healthy_0rpm.h5": (0.0, samples.GRID_0RPM, 101, None),
    "crack_rig_xy/open_crack_0rpm.h5": (0.0, samples.GRID_0RPM, 102, "open_crack"),
    "crack_rig_xy/healthy_1000rpm.h5": (1000.0, samples.GRID_1000RPM, 108, None),
    "crack_rig_xy/breathing_crack_1000rpm.h5": (1000.0, samples.GRID_1000RPM, 104, "breathing_crack"),
    "crack_rig_xy/healthy_1000rpm_repeat.h5": (1000.0, samples.GRID_1000RPM, 105, None),
    "three_mass/healthy.h5": (0.0, samples.GRID_THREE_MASS, 0, None),
    "three_mass/damaged.h5": (0.0, samples.GRID_THREE_MASS, 0, "stiffness_loss"),
}


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("samples")
    written = samples.write_samples(out)
    assert sorted(p.relative_to(out).as_posix() for p in written) == sorted(s.path for s in samples.SAMPLES)
    return out


def test_cli_md_bundled_names_exist_and_catalogue_matches() -> None:
    for name in CLI_MD_CONFIGS:
        assert (CONFIG_DIR / name).is_file(), name
    for name in CLI_MD_SAMPLES:
        assert (SAMPLE_DIR / name).is_file(), name
    # the catalogue that regenerates data_samples/ makes exactly the contract's files, no more
    assert sorted(s.path for s in samples.SAMPLES) == sorted(CLI_MD_SAMPLES + EXTRA_SAMPLES)
    on_disk = sorted(p.relative_to(SAMPLE_DIR).as_posix() for p in SAMPLE_DIR.rglob("*.h5"))
    assert on_disk == sorted(CLI_MD_SAMPLES + EXTRA_SAMPLES)


@pytest.mark.parametrize("name, seed, fault", [("crack_rig_sidebands/healthy_1000rpm.h5", 111, None),
                                               ("crack_rig_sidebands/breathing_crack_10pct_1000rpm.h5", 112,
                                                "breathing_crack")])
def test_sideband_samples_are_version_3_with_the_orders_and_seeds_they_say(name: str, seed: int,
                                                                            fault: str | None) -> None:
    sw = read_sweep(SAMPLE_DIR / name)
    run = next(iter(sw.runs.values()))
    assert run.speed_rpm == 1000.0 and f"seed {seed};" in run.notes
    assert (f"fault {fault!r}" in sw.generator) if fault else ("healthy" in sw.generator)
    np.testing.assert_array_equal(run.sideband_order, samples.SIDEBANDS)
    assert run.sideband_phasor_exc is not None and run.sideband_phasor_exc.shape == (run.frequency.size, 1, 4, 1)
    with h5py.File(SAMPLE_DIR / name, "r") as h5:
        assert int(h5.attrs["schema_version"]) == 3


def test_bundled_samples_total_under_2_mb() -> None:
    total = sum((SAMPLE_DIR / name).stat().st_size for name in CLI_MD_SAMPLES)
    assert 0 < total < 2 * 1024 * 1024, total


@pytest.mark.parametrize("name", CLI_MD_SAMPLES)
def test_bundled_file_is_valid_and_holds_what_its_name_says(name: str) -> None:
    sw = read_sweep(SAMPLE_DIR / name)  # validates on open
    speed, grid, seed, fault = EXPECTED[name]
    assert sw.source == "simulated"
    assert sw.rig_id == name.split("/")[0]
    assert sw.created_utc == samples.CREATED_UTC
    assert len(sw.runs) == 1
    run = next(iter(sw.runs.values()))
    assert run.speed_rpm == speed
    np.testing.assert_array_equal(run.frequency, grid)
    assert f"seed {seed};" in run.notes
    assert (f"fault {fault!r}" in sw.generator) if fault else ("healthy" in sw.generator)
    # the raw HDF5 holds the documented layout (datasets and dtypes) under /runs/<run_id>/
    with h5py.File(SAMPLE_DIR / name, "r") as h5:
        assert h5.attrs["schema"] == "rotorcheck.sweep" and int(h5.attrs["schema_version"]) == 1
        g = h5["runs"][run.run_id]
        nf = grid.size
        assert g["frequency"].dtype == np.float64 and g["frequency"].shape == (nf,)
        assert g["input_phasor"].dtype == np.complex128 and g["input_phasor"].shape == (nf, 1)
        assert g["output_phasor"].dtype == np.complex128 and g["output_phasor"].shape == (nf, 1)
        assert g["output_var"].dtype == np.float64 and g["output_var"].shape == (nf, 1)
        assert g["n_periods"].dtype == np.int32 and g["n_periods"].shape == (nf,)
        assert g["frf"].dtype == np.complex128 and g["frf"].shape == (nf, 1, 1)


@pytest.mark.parametrize("name", CLI_MD_SAMPLES)
def test_bundled_file_equals_regenerated_bit_for_bit(regenerated: Path, name: str) -> None:
    bundled = read_sweep(SAMPLE_DIR / name)
    fresh = read_sweep(regenerated / name)
    assert compare_sweeps(bundled, fresh) == []
    # and compare_sweeps is not blind: one ulp in one output phasor is reported
    run = next(iter(fresh.runs.values()))
    run.output_phasor[7, 0] = np.nextafter(run.output_phasor[7, 0].real, np.inf) + 1j * run.output_phasor[7, 0].imag
    diff = compare_sweeps(bundled, fresh)
    assert len(diff) == 1 and f"/runs/{run.run_id}/output_phasor: 1 of" in diff[0], diff


def test_check_samples_reports_a_tampered_copy(tmp_path: Path, regenerated: Path) -> None:
    """``python -m tools.samples --check`` passes on data_samples/ and fails, naming the
    file, on a copy where one frequency point moved by one ulp (the copy checked against the module's
    regenerated samples, ``--against``: the samples are made once more, by the first check, not three times)."""
    assert samples.main(["--check", str(SAMPLE_DIR)]) == 0
    name = "crack_rig/healthy_0rpm.h5"
    for s in samples.SAMPLES:
        dst = tmp_path / s.path
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes((regenerated / s.path).read_bytes())
    with h5py.File(tmp_path / name, "r+") as h5:
        ds = h5["runs/0rpm/frequency"]
        ds[100] = np.nextafter(ds[100], np.inf)
    problems = samples.check_samples(tmp_path, regenerated)
    assert list(problems) == [name]
    assert any("/runs/0rpm/frequency: 1 of 353 elements differ" in p for p in problems[name]), problems
    assert samples.main(["--check", str(tmp_path), "--against", str(regenerated)]) == 1
