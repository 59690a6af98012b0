"""A rig file for a sweep and rig variants: updated benign parameters, the speed tolerance, the damage port."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rotorcheck.baseline import Baseline, stored_rig
from rotorcheck.config import RigConfig, load_config
from rotorcheck.errors import InputError
from rotorcheck.faults.compliance import with_crack_depth
from rotorcheck.nominal import NominalModel, nominal_model
from rotorcheck.resources import default_rig_path
from rotorcheck.signatures import candidate_elements
from rotorcheck.variability import benign_parameters, recentred_rig, with_benign


def load_rig(path: str | Path) -> RigConfig:
    """Load and validate a rig YAML file (raises ConfigError naming file and field)."""
    return load_config(path)


def rig_with_crack_depth(config: RigConfig, rig_path: str | Path | None, fault: str, depth: float) -> RigConfig:
    """A copy of ``config`` whose crack ``fault`` has ``depth`` (fraction of the shaft diameter);
    bad values raise InputError naming ``--crack-depth``."""

    if fault not in config.faults:
        raise InputError(rig_path, f"faults.{fault}", f"no such fault (known: {', '.join(config.faults) or 'none'})")
    try:
        return with_crack_depth(config, fault, depth)
    except ValueError as exc:
        raise InputError(None, "--crack-depth", str(exc)) from None


def rig_for(rig_path: str | Path | None, rig_id: str, baseline_path: str | Path | None = None) -> Path:
    """The rig file for a command on a sweep of rig ``rig_id``: ``--rig``; else the one a baseline at
    ``baseline_path`` was made with (stored as its ``rig_path``) when it is of the same rig; else the
    bundled rig named ``rig_id``. A stored rig file that is gone is an error naming it."""
    if rig_path is not None:
        return Path(rig_path)
    if baseline_path is not None:
        base_id, stored = stored_rig(baseline_path)
        if stored is not None and base_id == rig_id:
            if not Path(str(stored)).exists():
                raise InputError(baseline_path, "/@x_rig_path", f"the rig file the baseline was made with ({stored}) "
                                 "is gone; pass --rig")
            return Path(str(stored))
    return default_rig_path(rig_id)


def updated_rig(rig: RigConfig, values: dict[str, float] | None) -> RigConfig:
    """``rig`` with updated parameter values applied (the model benign change is predicted around)."""
    if not values:
        return rig

    return with_benign(rig, values)[0]


def baseline_rig(rig: RigConfig, baseline: Baseline) -> RigConfig:
    """The rig as a baseline reads it: the parameter values ``validate --update`` fitted applied, and the benign
    ranges moved and widened as ``validate --learn-drift`` learned them (:mod:`rotorcheck.workflow.drift`)."""
    d = baseline.drift
    return recentred_rig(updated_rig(rig, d.updated_parameters), d.range_shift or {}, d.range_widen or {})


def damage_port_name(rig: RigConfig) -> str:
    if rig.damage is None:
        return ""
    p = rig.damage.port
    return p.mass if rig.kind == "lumped" and p.mass else f"station {p.station} {p.direction}"


def speed_tolerance(rig: RigConfig) -> float:
    """The rig's speed tolerance (rpm) from its ``variability`` section; 0 without one."""

    return max((max(abs(p.lo), abs(p.hi)) for p in benign_parameters(rig) if p.is_speed), default=0.0)


def port_static_stiffness(rig: RigConfig, speed_rpm: float) -> float:
    """The nominal static stiffness at the damage port, N/m: 1 / |E11| at a very low frequency."""

    model = nominal_model(rig, np.array([1e-3]), speed_rpm)
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(1.0 / abs(model.E[0, 0, 0]))



#: the last nominal model built by :func:`nominal_for` (a detector and the diagnosis after it share one)
_MODEL_MEMO: dict[tuple[int, bytes, float], tuple[RigConfig, NominalModel]] = {}


def nominal_for(rig: RigConfig, freq_hz: np.ndarray, speed_rpm: float) -> NominalModel:
    """:func:`rotorcheck.nominal.nominal_model` of ``rig`` on ``freq_hz`` (Hz) at ``speed_rpm``, built once
    for the same rig object, grid and speed (one entry kept)."""
    f = np.asarray(freq_hz, dtype=float)
    key = (id(rig), f.tobytes(), float(speed_rpm))
    hit = _MODEL_MEMO.get(key)
    if hit is not None and hit[0] is rig:
        return hit[1]
    model = nominal_model(rig, f, speed_rpm)
    _MODEL_MEMO.clear()
    _MODEL_MEMO[key] = (rig, model)
    return model


def check_elements(config: RigConfig, elements: Sequence[int] | None) -> tuple[int, ...] | None:
    """``elements`` (``--elements``) when each is a shaft element of the rig; an InputError naming the valid
    range otherwise (None: every element)."""
    if elements is None:
        return None
    known = candidate_elements(config)
    bad = [e for e in elements if e not in known]
    if bad:
        valid = f"{min(known)}-{max(known)}" if known else "none: the rig is lumped"
        raise InputError(None, "--elements", f"no shaft element {', '.join(map(str, bad))} in rig "
                         f"{config.rig_id!r} (elements {valid})")
    return tuple(elements)
