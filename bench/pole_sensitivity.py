"""The model's error in its relative pole sensitivities, measured on the truth variants (issue 29).

The modal anchor (:mod:`rotorcheck.modal_anchor`) predicts a benign change by moving the healthy sweep's fitted
poles by the FE model's relative pole sensitivities ``d ln(lambda) / d theta``; its model-form prior says how far
those may be off (:data:`rotorcheck.modal_anchor.POLE_SENSITIVITY_ERROR`, one standard deviation, absolute, per
unit of a relative parameter). This prints, per speed and benign parameter, the model's sensitivity of every mode
below 600 Hz and each truth variant's difference from it (the variant's mode nearest in frequency), then the worst
corner of the rig's ranges (each parameter at its range end, the largest difference of each, all adding) against
the prior's reach (the error times the summed ranges) in standard deviations.

``python -m bench.pole_sensitivity``
"""

from __future__ import annotations

import numpy as np

from bench.truth_variants import VARIANTS, nominal, truth_variant
from rotorcheck.config import RigConfig
from rotorcheck.fe.assembly import build_system
from rotorcheck.modal_anchor import POLE_SENSITIVITY_ERROR, fe_modes
from rotorcheck.signatures import _dofs
from rotorcheck.variability import benign_parameters, with_benign

STEP = 1e-4
BAND_HZ = 600.0


def sensitivities(cfg: RigConfig, speed_rpm: float, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(poles (k,) rad/s, d ln(lambda) / d theta (k,))`` of the modes below :data:`BAND_HZ` (forward
    difference of :data:`STEP`, each changed pole the nearest to its own)."""
    s0 = build_system(cfg)
    m0 = fe_modes(s0, speed_rpm, _dofs(s0, cfg, None))
    cfg1 = with_benign(cfg, {name: STEP})[0]
    s1 = build_system(cfg1)
    m1 = fe_modes(s1, speed_rpm, _dofs(s1, cfg1, None))
    p0 = m0.poles[np.abs(m0.poles) / (2 * np.pi) < BAND_HZ]
    d = np.array([(m1.poles[np.argmin(np.abs(m1.poles - lam))] / lam - 1.0) / STEP for lam in p0])
    return p0, d.real


def main() -> int:
    nom = nominal()
    params = [p for p in benign_parameters(nom) if p.kind == "factor" and p.changes_model]
    worst = {p.name: 0.0 for p in params}
    for speed in (0.0, 1000.0):
        print(f"\n## {speed:g} rpm: d ln(lambda) / d theta, the model's and each truth's difference\n")
        print("| parameter | variant | " + " | ".join(["mode"] * 6) + " |")
        print("|---|---|" + "---:|" * 6)
        for p in params:
            pm, sm = sensitivities(nom, speed, p.name)
            print(f"| {p.name} | model | " + " | ".join(f"{abs(x) / 2 / np.pi:.1f} Hz: {s:.4f}"
                                                     for x, s in zip(pm, sm)) + " |")
            for v in VARIANTS:
                pt, st = sensitivities(truth_variant(v, nom), speed, p.name)
                near = [int(np.argmin(np.abs(np.abs(pt) - abs(x)))) for x in pm]
                diff = np.array([st[k] - s for k, s in zip(near, sm)])
                worst[p.name] = max(worst[p.name], float(np.max(np.abs(diff))))
                print(f"| | {v} | " + " | ".join(f"{abs(pt[k]) / 2 / np.pi:.1f} Hz: {d:+.4f}"
                                                 for k, d in zip(near, diff)) + " |")
    size = {p.name: max(abs(p.lo), abs(p.hi)) for p in params}
    corner = sum(size[n] * worst[n] for n in worst)
    reach = POLE_SENSITIVITY_ERROR * sum(size.values())
    print("\nlargest difference: " + ", ".join(f"{n} {w:.4f}" for n, w in worst.items()))
    print(f"worst corner of the ranges: {corner:.3g} of a pole; the prior's reach (1 sd) {reach:.3g} "
          f"(POLE_SENSITIVITY_ERROR {POLE_SENSITIVITY_ERROR:g}): {corner / reach:.2f} sd")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
