"""What every detection report says, shared by its renderings (report.md, report.html, fault_points.csv):
the damage estimate to read and the headline damage figure, from a report document."""

from __future__ import annotations

import numpy as np

from rotorcheck.report.schema import DetectionReport


def damage_columns(report: DetectionReport) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, str]:
    """The damage estimate to read (f,): ``(re, im, min_abs, max_abs, kind)`` in N/m, the anchored D_u and its
    bound where the report has it, else the nominal-E22 one; ``kind`` says which."""
    if report.damage_dynamics_anchored_re is not None:
        keys = ("damage_dynamics_anchored_re", "damage_dynamics_anchored_im", "damage_anchored_bound_min_abs",
                "damage_anchored_bound_max_abs")
        kind = "anchored at the healthy data"
    else:
        keys = ("damage_dynamics_re", "damage_dynamics_im", "damage_bound_min_abs", "damage_bound_max_abs")
        kind = "nominal E22 (eq. 3.11; carries the model error)"
    re, im, lo, hi = (np.asarray(getattr(report, k), dtype=float) for k in keys)
    return re, im, lo, hi, kind


def headline_damage(report: DetectionReport) -> list[str]:
    """The headline damage figure: the anchored D_u (the estimate free of the nominal model's error) over
    the fault points (or the band) with its bound; the nominal-E22 one only where no anchored one exists. A
    verdict other than damage has no finding to headline (the numbers stay in report.json)."""
    if report.verdict != "damage":
        return []
    fault = np.asarray(report.fault, dtype=bool)
    sel = fault if np.any(fault) else np.ones_like(fault)
    where = f"median over the {int(np.sum(sel))} fault points" if np.any(fault) else "median over the band"
    re_all, _, lo_all, hi_all, kind = damage_columns(report)
    re, lo, hi = re_all[sel], lo_all[sel], hi_all[sel]
    if re.size == 0 or not np.any(np.isfinite(re)):
        return []
    significant = int(np.count_nonzero(lo > 0))
    return [f"Damage dynamics at {report.damage_port} ({kind}), {where}: Re D_u = {np.nanmedian(re):.4g} N/m "
            f"(positive: a stiffness loss); |D_u| within [{np.nanmedian(lo):.4g}, {np.nanmedian(hi):.4g}] N/m "
            f"(medians of the bound); the bound excludes 0 at {significant} of {re.size} points.", ""]


def best_candidate(report: DetectionReport) -> str | None:
    """The joint test's best candidate element and its loss with the interval, in words; None unless the verdict
    is damage (a healthy verdict shows no finding) and the report holds one."""
    interval, loss = report.stiffness_loss_interval, report.stiffness_loss
    if report.verdict != "damage" or report.best_element is None or not interval or loss is None:
        return None
    lo, hi = interval
    return (f"element {report.best_element}: stiffness loss {100 * loss:.3g} % [{100 * lo:.3g}, {100 * hi:.3g}] "
            "(95 %, linearized)")
