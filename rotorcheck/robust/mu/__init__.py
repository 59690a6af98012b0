"""Generalized structured singular value bound as an LMI per frequency (cvxpy + Clarabel).

Validation problem at one frequency (dissertation eq. 3.1-3.6, method.md): the uncertain model
``z = F_u(Me, Delta_u) W + v`` explains the data ``Zt`` iff there are ``|Delta_u| <= gamma``,
``|v_k| <= V`` with zero residual. As an implicit LFT in ``x = (u, e, t)`` (``u`` the outputs of
the uncertainty blocks, ``e`` the normalized noise, ``t`` the homogeneous multiplier of the data)::

    block i:  input A_i x = (Me11 u + Me12 W t)_i,  output B_i x = u_i,   |Delta_i| <= w_i gamma
    noise k:  input t,                                output e_k,          |Delta_v,k| <= 1
    kernel:   N x = (Zt - Me22 W) t - Me21 u - V e = 0            (V in the residual row)

Certificate of invalidation (S-procedure on the kernel, P an orthonormal basis of Ker N)::

    P^* ( sum_i D_i-scaled( r_i^2 A_i^* A_i - B_i^* B_i ) ) P  < 0

with scalar ``d_i >= 0`` for complex scalar and full blocks and a Hermitian PSD ``D_i`` for
repeated complex scalar blocks (``delta I_k``). With one uncertainty block (scalar or full) its
scale is fixed to 1 and ``gamma^2 = s`` enters linearly: ONE SDP per frequency,
``maximize s  s.t.  P^*(s F_u + F_0 + sum d_k F_k) P <= 0``. Several uncertainty blocks sharing one
gamma, or a repeated-scalar uncertainty block, give a generalized eigenvalue problem; it is solved by
bisection on ``s`` with an LMI feasibility problem (minimize lambda) at each step (documented
exception to the one-SDP rule).

Real scalar blocks (mixed mu): ``Block('real', (k, k))`` (:meth:`Structure.real`) is ``delta I_k``
with delta REAL, ``|delta| <= w gamma`` (k = 1 a real parameter, k > 1 one entering with rank k).
For ``u = delta v``, ``v^* G u - u^* G v = 0`` for every Hermitian G, so such a block adds the free
term ``j (B_i^* G_i A_i - A_i^* G_i B_i)`` to the certificate (G a real scalar for k = 1, Hermitian
for k > 1, either sign): the D-G scaling bound of mixed mu (Fan, Tits and Doyle, IEEE TAC 36(1),
1991). With G = 0 it is the complex certificate, so a real block's ``gamma_lower`` is never below the
complex one. One real scalar (k = 1) keeps ONE SDP per point (D fixed to 1, G free); a repeated real
block or several blocks use the bisection. The clarabel backend solves these LMIs (and those with
Hermitian D-scales) directly (:class:`~.backends.ClarabelGeneralLmi`), the cvxpy backend with cvxpy.
The explicit Delta of a real block is real: the real fit ``Re(v^* u) / |v|^2`` of the kernel vector,
a Gauss-Newton polish and the SQP refinement in real unknowns; when the only block is real the
smallest feasible delta is found exactly (:func:`~.witness.exact_single_real`: the residual times
``det(I - delta Me11)`` is a polynomial of degree k, so each ``|r_j|^2 <= V^2`` is a polynomial
inequality of degree 2k in delta whose real roots and 0 are the only candidates), verified by direct
evaluation. Measured (tests/robust/test_mixed_mu.py): D-G is exact for one real parameter with SISO
data (gap < 1e-7); one real + one complex block keeps a true relaxation gap on a few cases (up to
7 %). V = 0 with a real block is ill-posed in floating point (the data pin delta, real only to
rounding): such points use the noise bound ``REAL_V0_FLOOR * max|Zt|`` (1e-6 relative); data far
from every real delta relative to that floor make the unexplainability certificate ill-conditioned
(a G-scale of about 1/V) and Clarabel stalls at some points, reported 'lower_only' or
'solver_failed'. Give V > 0 with a real block.

Bounds, per frequency (what each number certifies):

* ``gamma_lower``: every gamma below it is *proven* invalidated. It is recomputed from the solver's
  D-scales by an eigenvalue computation (``max s`` with ``s F_u + G(d) < 0``), so it does not rely on
  the solver's reported objective.
* ``gamma_upper``: the size of an explicit structured ``Delta`` (built from the kernel vector of the
  optimal LMI, then polished by Gauss-Newton) that reproduces the data within the noise bound,
  checked by evaluating ``F_u(Me, Delta) W`` directly.

So ``gamma_lower <= gamma_required <= gamma_upper``. (In mu language the LMI is the upper bound on
mu and the explicit Delta the lower bound; in gamma = 1/mu the roles swap.) For SISO (two complex
scalar blocks) the relaxation is exact and the gap is below 1e-7 relative (the explicit Delta is
accepted as soon as it is within 1e-7 of the certificate). With several blocks the explicit Delta is
additionally refined by a local SQP (gap ~1e-9 on the tests).

Numerics (method.md's pitfalls and what the tests showed):

* per-frequency scaling: residual rows by ``max(|c_k|, V)`` (``c = Zt - Me22 W``), u-columns by
  ``max|c| / ||Me21||``, gamma by an estimate (the noise-free answer, an exact generalized
  eigenvalue, shrunk by ``(|c| - V) / |c|``), noise D-scales by ``(V/|c|)((|c| - V)/|c|)`` (their
  value at the optimum for additive SISO; without it a tiny V stalls Clarabel);
* near gamma* = 0 (``|c|`` barely above V) the worst case is a near-cancellation; the SDP is then
  posed in a kernel basis adapted to it (first the heuristic "noise aligned with the residual", after
  a pass the LMI's own worst-case vector) and re-solved: a second pass, as method.md says;
* pre-checks ``|Zt - Me22 W| <= V`` (gamma = 0, no solve) and ``Me12 W = 0`` or ``Me21 = 0``
  (status 'unexplainable', gamma = inf, never a number);
* explicit projection onto Ker N (no free multiplier); no chordal decomposition; one thread;
* solver status point by point: the D-scales of every solver answer are projected onto their
  cones before the certificate is checked (a stalled iterate returns scales of about -1e-7 for
  noise blocks inactive at the optimum; with them the "certified" lower bound exceeded the exact
  answer by up to 4e-7 relative and points failed); Clarabel's 'InsufficientProgress' /
  'AlmostSolved' iterates are used if the independently verified bounds agree within 1e-6, else
  the point is re-solved by bisection on the same LMI (method 'sdp+bisect');
* per point, never the batch: non-finite Me, W or Zt -> 'bad_data'; a solver raising (also a
  ``BaseException`` such as Clarabel's pyo3 ``PanicException``) or a point exceeding
  ``time_limit`` seconds (passed to Clarabel as its ``time_limit``) -> 'solver_failed' with the
  reason in ``GammaResult.reason``; a negative or NaN noise bound is a ``ValueError``;
* accuracy floor: gamma* is a function of ``|c| - V``; the data determine it only to about
  ``eps |Zt| / (|c| - V)`` relative (1e-6 at ``(|c| - V)/|c| ~ 1e-7`` with ``|Zt| ~ 1e3 |c|``).

Backends: 'cvxpy' builds each LMI once per shape with cvxpy Parameters and re-solves it per
frequency; 'clarabel' (the default) fills the identical conic data and calls Clarabel directly,
skipping cvxpy's per-solve canonicalization. Both give the same bounds (to about 1e-10 relative)
and statuses. The built problems live in an :class:`LmiCache` (one per call unless passed in): no
module state, so concurrent calls in threads are independent.

Stacked first pass: the plain first SDP pass of all the points of a call that start with one (V > 0,
one uncertainty block, not a near-cancellation) -- kernel bases, projected forms, conic data,
certificate check, explicit Delta and its polish -- is computed with numpy over the stack of points;
only the solver calls remain per point. The per-point driver then continues from it (a second
pass, the SQP refinement, the bisection fallback) exactly as from its own first pass.

Modules, each importing only those before it: :mod:`.structure` (blocks, layout, point data,
statuses, result), :mod:`.backends` (the two solver backends, the cache, the per-point guard),
:mod:`.certificates` (the scaled implicit LFT and the eig / SDP / bisection engines),
:mod:`.witness` (the explicit Delta), :mod:`.driver` (the per-point driver, entry points).

Units: gamma in the units of Delta_u (m/N for additive receptance uncertainty, kg for a mass
parameter, dimensionless for multiplicative); V in m (output displacement).
"""

from __future__ import annotations

from rotorcheck.lazy import lazy_exports

_HOME = {
    "BACKENDS": "backends", "LmiCache": "backends",
    "ImplicitBound": "certificates", "implicit_lmi_bound": "certificates",
    "inject_solver_failure": "driver", "required_gamma": "driver", "required_gamma_bisection": "driver",
    "DEFAULT_BACKEND": "structure", "DEFAULT_TIME_LIMIT": "structure", "STATUS_BAD_DATA": "structure",
    "STATUS_FAILED": "structure", "STATUS_LOWER_ONLY": "structure", "STATUS_OK": "structure",
    "STATUS_UNEXPLAINABLE": "structure", "Block": "structure", "GammaResult": "structure",
    "Structure": "structure", "blocks_for": "structure", "check_noise_bound": "structure",
    "REAL_V0_FLOOR": "structure",
}

__all__, __getattr__, __dir__ = lazy_exports(__name__, _HOME)
