"""What every detection report says, shared by its renderings (report.md, report.html, fault_points.csv):
the damage estimate to read and the headline damage figure, from a report document."""

from __future__ import annotations

from collections.abc import Callable

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
    """Where, in words: the diagnosis's location summary (the ranked candidate elements with their relative
    likelihoods; with ``--locate`` the certified intervals and exclusions; or why it is not locatable);
    None unless the verdict is damage (a healthy verdict shows no finding) and the report holds one."""
    if report.verdict != "damage" or report.location is None:
        return None
    return report.location.summary()


def fmt_p(p: float | None) -> str:
    """A p-value in words and figures: below the float resolution of its computation (1e-15) as "< 1e-15"."""
    if p is None:
        return "not computed"
    v = float(p)
    return "< 1e-15" if v < 1e-15 else format(v, ".3g")


def fmt_interval(lo: float, hi: float, fmt: str = "+.4g") -> str:
    """"[lo, hi]", or in words where it is not defined (a parameter held at its range end: NaN ends)."""
    a, b = float(lo), float(hi)
    if not (np.isfinite(a) and np.isfinite(b)):
        return "not defined (at the range edge)"
    return f"[{a:{fmt}}, {b:{fmt}}]"


def element_span(report: DetectionReport, element: int | None) -> str:
    """" (z = 0.295-0.335 m)" for a shaft element of the report's rig, "" when the report holds no stations."""
    z = report.stations_m
    if element is None or not z or not (1 <= element < len(z)):
        return ""
    return f" (z = {z[element - 1]:.3g}-{z[element]:.3g} m from the first station)"


def _sideband_decided(report: DetectionReport) -> bool:
    """The sideband test called damage and the joint test (if it ran) did not."""
    sb = report.sideband_test
    if sb is None or sb.get("verdict") != "damage":
        return False
    return report.joint_p_value is None or report.false_alarm is None or report.joint_p_value >= report.false_alarm


def _how_sure(report: DetectionReport) -> str:
    sb = report.sideband_test
    if sb is not None:
        p_sb = f"the sideband test's p-value is {fmt_p(sb.get('p_value'))}"
        if report.joint_statistic is None:
            return f"{p_sb} against a stated false-alarm rate of {float(sb['false_alarm']):.2g} per sweep"
        return (f"the joint test's p-value is {fmt_p(report.joint_p_value)} and {p_sb}, each against half the stated "
                f"false-alarm rate of {2 * float(sb['false_alarm']):.2g} per sweep (Bonferroni)")
    if report.joint_statistic is not None and report.false_alarm is not None:
        return (f"the joint test's p-value is {fmt_p(report.joint_p_value)} against a stated false-alarm rate of "
                f"{report.false_alarm:.2g} per sweep")
    if report.p_value is not None and report.confidence is not None:
        return (f"{report.n_fault_points} of {report.n_points} points are certified at {report.confidence:.0%} "
                f"family-wise confidence (sweep p-value {fmt_p(report.p_value)})")
    return f"{report.n_fault_points} of {report.n_points} points are certified fault points"


def _rests_on(report: DetectionReport) -> str:
    if _sideband_decided(report):
        return ("a healthy rotor is time-invariant (an axisymmetric shaft and supports, no crack when healthy), so "
                "its tones at f + k x speed are noise; the stated sideband variances are the noise's")
    if report.joint_statistic is not None:
        kappa = report.benign_model_error
        return ("Gaussian noise independent between frequency points with the healthy sweep's variance; benign "
                "change is what the model predicts inside the rig's variability ranges"
                + (f", wrong by at most {kappa:g} x its predicted size" if kappa else ""))
    return ("the noise bound of the baseline at its confidence, and the model error within the healthy sweep's "
            "gamma bound")


def _where(report: DetectionReport) -> tuple[str, int | None]:
    """Where, as far as the report says, and the element to name in the next step."""
    loc = report.location
    if loc is not None and loc.damage_found:  # the one ranking detect and locate report (rotorcheck.ranking)
        b = loc.best
        e = None if b is None or loc.kind == "not locatable" else b.element
        return loc.summary(), e  # the summary names the element with its axial span (m)
    if report.n_fault_points:
        return (f"the change shows at {report.n_fault_points} frequency points; the element is not estimated "
                "with this rule (run rotorcheck locate)"), None
    return "the element is not estimated with this rule (run rotorcheck locate)", None


def conclusion(report: DetectionReport) -> str:
    """The plain conclusion every rendering opens with: verdict, where and how big, how sure, what it rests on,
    what to do next (one paragraph)."""
    verdict = report.verdict
    sure = _how_sure(report)
    rests = _rests_on(report)
    if verdict == "damage":
        where, element = _where(report)
        nxt = (f"inspect element {element}, or repeat the sweep to confirm and run rotorcheck locate for certified "
               "intervals" if element is not None else "repeat the sweep to confirm, then run rotorcheck locate")
        advice = None if report.location is None else report.location.sensor_advice_detail
        if element is None and advice and advice.get("best"):
            added = [s for s in advice["best"]["sensors"] if s not in (advice.get("current") or {}).get("sensors", [])]
            nxt = f"add the probes {', '.join(added)} named above and sweep again, or " + nxt
        what = ("this sweep holds tones at f + k x speed beyond noise, which no benign change of a time-invariant "
                "rotor makes: a breathing crack's signature" if _sideband_decided(report) else
                "this sweep differs from the healthy baseline beyond noise and beyond every benign change inside the "
                "rig's ranges")
        return f"Damage: {what}; {where}. How sure: {sure}. It rests on: {rests}. Next: {nxt}."
    if verdict == "healthy":
        smallest = ""
        rows = (report.detectability or {}).get("elements", [])  # with the benign ranges: what drift cannot hide
        finite = [(float(r["open_loss_min"]), int(r["element"]), r.get("breathing_depth_min")) for r in rows
                  if r.get("open_loss_min") is not None and np.isfinite(float(r["open_loss_min"]))]
        if finite:
            x, e, depth = min(finite)
            crack = "" if depth is None else f" (a breathing crack {100 * float(depth):.3g} % of the diameter deep)"
            smallest = (f" Despite the benign ranges this sweep could have revealed a stiffness loss of {100 * x:.3g} %"
                        f"{crack} in element {e}{element_span(report, e)}, with 90 % power; smaller changes or "
                        "other elements could pass unseen.")
        return (f"Healthy: no change beyond noise and the benign ranges ({sure}).{smallest} It rests on: {rests}. "
                "Next: nothing to do; keep sweeping at the usual interval.")
    return (f"Inconclusive: {report.verdict_reason}. Nothing is claimed either way. It rests on: {rests}. Next: "
            "repeat the sweep (check the excitation and the points without a decision), then detect again.")


def benign_rows(report: DetectionReport) -> list[list[str]]:
    """The benign parameters fitted (name, estimate, 95 % interval, unit, beyond its range: at a range end with the
    data pushing beyond it, chi2 >= 3.84), as every rendering shows them."""
    return [[b["name"], f"{b['estimate']:+.4g}", fmt_interval(*b["interval"]), b["unit"],
             "yes" if b.get("at_range_edge") else "no"] for b in (report.benign_parameters or [])]


BENIGN_HEADER = ("benign parameter", "estimate", "95 % interval", "unit", "pushed beyond its range")


def method_paragraphs(report: DetectionReport, ranges: Callable[[list[float]], str]) -> list[str]:
    """The method section every rendering carries (the rule, the joint test's statistic, the benign change, the
    points unexplained after it and certified beyond it, what the sweep could reveal); ``ranges`` writes a list
    of frequencies as ranges."""
    out = [f"Rule: {report.verdict_rule}"]
    sb = report.sideband_test
    if sb is not None:
        p_sb = fmt_p(sb["p_value"])
        out.append(f"Sideband test (orders {', '.join(f'{int(k):+d}' for k in sb['orders'])}; "
                   f"{sb['n_tones']} separable tones): the strongest window's T = {float(sb['statistic']):.4g}, its "
                   f"threshold {float(sb['threshold']):.4g} at false-alarm rate {float(sb['false_alarm']):.2g} "
                   f"(Bonferroni over the windows; p {p_sb if p_sb.startswith('<') else '= ' + p_sb}); "
                   f"{len(sb['fault_frequencies_hz'])} points certified at the family-wise confidence"
                   + (f": {ranges(list(sb['fault_frequencies_hz']))}" if sb['fault_frequencies_hz'] else "")
                   + f". It {sb['assumes']}.")
    if report.joint_statistic is None:
        return out
    learned = report.learned_benign_directions or 0
    fit = ("" if report.joint_fit_chi2 is None else
           f"; H0's goodness of fit chi2 = {report.joint_fit_chi2:.5g} on {report.joint_fit_dof} dof (p = "
           f"{fmt_p(report.joint_fit_p_value)}), the GLR's own p = {fmt_p(report.joint_glr_p_value)}")
    out.append(f"Joint test: T = {report.joint_statistic:.4g}, threshold {report.joint_threshold:.4g} (the GLR's share "
               f"of the false-alarm rate {report.false_alarm:g}; the rule above) (p = {fmt_p(report.joint_p_value)}"
               f"{fit}); model-error fraction kappa = "
               f"{report.benign_model_error:g}"
               + (f"; {learned} benign directions learned from healthy sweeps (a baseline of an earlier version)."
                  if learned else "."))
    if report.joint_best_element is not None and report.verdict == "damage":
        out.append(f"The joint test's own element (its linearized statistic, not the diagnosis): "
                   f"{report.joint_best_element}.")
    beyond = report.fault_beyond_benign_frequencies_hz
    if beyond is not None:
        out.append(f"{len(beyond)} points stay unexplained after the fitted benign change (per point, the noise "
                   f"and the model-error allowance, Sidak at {report.false_alarm:g} over the points)"
                   + (f": {ranges(list(beyond))}." if beyond else "."))
    cert = report.certified_beyond_benign_frequencies_hz
    if cert is not None:
        out.append(f"{len(cert)} points are certified beyond every benign change inside the ranges (parameters "
                   f"real, branch and bound; {report.n_undecided_beyond_benign} undecided; with each parameter a "
                   f"complex disc instead: {report.n_certified_beyond_benign_complex})"
                   + (f": {ranges(list(cert))}." if cert else "."))
    els, det = report.candidate_elements or [], report.detectable_stiffness_loss or []
    if els:
        out.append("Smallest stiffness loss this sweep could reveal (90 % power at the stated rate): "
                   + ", ".join(f"element {e}: {100 * x:.3g} %" for e, x in zip(els, det)) + ".")
    return out


def grid_step(report: DetectionReport) -> float:
    """The report's grid step (Hz, the median spacing; 1 for a single point), for writing frequency ranges."""
    f = np.asarray(report.frequency_hz, dtype=float)
    return float(np.median(np.diff(f))) if f.size > 1 else 1.0


def frequency_ranges(freqs: list[float], step: float) -> str:
    """Frequencies (Hz) as ranges of consecutive grid points (``step`` the grid step, Hz): "12.0-14.5, 30.0 Hz"."""
    if not freqs:
        return "none"
    out, start, prev = [], freqs[0], freqs[0]
    for f in freqs[1:]:
        if f - prev > 1.5 * step:
            out.append((start, prev))
            start = f
        prev = f
    out.append((start, prev))
    return ", ".join(f"{a:.1f}" if a == b else f"{a:.1f}-{b:.1f}" for a, b in out) + " Hz"


def fault_table(report: DetectionReport) -> tuple[list[str], list[list[str]]]:
    """Every fault point: f, gamma healthy and required, their ratio, the damage estimate to read with its bound
    (header, rows), as every rendering shows it."""
    f = np.asarray(report.frequency_hz, dtype=float)
    fault = np.asarray(report.fault, dtype=bool)
    gh = np.asarray(report.gamma_healthy, dtype=float)
    gr = np.asarray(report.gamma_required, dtype=float)
    dre, dim, lo, hi, kind = damage_columns(report)
    anchored = kind.startswith("anchored")
    header = ["f (Hz)", "gamma healthy", "gamma required", "ratio",
              f"D_u{' anchored' if anchored else ''} (N/m)", "min |D_u| (N/m)", "max |D_u| (N/m)"]
    rows = []
    for i in np.flatnonzero(fault):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = gr[i] / gh[i]
        rows.append([format(f[i], ".2f"), format(gh[i], ".4e"), format(gr[i], ".4e"), format(ratio, ".4g"),
                     f"{dre[i]:.4g}{float(dim[i]):+.3g}j", format(lo[i], ".4g"), format(hi[i], ".4g")])
    return header, rows


def where_paragraphs(report: DetectionReport, ranges: Callable[[list[float]], str]) -> list[str]:
    """Where in the spectrum: the certified fault points as frequency ranges, and the points of every other
    status (``ranges`` writes a list of frequencies as ranges)."""
    f = np.asarray(report.frequency_hz, dtype=float)
    fault = np.asarray(report.fault, dtype=bool)
    out = [f"{report.n_fault_points} of {report.n_points} points are certified fault points (the healthy uncertain "
           f"model cannot explain them): {ranges(list(f[fault]))}."]
    if report.verdict == "healthy" and report.n_fault_points and report.joint_statistic is not None:
        out[0] = out[0][:-1] + ("; the sweep differs from the healthy one there, but the benign change fitted (Method) "
                                "explains them: no damage.")
    status = np.asarray(report.status).astype(str)
    for s in (s for s in np.unique(status) if s not in ("ok", "fault", "excluded")):
        out.append(f"{int(np.count_nonzero(status == s))} points with status '{s}': {ranges(list(f[status == s]))}.")
    for p in report.shaft_harmonic_points or []:
        out.append(f"{p['frequency_hz']:.2f} Hz sits {abs(p['offset_hz']):.2g} Hz from {p['order']}X "
                   f"({p['harmonic_hz']:.4g} Hz), inside the lock-in's resolution {p['resolution_hz']:.2g} Hz: it "
                   "measures the shaft's own response there, not the FRF, and is left out of every certified claim.")
    return out
