"""Linear fractional transformations and the Me builders, vectorized over a leading frequency axis.

Conventions (all arrays complex, frequency axis first, shape ``(f, rows, cols)``):

* Upper LFT, ``Delta`` closes the *first* channel of ``M``::

      v = M11 u + M12 w,   z = M21 u + M22 w,   u = Delta v
      F_u(M, Delta) = M22 + M21 Delta (I - M11 Delta)^-1 M12

  ``M11`` is ``(n_v, n_u)`` and ``Delta`` is ``(n_u, n_v)``.
* Lower LFT, ``D`` closes the *last* channel::

      z = M11 w + M12 u,   y = M21 w + M22 u,   u = D y
      F_l(M, D) = M11 + M12 D (I - M22 D)^-1 M21

  ``M22`` is ``(n_y, n_u)`` and ``D`` is ``(n_u, n_y)``.

The damage LFT of method.md, ``T = E22 + E21 D (I - E11 D)^-1 E12`` with port 1 = damage port, is
``F_u([[E11, E12], [E21, E22]], D)`` in this notation (method.md calls it "lower" because the
dissertation draws D below the engineering system; the algebra is what matters).

Receptances are in m/N and dynamic stiffnesses in N/m; nothing here depends on the units.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "additive_me",
    "as_freq_matrix",
    "damper_factor",
    "engineering_me",
    "engineering_system",
    "io_me",
    "lft_lower",
    "lft_upper",
    "low_rank_factor",
    "mass_factor",
    "multiplicative_me",
    "parametric_me",
    "selector",
    "spring_factor",
]


def as_freq_matrix(X: np.ndarray | complex | float, n_freq: int | None = None) -> np.ndarray:
    """Promote a scalar, ``(f,)`` SISO array, ``(r, c)`` matrix or ``(f, r, c)`` stack to
    ``(f, r, c)`` complex.

    A 1-D array is read as one scalar per frequency. A 2-D array is a constant matrix, repeated
    ``n_freq`` times (1 if not given).
    """
    A = np.asarray(X, dtype=complex)
    if A.ndim == 0:
        A = A.reshape(1, 1, 1)
    elif A.ndim == 1:
        A = A[:, None, None]
    elif A.ndim == 2:
        A = A[None]
    elif A.ndim != 3:
        raise ValueError(f"expected at most 3 dimensions, got shape {A.shape}")
    if n_freq is not None and A.shape[0] != n_freq:
        if A.shape[0] != 1:
            raise ValueError(f"frequency axis {A.shape[0]} does not match {n_freq}")
        A = np.broadcast_to(A, (n_freq, *A.shape[1:]))
    return A


def _split_sizes(M: np.ndarray, Delta: np.ndarray, n: int | tuple[int, int] | None,
                 where: str) -> tuple[int, int]:
    """(rows, cols) of the block of M that Delta closes; Delta has shape (cols, rows)."""
    d_rows, d_cols = Delta.shape[-2:]
    if n is None:
        return d_cols, d_rows
    n_rows, n_cols = (n, n) if isinstance(n, (int, np.integer)) else (int(n[0]), int(n[1]))
    if (d_rows, d_cols) != (n_cols, n_rows):
        raise ValueError(f"{where}: Delta shape {Delta.shape[-2:]} does not fit n={n}")
    return n_rows, n_cols


def lft_upper(M: np.ndarray, Delta: np.ndarray | complex, n: int | tuple[int, int] | None = None
              ) -> np.ndarray:
    """Upper LFT ``F_u(M, Delta) = M22 + M21 Delta (I - M11 Delta)^-1 M12`` per frequency.

    ``M``: ``(f, n_v + n_z, n_u + n_w)`` (or one matrix); ``Delta``: ``(f, n_u, n_v)``, one
    matrix, or a scalar (then ``n_u = n_v = 1``). ``n`` (optional) is ``n_v`` or ``(n_v, n_u)``,
    checked against ``Delta``. Returns ``(f, n_z, n_w)``.
    """
    M = as_freq_matrix(M)
    D = as_freq_matrix(Delta)
    nv, nu = _split_sizes(M, D, n, "lft_upper")
    f = max(M.shape[0], D.shape[0])
    M = np.broadcast_to(M, (f, *M.shape[1:]))
    D = np.broadcast_to(D, (f, *D.shape[1:]))
    M11, M12 = M[:, :nv, :nu], M[:, :nv, nu:]
    M21, M22 = M[:, nv:, :nu], M[:, nv:, nu:]
    eye = np.eye(nv, dtype=complex)
    X = np.linalg.solve(eye[None] - M11 @ D, M12)  # (f, n_v, n_w)
    return M22 + M21 @ (D @ X)


def lft_lower(M: np.ndarray, D: np.ndarray | complex, n: int | tuple[int, int] | None = None
              ) -> np.ndarray:
    """Lower LFT ``F_l(M, D) = M11 + M12 D (I - M22 D)^-1 M21`` per frequency.

    ``M``: ``(f, n_z + n_y, n_w + n_u)``; ``D``: ``(f, n_u, n_y)`` (or one matrix / scalar);
    ``n`` (optional) is ``n_y`` or ``(n_y, n_u)``. Returns ``(f, n_z, n_w)``.
    """
    M = as_freq_matrix(M)
    Dm = as_freq_matrix(D)
    ny, nu = _split_sizes(M, Dm, n, "lft_lower")
    f = max(M.shape[0], Dm.shape[0])
    M = np.broadcast_to(M, (f, *M.shape[1:]))
    Dm = np.broadcast_to(Dm, (f, *Dm.shape[1:]))
    p, q = M.shape[1:]
    M11, M12 = M[:, : p - ny, : q - nu], M[:, : p - ny, q - nu:]
    M21, M22 = M[:, p - ny:, : q - nu], M[:, p - ny:, q - nu:]
    eye = np.eye(ny, dtype=complex)
    X = np.linalg.solve(eye[None] - M22 @ Dm, M21)  # (f, n_y, n_w)
    return M11 + M12 @ (Dm @ X)


def _blocks(M11: np.ndarray, M12: np.ndarray, M21: np.ndarray, M22: np.ndarray) -> np.ndarray:
    top = np.concatenate([M11, M12], axis=2)
    bottom = np.concatenate([M21, M22], axis=2)
    return np.concatenate([top, bottom], axis=1)


def additive_me(G: np.ndarray) -> np.ndarray:
    """Me of the additive uncertainty on the io channel, ``F_u(Me, Delta) = G + Delta``.

    ``Me = [[0, I_in], [I_out, G]]``; ``G``: ``(f, n_out, n_in)`` receptance (m/N) or ``(f,)``
    for SISO. ``Delta`` is ``(n_out, n_in)`` in m/N. Returns ``(f, n_in + n_out, n_out + n_in)``.
    """
    G = as_freq_matrix(G)
    f, n_out, n_in = G.shape
    z = np.zeros((f, n_in, n_out), dtype=complex)
    i_in = np.broadcast_to(np.eye(n_in, dtype=complex), (f, n_in, n_in))
    i_out = np.broadcast_to(np.eye(n_out, dtype=complex), (f, n_out, n_out))
    return _blocks(z, i_in, i_out, G)


def multiplicative_me(G: np.ndarray, side: str = "output") -> np.ndarray:
    """Me of a multiplicative uncertainty on the io channel.

    ``side='output'``: ``F_u = (I + Delta) G``, ``Me = [[0, G], [I, G]]``, Delta ``(n_out, n_out)``.
    ``side='input'``: ``F_u = G (I + Delta)``, ``Me = [[0, I], [G, G]]``, Delta ``(n_in, n_in)``.
    Delta is dimensionless (relative error). For SISO both are the same.
    """
    G = as_freq_matrix(G)
    f, n_out, n_in = G.shape
    if side == "output":
        z = np.zeros((f, n_out, n_out), dtype=complex)
        i_out = np.broadcast_to(np.eye(n_out, dtype=complex), (f, n_out, n_out))
        return _blocks(z, G, i_out, G)
    if side == "input":
        z = np.zeros((f, n_in, n_in), dtype=complex)
        i_in = np.broadcast_to(np.eye(n_in, dtype=complex), (f, n_in, n_in))
        return _blocks(z, i_in, G, G)
    raise ValueError(f"side must be 'output' or 'input', got {side!r}")


def _factor(X: np.ndarray, f: int, n: int, name: str) -> np.ndarray:
    A = np.asarray(X, dtype=complex)
    if A.ndim == 1:
        A = A[:, None]
    if A.ndim == 2:
        A = np.broadcast_to(A[None], (f, *A.shape))
    if A.ndim != 3 or A.shape[0] != f or A.shape[1] != n:
        raise ValueError(f"{name} must be (n, r) or (f, n, r) with n={n}, f={f}; got {A.shape}")
    return A


def parametric_me(Z: np.ndarray, L: np.ndarray, R: np.ndarray, b_in: np.ndarray,
                  c_out: np.ndarray) -> np.ndarray:
    """Upper-LFT Me of a parameter change of the dynamic stiffness ``Z(w) = Z0 + L delta R^T``.

    ``Z``: ``(f, n, n)`` nominal Z0 (N/m); ``L``, ``R``: ``(n, r)`` or ``(f, n, r)`` (``R^T`` is a
    plain transpose, not conjugate); ``b_in``: ``(n, n_in)`` force input selector; ``c_out``:
    ``(n_out, n)`` displacement output selector. The uncertain model is
    ``c_out (Z0 + L delta R^T)^-1 b_in = F_u(Me, delta I_r)`` with (derivation: ``Z0 x = b f - L u``,
    ``u = delta v``, ``v = R^T x``)::

        Me11 = -R^T Z0^-1 L   Me12 = R^T Z0^-1 b_in
        Me21 = -c Z0^-1 L     Me22 = c Z0^-1 b_in

    Returns ``(f, r + n_out, r + n_in)``. Only solves with Z0, no explicit inverse.
    """
    Z = as_freq_matrix(Z)
    f, n, _ = Z.shape
    Lf = _factor(L, f, n, "L")
    Rf = _factor(R, f, n, "R")
    r = Lf.shape[2]
    if Rf.shape[2] != r:
        raise ValueError(f"L has {r} columns but R has {Rf.shape[2]}")
    b = np.asarray(b_in, dtype=complex)
    b = b[:, None] if b.ndim == 1 else b
    c = np.asarray(c_out, dtype=complex)
    c = c[None, :] if c.ndim == 1 else c
    rhs = np.concatenate([Lf, np.broadcast_to(b, (f, *b.shape))], axis=2)
    X = np.linalg.solve(Z, rhs)  # (f, n, r + n_in)
    XL, Xb = X[:, :, :r], X[:, :, r:]
    Rt = np.swapaxes(Rf, 1, 2)
    return _blocks(-(Rt @ XL), Rt @ Xb, -(c @ XL), c @ Xb)


def selector(dofs: Sequence[int] | np.ndarray | int, n: int) -> np.ndarray:
    """Column selector ``(n, k)``: unit columns at integer ``dofs``, or a given ``(n, k)`` array
    (e.g. a direction combination) passed through."""
    a = np.asarray(dofs)
    if a.ndim == 2:
        if a.shape[0] != n:
            raise ValueError(f"selector must have {n} rows, got {a.shape}")
        return a.astype(complex)
    idx = np.atleast_1d(a).astype(int)
    S = np.zeros((n, idx.size), dtype=complex)
    S[idx, np.arange(idx.size)] = 1.0
    return S


def engineering_system(Z: np.ndarray, damage_dofs: Sequence[int] | np.ndarray | int,
                       in_dofs: Sequence[int] | np.ndarray | int,
                       out_dofs: Sequence[int] | np.ndarray | int
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Engineering system partitions from the dynamic stiffness ``Z`` (f, n, n), N/m.

    Returns ``(E11, E12, E21, E22) = (H_dd, H_d,in, H_out,d, H_out,in)`` in m/N, each
    ``(f, rows, cols)``, with ``H = Z^-1`` obtained by solves for the damage and input columns only.
    dofs are integer indices or ``(n, k)`` selectors (outputs use the transpose).
    """
    Z = as_freq_matrix(Z)
    n = Z.shape[1]
    Sd, Si, So = selector(damage_dofs, n), selector(in_dofs, n), selector(out_dofs, n)
    nd = Sd.shape[1]
    X = np.linalg.solve(Z, np.concatenate([Sd, Si], axis=1)[None].repeat(Z.shape[0], axis=0))
    Xd, Xi = X[:, :, :nd], X[:, :, nd:]
    SdT, SoT = Sd.T, So.T
    return SdT @ Xd, SdT @ Xi, SoT @ Xd, SoT @ Xi


def engineering_me(Z: np.ndarray, L: np.ndarray, R: np.ndarray,
                   damage_dofs: Sequence[int] | np.ndarray | int,
                   in_dofs: Sequence[int] | np.ndarray | int,
                   out_dofs: Sequence[int] | np.ndarray | int) -> np.ndarray:
    """Uncertain engineering system as an upper LFT in the parameter ``delta``.

    ``F_u(Me_E, delta I_r) = [[E11, E12], [E21, E22]](delta)`` with ports (damage, io) for
    ``Z(delta) = Z0 + L delta R^T``. Shape ``(f, r + nd + n_out, r + nd + n_in)``.
    """
    Z = as_freq_matrix(Z)
    n = Z.shape[1]
    Sd, Si, So = selector(damage_dofs, n), selector(in_dofs, n), selector(out_dofs, n)
    return parametric_me(Z, L, R, np.concatenate([Sd, Si], axis=1),
                         np.concatenate([Sd, So], axis=1).T)


def io_me(E11: np.ndarray, E12: np.ndarray, E21: np.ndarray, E22: np.ndarray,
          kind: str = "additive") -> np.ndarray:
    """Uncertain engineering system with the uncertainty on the io output.

    ``kind='additive'``: ``E22 -> E22 + Delta`` (E21 unchanged); ``'multiplicative'`` (output
    side, as :mod:`rotorcheck.nominal` builds it: ``z = (I + Delta)(E21 f_d + E22 w)``):
    ``[E21, E22] -> (I + Delta) [E21, E22]``, i.e. the damage path to the output is scaled too.
    Returns ``Me_E`` with ``F_u(Me_E, Delta) = [[E11, E12], [E21_hat, E22_hat]]``, ports
    (damage, io).
    """
    E11, E12, E21, E22 = (as_freq_matrix(x) for x in (E11, E12, E21, E22))
    f = max(x.shape[0] for x in (E11, E12, E21, E22))
    E11, E12, E21, E22 = (np.broadcast_to(x, (f, *x.shape[1:])) for x in (E11, E12, E21, E22))
    nd = E11.shape[1]
    n_out, n_in = E22.shape[1:]
    E = _blocks(E11, E12, E21, E22)
    if kind == "additive":
        nv, nu = n_in, n_out
        M12 = np.concatenate([np.zeros((f, nv, nd), complex),
                              np.broadcast_to(np.eye(n_in, dtype=complex), (f, n_in, n_in))], 2)
    elif kind == "multiplicative":
        nv, nu = n_out, n_out
        M12 = np.concatenate([E21, E22], 2)
    else:
        raise ValueError(f"kind must be 'additive' or 'multiplicative', got {kind!r}")
    M11 = np.zeros((f, nv, nu), complex)
    M21 = np.concatenate([np.zeros((f, nd, nu), complex),
                          np.broadcast_to(np.eye(n_out, dtype=complex), (f, n_out, nu))], 1)
    return _blocks(M11, M12, M21, E)


# --- low-rank factors of parameter changes dZ = L delta R^T ----------------------------------------

def _unit(n: int, i: int) -> np.ndarray:
    e = np.zeros(n)
    e[i] = 1.0
    return e


def _pair(n: int, i: int, j: int | None) -> np.ndarray:
    e = _unit(n, i)
    if j is not None:
        e = e - _unit(n, j)
    return e


def mass_factor(omega: np.ndarray, dof: int, n: int, scale: float = 1.0
                ) -> tuple[np.ndarray, np.ndarray]:
    """Factor of a lumped-mass change at ``dof``: ``dZ/dm = -w^2 e e^T``.

    ``omega`` in rad/s, shape (f,). With ``delta`` in units of ``scale`` kg (``m = m_e + scale
    delta``), returns ``L`` ``(f, n, 1)`` (frequency dependent) and ``R`` ``(n, 1)``.
    """
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    e = _unit(n, dof)
    L = (-(w**2) * scale)[:, None, None] * e[None, :, None]
    return L.astype(complex), e[:, None].astype(complex)


def spring_factor(n: int, dof_i: int, dof_j: int | None = None, scale: float = 1.0
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Factor of a spring change (N/m per unit delta) between ``dof_i`` and ``dof_j`` (or ground
    if ``None``): ``L = scale (e_i - e_j)``, ``R = e_i - e_j``, both ``(n, 1)``."""
    e = _pair(n, dof_i, dof_j)
    return (scale * e)[:, None].astype(complex), e[:, None].astype(complex)


def damper_factor(omega: np.ndarray, n: int, dof_i: int, dof_j: int | None = None,
                  scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Factor of a damper change (N s/m per unit delta): ``L = j w scale (e_i - e_j)`` (f, n, 1)."""
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    e = _pair(n, dof_i, dof_j)
    L = (1j * w * scale)[:, None, None] * e[None, :, None]
    return L, e[:, None].astype(complex)


def low_rank_factor(dZ: np.ndarray, rtol: float = 1e-10) -> tuple[np.ndarray, np.ndarray]:
    """Factor a constant real symmetric change ``dZ = L R^T`` (e.g. ``K_e / E`` of an element for a
    modulus change) by its eigen-decomposition, keeping eigenvalues above ``rtol * max``.

    The rank ``r`` is the size of the repeated scalar block ``delta I_r`` it creates.
    """
    S = np.asarray(dZ, dtype=float)
    S = 0.5 * (S + S.T)
    lam, U = np.linalg.eigh(S)
    keep = np.abs(lam) > rtol * max(np.abs(lam).max(), np.finfo(float).tiny)
    U, lam = U[:, keep], lam[keep]
    return (U * lam).astype(complex), U.astype(complex)
