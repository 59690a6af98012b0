"""What the model says a change looks like at the measured channel: crack signatures per element and
benign changes, by re-solving the model (not a first-order expansion around it).

Both are anchored at the measured healthy FRF ``T_h``: the model supplies the relative change
``G_changed / G - 1`` and the data the level, ``T_h (G_changed / G - 1)`` (m/N). On the crack rig this
halves the part of a benign change the nominal model cannot explain compared with the absolute
change ``G_changed - G`` (E -1 %: 27 % against 48 % of the change left after the best fit; bearing
+-2 %: 38-48 % against 61-72 %).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorcheck.config import RigConfig
from rotorcheck.fe.assembly import build_system, config_key
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.modal_anchor import (
    POLE_SENSITIVITY_ERROR,
    RESIDUE_SENSITIVITY_ERROR,
    FEModes,
    ModalAnchor,
    ModalSensitivity,
    fe_modes,
    fit_anchor,
    sensitivity,
)
from rotorcheck.modal_anchor import SILENT as MODAL_SILENT
from rotorcheck.nominal import ChannelPair, model_pairs, nominal_model, pair_receptance, primary_pair
from rotorcheck.robust.affine import AffineModel, AffineParameter
from rotorcheck.robust.joint import ModelForm
from rotorcheck.variability import BenignParameter, benign_parameters, with_benign

#: stiffness loss (fraction of the element's E) at which a crack signature is re-solved
SIGNATURE_LOSS = 1e-3
#: relative signature norm below which an element counts as invisible at the channel
VISIBLE = 1e-4


def io_frf(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float,
           pairs: Sequence[ChannelPair] | None = None, system: MechanicalSystem | None = None) -> np.ndarray:
    """The model's receptance actuator -> sensor (f,), m/N; with ``pairs`` every channel pair's (f, P).
    ``system``: ``config`` assembled (:func:`rotorcheck.fe.assembly.build_system`) when the caller has it.

    Without ``system`` the result is kept for equal arguments (the rig by its content): ``detect`` solves
    the healthy model and each element's crack signature from several places (the joint test, the
    certificate beyond benign change, the detectability figures); a copy is returned each time."""
    if system is None:
        key = _frf_key(config, freq_hz, speed_rpm, pairs)
        hit = _IO_FRF.get(key) if key is not None else None
        if hit is None:
            hit = io_frf(config, freq_hz, speed_rpm, pairs, build_system(config))
            if key is not None:
                _IO_FRF[key] = hit
                _bounded(_IO_FRF, 64)
        return hit.copy()
    several = model_pairs(config, pairs)  # any list but the rig's own pair alone
    if several is not None:
        return pair_receptance(config, freq_hz, speed_rpm, several, system)
    g = nominal_model(config, freq_hz, speed_rpm, system).frf
    return g[:, None] if pairs is not None else g


#: :func:`io_frf` results by :func:`_frf_key`
_IO_FRF: dict[tuple[Any, ...], np.ndarray] = {}


def _frf_key(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float,
             pairs: Sequence[ChannelPair] | None) -> tuple[Any, ...] | None:
    """Equal keys, equal :func:`io_frf`: the rig's content (:func:`rotorcheck.fe.assembly.config_key`) less its
    ``variability`` ranges (they change no model: a baseline's learned ranges, the drift learning's trial ranges),
    the grid's bytes, the speed and the channel pairs' ports; None: not kept."""
    content = config_key(config, exclude={"variability"})
    if content is None:
        return None
    f = np.ascontiguousarray(np.asarray(freq_hz, dtype=float))
    ports = None if pairs is None else tuple(p.key() for p in pairs)
    return content, f.shape, f.tobytes(), float(speed_rpm), ports


#: relative step of a factor parameter or an element's loss (and rpm of a speed offset) at which the model's modes
#: are re-solved for a modal-anchored sensitivity: small beside the spacing of close modes (3.5e-4 between the
#: forward and backward whirl at 172.7 Hz and 1000 rpm), large beside the eigenvalues' round-off
MODAL_STEP = 1e-5
MODAL_STEP_RPM = 0.01
#: the model's relative error in the change of its modes outside the fitted band (the quasi-static compliance
#: inside it) that a benign parameter makes
OUT_OF_BAND_ERROR = 0.5
#: the modal fit's misfit (relative residual norm) up to which the model-form prior keeps its scales: the bundled
#: samples' single probe at 0, 1000 and 2000 rpm fit to 0.0008-0.004; beyond, the scales grow with the misfit
MISFIT_REFERENCE = 0.002


def _dofs(system: MechanicalSystem, config: RigConfig, pairs: Sequence[ChannelPair] | None) -> list[tuple[int, int]]:
    """(input DOF, output DOF) of each channel pair (the rig's own pair without ``pairs``)."""
    return [(system.port_dof(p.input), system.port_dof(p.output)) for p in (pairs or [primary_pair(config)])]


#: :func:`modal_anchor` results by rig, grid, speed, pairs and the healthy FRF's bytes
_ANCHORS: dict[tuple[Any, ...], ModalAnchor | None] = {}


def modal_anchor(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, healthy_frf: np.ndarray,
                 pairs: Sequence[ChannelPair] | None = None, healthy_var: np.ndarray | None = None
                 ) -> ModalAnchor | None:
    """The healthy FRF's modal model (:func:`rotorcheck.modal_anchor.fit_anchor`) with the rig's modes as the
    start; ``healthy_frf`` (f,) or (f, P) m/N (stacked pair after pair is read too), ``healthy_var`` its variance
    (same shape, m^2/N^2; the misfit is then judged beyond the noise). None when the fit is refused (the caller
    then anchors the model's own relative change). Kept for equal arguments."""
    f = np.asarray(freq_hz, dtype=float)
    P = 1 if not pairs else len(pairs)
    th = unstacked(np.asarray(healthy_frf, dtype=complex), (f.size, P))
    vh = None if healthy_var is None else unstacked(np.asarray(healthy_var, dtype=float), (f.size, P))
    base = _frf_key(config, f, speed_rpm, pairs)
    key = None if base is None else (*base, th.tobytes(), None if vh is None else vh.tobytes())
    if key is not None and key in _ANCHORS:
        return _ANCHORS[key]
    system = build_system(config)
    out = fit_anchor(system, speed_rpm, _dofs(system, config, pairs), f, th, vh)
    if key is not None:
        _ANCHORS[key] = out
        _bounded(_ANCHORS, 32)
    return out


def _modal_sensitivity(anchor: ModalAnchor, config: RigConfig, speed_rpm: float, step: float,
                       pairs: Sequence[ChannelPair] | None) -> ModalSensitivity | None:
    """The anchor's sensitivity to a change that gives the rig ``config`` at ``speed_rpm`` when made ``step``
    units large (the change's own size: a loss, a relative change, rpm). The changed rig's modes are kept for
    equal rigs, speeds and pairs, as :func:`io_frf`'s receptances were: detect asks for every element's
    signature from the joint test and again from the diagnosis (the rig's benign ranges change no mode: not in the
    key)."""
    content = config_key(config, exclude={"variability"})
    key = None if content is None else (content, float(speed_rpm),
                                        None if pairs is None else tuple(p.key() for p in pairs))
    modes = _FE_MODES.get(key) if key is not None else None
    if modes is None:
        system = build_system(config)
        modes = fe_modes(system, speed_rpm, _dofs(system, config, pairs))
        if key is not None:
            _FE_MODES[key] = modes
            _bounded(_FE_MODES, 64)
    return sensitivity(anchor, modes, step)


#: the changed rigs' modes of :func:`_modal_sensitivity`
_FE_MODES: dict[tuple[Any, ...], FEModes] = {}


#: a channel pair whose model receptance is below this fraction of the largest pair's is one the model
#: says does not respond (x force -> y probe at standstill: the planes decouple); its predicted relative
#: change is taken as none (the modal anchor's own :data:`rotorcheck.modal_anchor.SILENT`)
SILENT = MODAL_SILENT


def relative(g: np.ndarray, g0: np.ndarray) -> np.ndarray:
    """``g / g0`` per point and pair, 1 where the model's ``g0`` is silent (:data:`SILENT`)."""
    g0 = np.asarray(g0)
    scale = np.max(np.abs(g0)) if g0.size else 0.0
    quiet = np.abs(g0) <= SILENT * scale
    return np.where(quiet, 1.0, np.asarray(g) / np.where(quiet, 1.0, g0))


def unstacked(x: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """An array as ``shape`` (f, P); a 1-D array of f P values is taken as :func:`stacked` (pair after pair),
    never reshaped row-major (that would interleave the pairs)."""
    a = np.asarray(x)
    if len(shape) == 2 and a.ndim == 1 and a.size == shape[0] * shape[1]:
        return a.reshape(shape[1], shape[0]).T
    return a.reshape(shape)


def stacked(x: np.ndarray) -> np.ndarray:
    """An (f, P) array as one vector, channel pair after channel pair (P f,); an (f,) array as it is."""
    x = np.asarray(x)
    return x.T.ravel() if x.ndim == 2 else x


def with_element_loss(config: RigConfig, element: int, loss: float) -> RigConfig:
    """``config`` with shaft element ``element`` (1-based) stiffer by ``1 - loss`` (its E times that)."""
    shaft = [e.model_copy(update={"modulus_factor": e.modulus_factor * (1.0 - loss)}) if e.start == element else e
             for e in config.shaft]
    return config.model_copy(update={"shaft": shaft})


def candidate_elements(config: RigConfig) -> tuple[int, ...]:
    """Every shaft element (1-based) of a rotor; none for a lumped rig."""
    return tuple(sorted(e.start for e in config.shaft)) if config.kind == "rotor" else ()


def crack_signatures(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, healthy_frf: np.ndarray,
                     elements: Sequence[int] | None = None, loss: float = SIGNATURE_LOSS,
                     pairs: Sequence[ChannelPair] | None = None, model_frf: np.ndarray | None = None,
                     modal: bool = True, healthy_var: np.ndarray | None = None) -> tuple[tuple[int, ...], np.ndarray]:
    """``(elements, S)``: S (n_e, f) complex, the FRF change per unit stiffness loss (m/N per 1) of
    each element, anchored at ``healthy_frf``: with ``modal`` (default) the healthy FRF's fitted modes moved
    by the model's sensitivities (:mod:`rotorcheck.modal_anchor`), else (or when that fit is refused) the
    model re-solved at ``loss`` as a relative change; with ``pairs`` (``healthy_frf`` (f, P)) each row is
    stacked over the pairs (P f,), pair after pair. ``model_frf``: the model's :func:`io_frf` at these
    arguments when the caller has it (else solved here); ``healthy_var``: the healthy FRF's variance for the
    anchor's fit (:func:`modal_anchor`)."""
    f = np.asarray(freq_hz, dtype=float)
    els = tuple(elements) if elements is not None else candidate_elements(config)
    g0 = model_frf if model_frf is not None else io_frf(config, f, speed_rpm, pairs)
    th = unstacked(healthy_frf, g0.shape)
    anchor = modal_anchor(config, f, speed_rpm, th, pairs, healthy_var) if modal else None

    def signature(e: int) -> np.ndarray:
        if anchor is not None:
            sens = _modal_sensitivity(anchor, with_element_loss(config, e, MODAL_STEP), speed_rpm, MODAL_STEP, pairs)
            if sens is not None:
                return stacked(anchor.derivative(sens.d_lnpole, sens.d_res, sens.d_out))
        changed = with_element_loss(config, e, loss)
        return stacked(th * (relative(io_frf(changed, f, speed_rpm, pairs), g0) - 1.0) / loss)

    S = np.array([signature(e) for e in els], dtype=complex).reshape(len(els), th.size)
    healthy_frf = stacked(th)
    # an element the channel cannot see (an overhang with a free end carries no bending moment): its
    # "signature" is round-off, not a shape; it is no candidate
    scale = np.abs(healthy_frf)  # a silent pair (0: y probe of an x force at standstill) weighs nothing, not NaN
    norms = (np.linalg.norm(np.divide(S, scale, out=np.zeros_like(S), where=scale > 0), axis=1) if S.size
             else np.zeros(0))
    seen = norms > VISIBLE * (norms.max() if norms.size else 0.0)
    return tuple(e for e, k in zip(els, seen) if k), S[seen]


def _bounded(cache: dict[Any, Any], size: int = 256) -> None:
    """Drop the oldest entry of ``cache`` beyond ``size`` entries."""
    if len(cache) > size:
        cache.pop(next(iter(cache)))


@dataclass(frozen=True)
class BenignPrediction:
    """``predict(theta)``: the benign change (f,) m/N at parameter values ``theta`` (in the
    :class:`BenignParameter` units: relative change for factors, offset for offsets)."""

    parameters: tuple[BenignParameter, ...]
    predict: Callable[[np.ndarray], np.ndarray]
    model_form: ModelForm | None = None  # the prediction's own bounded error (modal anchor only)
    cheap: bool = False  # ``predict`` is a closed form (modal anchor), no model re-solved
    #: (p,) relative standard error of each fitted parameter from the model's error in its pole sensitivities (a
    #: parameter read off the poles through a sensitivity wrong by e is wrong by e / sensitivity of itself): the
    #: modal anchor's POLE_SENSITIVITY_ERROR over the median |d ln(lambda) / d theta| of the fitted modes; 0 for
    #: gains and offsets, None off the anchor
    relative_error: np.ndarray | None = None

    @property
    def lo(self) -> np.ndarray:
        return np.array([p.lo for p in self.parameters], dtype=float)

    @property
    def hi(self) -> np.ndarray:
        return np.array([p.hi for p in self.parameters], dtype=float)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)


def benign_prediction(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, healthy_frf: np.ndarray,
                      parameters: Sequence[BenignParameter] | None = None,
                      pairs: Sequence[ChannelPair] | None = None, modal: bool = True,
                      healthy_var: np.ndarray | None = None) -> BenignPrediction:
    """The model's benign change around ``config`` at ``speed_rpm``, anchored at ``healthy_frf``: with
    ``modal`` (default) the healthy FRF's fitted modes moved by the model's sensitivities,
    ``g_s g_a (T_h + dT(theta)) - T_h`` (:mod:`rotorcheck.modal_anchor`); else (or when that fit is refused)
    ``T_h (g_s g_a G(theta) / G - 1)`` with the model re-solved at ``theta``; gains multiply; with ``pairs``
    (``healthy_frf`` (f, P)) stacked over the pairs (P f,); ``healthy_var``: the healthy FRF's variance for the
    anchor's fit (:func:`modal_anchor`)."""
    f = np.asarray(freq_hz, dtype=float)
    params = tuple(parameters) if parameters is not None else benign_parameters(config)
    g0 = io_frf(config, f, speed_rpm, pairs)
    th = unstacked(healthy_frf, g0.shape)
    anchor = modal_anchor(config, f, speed_rpm, th, pairs, healthy_var) if modal else None
    if anchor is not None:
        modal_prediction = _modal_benign(anchor, config, speed_rpm, th, params, pairs)
        if modal_prediction is not None:
            return modal_prediction
    cache: dict[tuple[float, ...], np.ndarray] = {}
    # the model re-solved depends on the parameters that change the rig and on the speed offset only: a
    # gain (the finite-difference column of a Jacobian, the exact part of the model-error allowance) or a
    # speed change re-uses the solve or the assembled rig of the same values (the same numbers, not re-done)
    solved: dict[tuple[tuple[float, ...], float], np.ndarray] = {}
    systems: dict[tuple[float, ...], tuple[RigConfig, MechanicalSystem]] = {}

    def predict(theta: np.ndarray) -> np.ndarray:
        key = tuple(float(x) for x in theta)
        if key not in cache:
            # the speed offset and the gains (no config change), then the rig's own parameters where a
            # re-solve needs their config (with_benign applies each parameter on its own)
            _, d_rpm, g_s, g_a = with_benign(config, {p.name: float(x) for p, x in zip(params, theta)
                                                      if not p.changes_model})
            rig_key = tuple(float(x) for p, x in zip(params, theta) if p.changes_model)
            resolve = d_rpm != 0.0 or any(x != 0.0 for x in rig_key)
            g = g0
            if resolve:
                hit = solved.get((rig_key, d_rpm))
                if hit is None:
                    rig = systems.get(rig_key)
                    if rig is None:
                        cfg = with_benign(config, {p.name: float(x) for p, x in zip(params, theta)
                                                   if p.changes_model})[0]
                        rig = systems[rig_key] = (cfg, build_system(cfg))
                        _bounded(systems)
                    hit = solved[(rig_key, d_rpm)] = io_frf(rig[0], f, speed_rpm + d_rpm, pairs, rig[1])
                    _bounded(solved)
                g = hit
            cache[key] = stacked(th * (g_s * g_a * relative(g, g0) - 1.0))
            _bounded(cache)
        return cache[key]

    return BenignPrediction(params, predict)


def _modal_benign(anchor: ModalAnchor, config: RigConfig, speed_rpm: float, th: np.ndarray,
                  params: tuple[BenignParameter, ...], pairs: Sequence[ChannelPair] | None) -> BenignPrediction | None:
    """:func:`benign_prediction` on the modal anchor: each parameter's sensitivity from the model's modes
    re-solved at :data:`MODAL_STEP` (a speed offset: :data:`MODAL_STEP_RPM`); gains multiply. None when a
    mode cannot be followed."""
    sens: list[ModalSensitivity | None] = []
    for p in params:
        if p.is_gain:
            sens.append(None)
            continue
        step = MODAL_STEP_RPM if p.is_speed else MODAL_STEP
        cfg, d_rpm, _, _ = with_benign(config, {p.name: step})
        s = _modal_sensitivity(anchor, cfg, speed_rpm + d_rpm, step, pairs)
        if s is None:
            return None
        sens.append(s)
    gains = [i for i, p in enumerate(params) if p.is_gain]
    moving = [i for i, s in enumerate(sens) if s is not None]
    given = [s for s in sens if s is not None]
    d_ln = np.array([s.d_lnpole for s in given]).reshape(len(given), anchor.poles.size)
    d_res = np.array([s.d_res for s in given]).reshape(len(given), *anchor.residues.shape)
    d_out = np.array([s.d_out for s in given]).reshape(len(given), th.shape[0], anchor.residues.shape[1])
    cache: dict[tuple[float, ...], np.ndarray] = {}
    th = th.reshape(th.shape[0], -1)

    def predict(theta: np.ndarray) -> np.ndarray:
        key = tuple(float(x) for x in theta)
        if key not in cache:
            x = np.asarray(theta, dtype=float)
            xm = x[moving]
            change = anchor.change(xm @ d_ln, np.tensordot(xm, d_res, axes=1), np.tensordot(xm, d_out, axes=1))
            g = float(np.prod([1.0 + x[i] for i in gains])) if gains else 1.0
            cache[key] = stacked(g * (th + change) - th)
            _bounded(cache)
        return cache[key]

    # how far each fitted pole may sit from its predicted place: the model's pole sensitivities are uncertain by
    # POLE_SENSITIVITY_ERROR (absolute) for a relative parameter, by their own size for an offset, times the range
    # the change of the modes outside the fit (a quasi-static compliance inside the band) is the model's too: it
    # may be off by OUT_OF_BAND_ERROR of its largest size over the ranges, as a constant (real and imaginary) and a
    # 1 / w^2 line per channel pair
    reach = reach_r = 0.0
    out_size = np.zeros(d_out.shape[1:])  # (f, P): the other modes' change over the ranges, parameter by parameter
    for k, i in enumerate(moving):
        p = params[i]
        if not p.changes_model:
            continue
        size = max(abs(p.lo), abs(p.hi))
        own = float(np.max(np.abs(d_ln[k])))
        reach += size * (POLE_SENSITIVITY_ERROR if p.kind == "factor" else own)
        reach_r += size * (RESIDUE_SENSITIVITY_ERROR if p.kind == "factor" else own)
        out_size += size * np.abs(d_out[k])
    # learned from the healthy sweep: a modal model that fits it less well (physics the model lacks: damping in
    # the bearings, a support mode) predicts less well; the prior widens in proportion beyond the reference fit
    widen = max(1.0, anchor.misfit / MISFIT_REFERENCE)
    reach, reach_r = reach * widen, reach_r * widen
    out_reach = widen * OUT_OF_BAND_ERROR * np.max(out_size, axis=0)  # (P,)
    dirs: list[np.ndarray] = []
    bounds: list[float] = []
    if reach > 0:
        dirs.extend(stacked(v) for v in anchor.pole_directions())
        bounds.extend([reach] * (2 * anchor.poles.size))
    if reach_r > 0:
        for r, per_mode in enumerate(anchor.residue_directions()):
            for part in per_mode:
                for q in range(th.shape[1]):
                    dirs.append(stacked(part[..., q]))
                    bounds.append(reach_r * float(abs(anchor.residues[r, q])))
    w = anchor.omega
    for k, size in enumerate(out_reach):
        if size <= 0:
            continue
        for shape in (np.ones_like(w), 1j * np.ones_like(w), (w.min() / w) ** 2):
            one = np.zeros((w.size, th.shape[1]), dtype=complex)
            one[:, k] = shape
            dirs.append(stacked(one))
            bounds.append(float(size))
    # a direction with no prior scale (a silent pair's residue or compliance) is no freedom at all
    scales = np.array(bounds, dtype=float)
    keep = scales > 0
    dirs = [d for d, k in zip(dirs, keep) if k]
    bounds = [float(b) for b, k in zip(scales, keep) if k]
    form = None
    if dirs:
        form = ModelForm(np.array(dirs), np.array(bounds),
                         f"each fitted mode's pole off its predicted place by {POLE_SENSITIVITY_ERROR:g}, each residue "
                         f"by {RESIDUE_SENSITIVITY_ERROR:g} of itself, per unit of the summed relative ranges, and the "
                         f"other modes' change by {OUT_OF_BAND_ERROR:g} of itself (1 sigma"
                         + (f"; x {widen:.2g}: the healthy sweep's modal fit leaves {anchor.misfit:.2g} of it"
                            if widen > 1 else "") + ")")
    rel = np.zeros(len(params))
    for k, i in enumerate(moving):
        typical = float(np.median(np.abs(d_ln[k])))
        if params[i].kind == "factor" and params[i].changes_model and typical > 0:
            rel[i] = POLE_SENSITIVITY_ERROR / typical
    return BenignPrediction(params, predict, form, True, rel)


@dataclass(frozen=True)
class BenignBox:
    """The rig's benign parameters as an affine real-parameter model of the dynamic stiffness
    (:class:`rotorcheck.robust.affine.AffineModel`, seen from one channel pair) plus the gain factor's
    range; ``notes`` name the parameters whose damping change is held at its healthy value."""

    model: AffineModel
    gain: tuple[float, float]
    names: tuple[str, ...]
    notes: tuple[str, ...]
    system: Any = field(repr=False)  # the assembled rig (fe.system.MechanicalSystem): its ports' DOFs

    def for_pair(self, pair: ChannelPair) -> BenignBox:
        """The same parameters seen from ``pair`` (unit force at its input, displacement at its output)."""
        b = np.zeros(self.system.n_dof)
        c = np.zeros(self.system.n_dof)
        b[self.system.port_dof(pair.input)] = 1.0
        c[self.system.port_dof(pair.output)] = 1.0
        return dataclasses.replace(self, model=dataclasses.replace(self.model, b=b, c=c))


def benign_box(config: RigConfig, speed_rpm: float, parameters: Sequence[BenignParameter] | None = None,
               speed_offset: float = 0.0, pair: ChannelPair | None = None) -> BenignBox:
    """The benign parameters of ``config`` at ``speed_rpm``, seen from ``pair`` (default: the rig's
    actuator -> sensor; :meth:`BenignBox.for_pair` for others), as real parameters entering the dynamic
    stiffness affinely: each parameter by the exact change of M, C and K per unit (checked affine at its
    range's ends and centre), the speed tolerance by ``Omega G`` (range moved by ``speed_offset`` rpm), the
    gains as one factor. Modal damping is rebuilt from the changed modes (not affine in a stiffness): it
    is held at its healthy value, which on the crack rig moves a predicted benign change by less than 5 %
    of itself (3.1 % at most in the test's draws, 30-495 Hz), far inside the model-error allowance. A
    stiffness or mass that is not affine in its parameter raises ValueError naming it."""
    params = tuple(parameters) if parameters is not None else benign_parameters(config)
    sys0 = build_system(config)
    M, C, G, K = sys0.matrices(speed_rpm)
    affine: list[AffineParameter] = []
    g_lo, g_hi = 1.0, 1.0
    held: list[str] = []
    for prm in params:
        if prm.is_gain:
            g_lo, g_hi = g_lo * (1.0 + prm.lo), g_hi * (1.0 + prm.hi)
            continue
        if prm.is_speed:
            affine.append(AffineParameter(prm.name, (("D", G * RPM_TO_RAD_S),), prm.lo + speed_offset,
                                          prm.hi + speed_offset))
            continue
        lo_m, mid_m, hi_m = (build_system(with_benign(config, {prm.name: x})[0]).matrices(speed_rpm)
                             for x in (prm.lo, 0.5 * (prm.lo + prm.hi), prm.hi))
        span = prm.hi - prm.lo
        terms = []
        for kind, j, base in (("M", 0, M), ("D", 1, C), ("K", 3, K)):
            dA = (hi_m[j] - lo_m[j]) / span
            if np.abs(dA).max() <= 1e-12 * max(np.abs(base).max(), 1e-300):
                continue
            tol = 1e-9 * np.abs(base).max()
            affine_here = np.allclose(0.5 * (hi_m[j] + lo_m[j]), mid_m[j], rtol=0.0, atol=tol)
            if kind == "D" and not affine_here:
                held.append(prm.name)  # modal damping rebuilt from the changed modes: held at the centre
                continue
            if not affine_here:
                raise ValueError(f"{prm.name}: the {'mass' if kind == 'M' else 'stiffness'} matrix is not affine "
                                 "in it; the per-point certificate cannot take it")
            terms.append((kind, dA))
        affine.append(AffineParameter(prm.name, tuple(terms), prm.lo, prm.hi))
    notes = [f"damping held at its healthy value for {', '.join(held)} (modal damping rebuilt from the changed "
             "modes is not affine in the parameter)"] if held else []
    n = sys0.n_dof
    model = AffineModel(M, C + speed_rpm * RPM_TO_RAD_S * G, K, np.zeros(n), np.zeros(n), tuple(affine))
    box = BenignBox(model, (g_lo, g_hi), tuple(a.name for a in affine), tuple(notes), sys0)
    return box.for_pair(pair if pair is not None else primary_pair(config))
