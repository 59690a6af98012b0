"""Model updating: fit the rig's named benign parameters to a healthy FRF by least squares.

The fit minimizes the relative error of the receptance, ``log(g G(theta) / T_h)`` (real and imaginary
parts: log magnitude and phase), over the parameters of the ``variability`` section, each allowed
``span`` times its benign range. Standard errors from the Jacobian at the optimum with the residual
variance estimated from the fit (an assumption: residuals independent across points; model error is
not, so they are optimistic where the model misses physics).

What it is for, measured on the crack rig: updating E and the two bearing stiffnesses of the nominal
model to the truth's healthy FRF lowers the RMS log error from 0.21 to 0.12 but moves the bearings by
-65 % and -61 % (they absorb the disc, coupling and pedestal the model lacks), and it does not make
the model's benign predictions better (E -1 %: 33 % of the change left unexplained after updating,
28 % without). So detection anchors benign predictions at the measured FRF and learns the rest from
healthy sweeps; updating is reported, and used only when asked (``validate --update``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from rotorcheck.config import RigConfig
from rotorcheck.robust.joint import linearized_se
from rotorcheck.signatures import io_frf
from rotorcheck.variability import benign_parameters, with_benign


@dataclass(frozen=True)
class Update:
    """Updated parameter values (relative change for factors, offset for offsets) with standard errors,
    and the RMS relative FRF error before and after."""

    names: tuple[str, ...]
    values: np.ndarray
    se: np.ndarray
    at_bound: np.ndarray
    rms_before: float
    rms_after: float

    def as_dict(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values)}


def update_parameters(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, frf: np.ndarray,
                      span: float = 10.0) -> Update:
    """Fit the ``variability`` parameters (not the speed) of ``config`` to the measured ``frf`` (f,) m/N."""
    f = np.asarray(freq_hz, dtype=float)
    params = [p for p in benign_parameters(config) if not p.is_speed]
    if not params:
        raise ValueError("the rig has no variability parameters to update")
    lo = np.array([max(span * p.lo, -0.95) if p.kind == "factor" else span * p.lo for p in params])
    hi = np.array([span * p.hi for p in params])
    names = tuple(p.name for p in params)
    target = np.asarray(frf, dtype=complex)

    def resid(x: np.ndarray) -> np.ndarray:
        cfg, d_rpm, g_s, g_a = with_benign(config, dict(zip(names, map(float, x))))
        e = np.log(g_s * g_a * io_frf(cfg, f, speed_rpm + d_rpm) / target)
        return np.concatenate([e.real, e.imag])

    r0 = resid(np.zeros(len(params)))
    sol = least_squares(resid, np.zeros(len(params)), bounds=(lo, hi), x_scale=np.maximum(hi - lo, 1e-6) / 10,
                        diff_step=1e-4)
    span_ = np.maximum(hi - lo, 1e-300)
    at_bound = (sol.x - lo <= 1e-6 * span_) | (hi - sol.x <= 1e-6 * span_)
    dof = max(sol.fun.size - len(params), 1)
    s2 = float(sol.fun @ sol.fun) / dof
    se = linearized_se(sol.jac, ~at_bound) * np.sqrt(s2)
    return Update(names, sol.x, se, at_bound, float(np.sqrt(np.mean(r0**2))), float(np.sqrt(np.mean(sol.fun**2))))
