"""Convergence of the two tapered-element formulations on ROSS's conical rotor (issue 32, defect 2).

The cone of ``tests/data/ross/ross_rotor_conical.yaml`` (steel, 0.5 m, diameter 0.1 -> 0.01 m, rigid
supports 1e20 N/m, Cowper's kappa) meshed with 4, 8, 16 and 32 equal tapered elements, each
formulation of ``tapered_element``. Reference: the converged mesh, Richardson extrapolation (O(h^2),
the rate of the Timoshenko element with shear) of 256 and 512 elements; the two formulations'
extrapolations agree to 2e-7, the exact one is taken. Error of modes 1-3 (distinct bending
frequencies at rest), %::

    elements   exact                         greenhill
                mode 1    mode 2   mode 3      mode 1  mode 2  mode 3
       4       -0.0299   -3.76    -17.5        +4.88   +4.21   +6.49
       8       +0.00963  +0.0737   +0.493      +3.47   +2.40   +2.97
      16       +0.00295  +0.0195   +0.123      +1.84   +1.12   +1.28
      32       +0.000848 +0.00545  +0.0305     +0.700  +0.413  +0.459

``exact`` (the default) converges best: from 8 elements on every mode is 6-830x closer than
``greenhill``, and mode 1 is 160x closer already at 4 elements. At 4 elements its modes 2 and 3 are
further off than greenhill's (-3.8 % and -17.5 % against +4.2 % and +6.5 %): its stiffness is the
exact one of the tapered beam but its mass is that of cubic shape functions, and 4 elements are too
few for a third mode of this cone (the stiffness is no Rayleigh-Ritz partner of the mass there, so the
error has no sign). The default stays ``exact``; a 4-element mesh is only good for the first mode.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from rotorcheck.config import RigConfig, parse_config
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.modal import modes

BASE = yaml.safe_load((Path(__file__).resolve().parents[1] / "data" / "ross" / "ross_rotor_conical.yaml").read_text())

#: (elements, formulation) -> error (%) of modes 1-3 against the converged mesh (module docstring)
TABLE = {
    (4, "exact"): (-0.0299, -3.76, -17.5), (4, "greenhill"): (4.88, 4.21, 6.49),
    (8, "exact"): (0.00963, 0.0737, 0.493), (8, "greenhill"): (3.47, 2.40, 2.97),
    (16, "exact"): (0.00295, 0.0195, 0.123), (16, "greenhill"): (1.84, 1.12, 1.28),
    (32, "exact"): (0.000848, 0.00545, 0.0305), (32, "greenhill"): (0.700, 0.413, 0.459),
}


def _cone(n: int, taper: str) -> RigConfig:
    """The cone as ``n`` equal tapered elements (8 spans of n / 8 elements, or n spans of one)."""
    spans = min(n, 8)
    z = np.linspace(0.0, 0.5, spans + 1)
    d = 0.1 - 0.18 * z
    rig = {k: v for k, v in BASE.items() if k not in ("stations", "shaft", "bearings")}
    rig.update(
        tapered_element=taper, stations=z.tolist(),
        shaft=[{"start": i + 1, "end": i + 2, "material": "steel", "outer_diameter": float(d[i]),
                "outer_diameter_right": float(d[i + 1]), "refine": n // spans} for i in range(spans)],
        bearings=[dict(BASE["bearings"][0]), dict(BASE["bearings"][1], station=spans + 1)],
    )
    return parse_config(rig)


def _modes_1_3(n: int, taper: str) -> np.ndarray:
    f = modes(build_system(_cone(n, taper)), 0.0, n_modes=6).frequency_hz
    np.testing.assert_allclose(f[0::2], f[1::2], rtol=1e-9)  # x and y planes: degenerate pairs
    return f[0::2]


@pytest.fixture(scope="module")
def converged() -> np.ndarray:
    ext = {t: _modes_1_3(512, t) + (_modes_1_3(512, t) - _modes_1_3(256, t)) / 3.0 for t in ("exact", "greenhill")}
    assert np.max(np.abs(ext["greenhill"] / ext["exact"] - 1)) < 3e-7  # two formulations, one limit
    return ext["exact"]


def test_tapered_formulations_convergence_table(converged: np.ndarray) -> None:
    err = {key: 100.0 * (_modes_1_3(*key) / converged - 1.0) for key in TABLE}
    for key, expected in TABLE.items():
        np.testing.assert_allclose(err[key], expected, rtol=0.01, err_msg=str(key))
    for n in (8, 16, 32):  # exact converges best from 8 elements on, every mode
        assert np.all(np.abs(err[(n, "exact")]) * 6 < np.abs(err[(n, "greenhill")]))
    assert abs(err[(4, "exact")][0]) * 100 < abs(err[(4, "greenhill")][0])
    assert RigConfig.model_fields["tapered_element"].default == "exact"


def test_undamped_frequencies_at_rest_on_rigid_supports() -> None:
    """``model``'s ``undamped_frequencies_at_rest_hz`` of the 4-element cone on 1e20 N/m supports came
    from ``eigh(K, M)``, whose round-off scales with ``||K||``: its first pair was split (238.76 and
    250.78 Hz) and 3.5 % low. Now from ``(M, K)`` (``1 / w^2``): the pairs degenerate and equal to the
    cone pinned exactly (the support translations removed; the 1e20 N/m springs differ from a pin by
    ~1e-11)."""
    import scipy.linalg as sla

    from rotorcheck.fe.modal import natural_frequencies_at_rest

    system = build_system(_cone(4, "exact"))
    f = natural_frequencies_at_rest(system, 6)
    M, _, _, K = system.matrices(0.0)
    pinned = [system.dof(st, d) for st in (1, 5) for d in ("x", "y")]
    free = np.setdiff1d(np.arange(M.shape[0]), pinned)
    ref = np.sqrt(sla.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)[:6]) / (2 * np.pi)
    np.testing.assert_allclose(f, ref, rtol=1e-9)
    np.testing.assert_allclose(f[0::2], f[1::2], rtol=1e-9)
