"""The Rig object (issue 28): its receptances against the FE engine called directly, an element's loss against
the assembly with that modulus factor, benign gains and speed offsets against their closed forms."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

from rotorcheck import rig as rig_module
from rotorcheck.config import load_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import system_receptance
from rotorcheck.resources import configs_dir
from rotorcheck.rig import Rig
from rotorcheck.variability import benign_parameters

F = np.linspace(30.0, 600.0, 40)


def _direct(cfg, speed: float, factors: dict[int, float] | None = None) -> np.ndarray:
    """Sensor/actuator receptance from the engine, the system assembled here."""
    system = build_system(cfg, modulus_factors=factors)
    out, inp = system.port_dof(cfg.ports.sensor), system.port_dof(cfg.ports.actuator)
    return system_receptance(system, speed, [out], [inp], band_hz=float(F.max())).at_hz(F)[:, 0, 0]


def test_docstring_example() -> None:
    failed, tried = doctest.testmod(rig_module)
    assert tried > 0 and failed == 0


def test_receptance_and_element_loss_against_the_engine() -> None:
    cfg = load_config(configs_dir() / "crack_rig.yaml")
    rig = Rig(cfg, speed_rpm=1000.0)
    np.testing.assert_allclose(rig.receptance(F)[:, 0], _direct(cfg, 1000.0), rtol=1e-9)
    lossy = rig.with_element_loss(4, 0.54)
    np.testing.assert_allclose(lossy.receptance(F)[:, 0], _direct(cfg, 1000.0, {4: 0.46}), rtol=1e-9)
    assert np.max(np.abs(lossy.receptance(F) - rig.receptance(F))) > 1e-3 * np.max(np.abs(rig.receptance(F)))


def test_benign_gain_and_speed_offset() -> None:
    cfg = load_config(configs_dir() / "crack_rig.yaml")
    names = [p.name for p in benign_parameters(cfg)]
    gain = next(n for n in names if "gain" in n)
    rig = Rig(cfg, speed_rpm=1000.0)
    np.testing.assert_allclose(rig.with_benign({gain: 0.01}).receptance(F), 1.01 * rig.receptance(F), rtol=1e-12)
    speed = next((n for n in names if "speed" in n), None)
    if speed is None:
        pytest.skip("the rig has no speed tolerance")
    moved = rig.with_benign({speed: 15.0})
    np.testing.assert_allclose(moved.receptance(F)[:, 0], _direct(cfg, 1015.0), rtol=1e-9)


def test_elements_outside_the_rig_are_refused_by_the_library() -> None:
    """--elements is checked where detectability and locate take it (the library), not only in the CLI."""
    from rotorcheck import workflow
    from rotorcheck.errors import InputError

    cfg = load_config(configs_dir() / "crack_rig.yaml")
    for bad in ((0,), (99,), (4, 10)):
        with pytest.raises(InputError, match=r"--elements.*elements 1-9"):
            workflow.detectability_for_rig(cfg, noise_std_m=2e-7, elements=bad)
    assert workflow.check_elements(cfg, [4, 6]) == (4, 6)
