"""Assemble a :class:`~rotorcheck.fe.system.MechanicalSystem` from a validated rig config.

Rotor (``kind: rotor``): each config shaft element ``e`` (between stations e and e+1) is split into
``refine`` equal Timoshenko elements; ``station_node`` maps config stations to mesh nodes. Discs,
bearings and station springs act at station nodes. Assembly is vectorised: element matrices are
built as one (ne, 8, 8) stack and scattered with ``np.add.at`` (no Python loop over the global
matrix).

Speed dependence: bearing coefficients (``SpeedTable``) and, through K, the modal damping. The
matrices are computed once per distinct set of bearing coefficients and cached (last 64 sets), so
the speeds of a Campbell diagram over constant bearings share one modal-damping eigensolution; the
set is the system's ``matrix_key``.

Faults: ``modulus_factors={element: factor}`` scales Young's modulus of config element(s) (an open
crack: ``{4: 0.46}``), on top of the config's own ``modulus_factor``; lumped models accept
``stiffness_overrides={spring: N/m}`` (the three-mass damage ``{"k3": 350}``).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping

import numpy as np

from rotorcheck.config import ModalDamping, RayleighDamping, RigConfig
from rotorcheck.fe.damping import modal_damping_matrix, rayleigh_damping_matrix
from rotorcheck.fe.elements import RigidDisc, beam_matrices, shear_coefficient
from rotorcheck.fe.lumped import build_lumped
from rotorcheck.fe.system import BeamElementInfo, MechanicalSystem

Matrices = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
_CACHE_SIZE = 64


def build_system(
    config: RigConfig,
    modulus_factors: Mapping[int, float] | None = None,
    stiffness_overrides: Mapping[str, float] | None = None,
) -> MechanicalSystem:
    """The mechanical system of ``config`` (rotor FE or lumped), optionally with fault changes.

    ``modulus_factors`` (rotor): 1-based config element -> factor on E. ``stiffness_overrides``
    (lumped): spring name -> stiffness (N/m).
    """
    if config.kind == "lumped":
        if modulus_factors:
            raise ValueError("modulus_factors apply to rotor models only")
        return build_lumped(config, stiffness_overrides=stiffness_overrides)
    if stiffness_overrides:
        raise ValueError("stiffness_overrides apply to lumped models only")
    return build_rotor(config, modulus_factors)


# --------------------------------------------------------------------------------------------
# rotor


def rotor_mesh(
    config: RigConfig, modulus_factors: Mapping[int, float] | None = None
) -> tuple[np.ndarray, tuple[int, ...], tuple[BeamElementInfo, ...]]:
    """Mesh of a rotor config: (node positions (m), station -> node, element infos)."""
    factors = dict(modulus_factors or {})
    n_seg = len(config.stations) - 1
    for seg in factors:
        if not (1 <= seg <= n_seg):
            raise KeyError(f"modulus_factors: element {seg} out of range 1..{n_seg}")
    by_start = {e.start: e for e in config.shaft}
    positions: list[float] = [config.stations[0]]
    station_node = [0]
    infos: list[BeamElementInfo] = []
    for seg in range(1, n_seg + 1):
        e = by_start[seg]
        mat = config.materials[e.material]
        z0, z1 = config.stations[seg - 1], config.stations[seg]
        zs = np.linspace(z0, z1, e.refine + 1)
        E = mat.youngs_modulus * e.modulus_factor * factors.get(seg, 1.0)
        for k in range(e.refine):
            node_i = len(positions) - 1
            positions.append(float(zs[k + 1]))
            infos.append(
                BeamElementInfo(
                    index=len(infos),
                    segment=seg,
                    node_i=node_i,
                    node_j=node_i + 1,
                    length=float(zs[k + 1] - zs[k]),
                    youngs_modulus=E,
                    shear_modulus=mat.G,
                    density=mat.density,
                    outer_diameter=e.outer_diameter,
                    inner_diameter=e.inner_diameter,
                    poisson=mat.nu,
                )
            )
        station_node.append(len(positions) - 1)
    return np.asarray(positions), tuple(station_node), tuple(infos)


def assemble_beams(infos: tuple[BeamElementInfo, ...], n_dof: int) -> tuple[np.ndarray, ...]:
    """Global (M, G, K) of the shaft elements only (dense, n_dof x n_dof)."""
    f = lambda name: np.array([getattr(i, name) for i in infos], dtype=float)  # noqa: E731
    od, idm, nu = f("outer_diameter"), f("inner_diameter"), f("poisson")
    kappa = np.array([shear_coefficient(a, b, c) for a, b, c in zip(nu, od, idm)])
    Me, Ge, Ke = beam_matrices(
        f("length"), f("youngs_modulus"), f("shear_modulus"), f("density"), od, idm, kappa
    )
    dofs = np.stack([i.dofs for i in infos])  # (ne, 8)
    rows = np.broadcast_to(dofs[:, :, None], Me.shape)
    cols = np.broadcast_to(dofs[:, None, :], Me.shape)
    out = []
    for blocks in (Me, Ge, Ke):
        A = np.zeros((n_dof, n_dof))
        np.add.at(A, (rows, cols), blocks)
        out.append(A)
    return tuple(out)


def _node_block(A: np.ndarray, node: int, block: np.ndarray) -> None:
    A[4 * node : 4 * node + 4, 4 * node : 4 * node + 4] += block


def build_rotor(config: RigConfig, modulus_factors: Mapping[int, float] | None = None) -> MechanicalSystem:
    """Timoshenko FE model of a ``kind: rotor`` config (see module docstring)."""
    positions, station_node, infos = rotor_mesh(config, modulus_factors)
    n_dof = 4 * positions.size
    M, G, K0 = assemble_beams(infos, n_dof)
    C0 = np.zeros_like(M)
    features: list[tuple[str, str, int]] = []
    for d in config.discs:
        disc = RigidDisc(d.mass, d.transverse_inertia, d.polar_inertia)
        node = station_node[d.station - 1]
        _node_block(M, node, disc.mass_matrix())
        _node_block(G, node, disc.gyroscopic())
        features.append(("disc", d.name, d.station))
    for s in config.springs:
        node = station_node[s.station - 1]
        _node_block(K0, node, np.diag([s.kxx, s.kyy, s.k_rot, s.k_rot]))
        _node_block(C0, node, np.diag([s.cxx, s.cyy, 0.0, 0.0]))
        features.append(("spring", s.name, s.station))
    bearing_dofs = []
    for b in config.bearings:
        node = station_node[b.station - 1]
        bearing_dofs.append(np.array([4 * node, 4 * node + 1]))
        features.append(("bearing", b.name, b.station))
    bearings = tuple(config.bearings)
    damping = config.damping
    base = 4 * np.arange(positions.size)
    planes = (np.sort(np.r_[base, base + 3]), np.sort(np.r_[base + 1, base + 2]))
    cache: OrderedDict[tuple[float, ...], Matrices] = OrderedDict()
    names = ("kxx", "kxy", "kyx", "kyy", "cxx", "cxy", "cyx", "cyy")

    def key(speed_rpm: float) -> tuple[float, ...]:
        """The bearing coefficients at ``speed_rpm``: everything the matrices depend on."""
        out: list[float] = []
        for b in bearings:
            co = b.coefficients(speed_rpm)
            out.extend(float(co[k]) for k in names)
        return tuple(out)

    def compute(coefficients: tuple[float, ...]) -> Matrices:
        K = K0.copy()
        Cb = C0.copy()
        for j, d in enumerate(bearing_dofs):
            co = dict(zip(names, coefficients[8 * j : 8 * j + 8]))
            sub = np.ix_(d, d)
            K[sub] += [[co["kxx"], co["kxy"]], [co["kyx"], co["kyy"]]]
            Cb[sub] += [[co["cxx"], co["cxy"]], [co["cyx"], co["cyy"]]]
        if isinstance(damping, ModalDamping):
            C = Cb + modal_damping_matrix(M, K, damping.ratios, planes)
        elif isinstance(damping, RayleighDamping):
            C = Cb + rayleigh_damping_matrix(M, K, damping.alpha, damping.beta)
        else:
            C = Cb
        return M, C, G, K

    def matrices(speed_rpm: float) -> Matrices:
        k = key(speed_rpm)
        hit = cache.get(k)
        if hit is None:
            hit = compute(k)
            cache[k] = hit
            if len(cache) > _CACHE_SIZE:
                cache.popitem(last=False)
        else:
            cache.move_to_end(k)
        M, C, G, K = hit
        return M.copy(), C.copy(), G.copy(), K.copy()

    labels = tuple(
        f"n{node}.{d}" if node not in station_node else f"s{station_node.index(node) + 1}.{d}"
        for node in range(positions.size)
        for d in ("x", "y", "theta", "psi")
    )
    return MechanicalSystem(
        kind="rotor",
        n_dof=n_dof,
        labels=labels,
        _matrices=matrices,
        station_node=station_node,
        node_positions=positions,
        elements=infos,
        features=tuple(features),
        _key=key,
    )
