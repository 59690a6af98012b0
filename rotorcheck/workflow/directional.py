"""The damage dynamics at the damage station in x and y (N/m) from several channel pairs, with intervals."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorcheck.config import Port, RigConfig
from rotorcheck.nominal import ChannelPair, pair_receptance
from rotorcheck.progress import Progress
from rotorcheck.robust.damage_block import DamageBlockBound, damage_block_bound
from rotorcheck.robust.identify import damage_dynamics
from rotorcheck.workflow.measured import MeasuredRun, PairGrid

#: refinement rounds of the certified bound (:func:`rotorcheck.robust.damage_block.damage_block_bound`): none.
#: On the bundled x/y samples the rounds moved the outer (certified) ends by at most 2e-5 relative at 0 rpm and
#: left 94-98 % of the widths unchanged at 1000 rpm (the largest change 7 % of one width), at 3.5 times the cost
#: (the whole bound 9.8 -> 2.8 s of CPU per 261-point sweep); they mostly add witnesses inside.
DAMAGE_BOUND_REFINE = 0


@dataclass
class DirectionalDamage:
    """The damage dynamics at the damage station in x and y from several channel pairs: ``estimate``
    (f, 2, 2) N/m, and per direction (columns x, y) the 95 % intervals of the real and imaginary parts of
    the diagonal, (f, 2) each, by Monte Carlo over both sweeps' noise (complex Gaussian with the stored
    variances; the model's receptances to and from the damage station taken as exact)."""

    estimate: np.ndarray
    re_interval: tuple[np.ndarray, np.ndarray]
    im_interval: tuple[np.ndarray, np.ndarray]
    draws: int
    bound: DamageBlockBound | None = None  # the certified set over the noise polydisc


def damage_per_direction(rig: RigConfig, run: MeasuredRun, healthy_frf: np.ndarray,
                         healthy_var: np.ndarray | None = None, draws: int = 200, seed: int = 20261124,
                         radius: np.ndarray | None = None, progress: Progress | None = None
                         ) -> DirectionalDamage | None:
    """With several channel pairs: the damage dynamics at the damage port's station in x and y, (f, 2, 2)
    N/m (rows and columns x, y; a stiffness loss is positive on the diagonal), eq. 3.11 in matrix form
    anchored at the measured healthy FRF: ``D = [E12 (T - T_h)^+ E21 + E11]^-1`` with the model's
    receptances between the damage DOFs and the channels, and its Monte Carlo intervals
    (:class:`DirectionalDamage`; ``healthy_var`` (f, P) the healthy FRF's variance, none: no interval).
    ``radius`` (f, P) m/N: the noise allowance of each pair's difference at a family-wise confidence; with
    it, the certified set of D over that noise polydisc (:func:`rotorcheck.robust.damage_block.damage_block_bound`;
    ``progress`` hears each frequency).
    None with one pair or no damage port, or when the pairs are not every output against every input."""

    grid = PairGrid.of(run)
    if grid is None or rig.damage is None or rig.kind != "rotor" or run.frf_pairs is None:
        return None
    ins, outs, matrix = grid.inputs, grid.outputs, grid.matrix
    dmg = [Port(station=rig.damage.port.station, direction=d) for d in ("x", "y")]
    f, nf = run.frequency_hz, run.frequency_hz.size
    T = matrix(np.asarray(run.frf_pairs))
    Th = matrix(np.asarray(healthy_frf).reshape(nf, -1))
    cross = ([ChannelPair(a, b, "") for a in dmg for b in dmg]
             + [ChannelPair(a, i, "") for a in dmg for i in ins]
             + [ChannelPair(o, b, "") for o in outs for b in dmg])
    H = pair_receptance(rig, f, run.speed_rpm, cross)
    E11 = H[:, :4].reshape(nf, 2, 2)
    E12 = H[:, 4:4 + 2 * len(ins)].reshape(nf, 2, len(ins))
    E21 = H[:, 4 + 2 * len(ins):].reshape(nf, len(outs), 2)

    def solve(t: np.ndarray, th: np.ndarray, reps: int = 1) -> np.ndarray:
        """D for ``reps`` stacked copies of the grid (draw after draw)."""
        e11, e12, e21 = (np.tile(x, (reps, 1, 1)) for x in (E11, E12, E21))
        with np.errstate(all="ignore"):
            return np.asarray(damage_dynamics(e11, e12, e21, th.reshape(-1, *th.shape[-2:]),
                                              t.reshape(-1, *t.shape[-2:])))

    try:
        est = solve(T, Th)
    except np.linalg.LinAlgError:
        return None
    bound = None
    if radius is not None:

        bound = damage_block_bound(E11, E12, E21, T - Th, matrix(np.asarray(radius, dtype=float).reshape(nf, -1)),
                                   refine=DAMAGE_BOUND_REFINE, progress=progress)
        est = bound.estimate  # the weighted least-squares member (its W) rather than the pseudo-inverse's
    nan = np.full((nf, 2), np.nan)
    if healthy_var is None or run.var_pairs is None or draws < 2:
        return DirectionalDamage(est, (nan, nan), (nan, nan), 0, bound)
    rng = np.random.default_rng(seed)

    def noisy(x: np.ndarray, var: np.ndarray) -> np.ndarray:
        sd = np.sqrt(np.asarray(var).reshape(nf, -1) / 2.0)
        return x + matrix(sd * (rng.standard_normal((draws, *sd.shape)) + 1j * rng.standard_normal((draws, *sd.shape))))

    try:
        sims = solve(noisy(T, run.var_pairs), noisy(Th, healthy_var), draws).reshape(draws, nf, 2, 2)
    except np.linalg.LinAlgError:
        return DirectionalDamage(est, (nan, nan), (nan, nan), 0, bound)
    diag = sims[:, :, [0, 1], [0, 1]]  # (draws, f, 2)
    lo_re, hi_re = np.nanpercentile(diag.real, [2.5, 97.5], axis=0)
    lo_im, hi_im = np.nanpercentile(diag.imag, [2.5, 97.5], axis=0)
    return DirectionalDamage(est, (lo_re, hi_re), (lo_im, hi_im), draws, bound)

