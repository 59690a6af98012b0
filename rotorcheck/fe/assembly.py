"""Assemble a :class:`~rotorcheck.fe.system.MechanicalSystem` from a validated rig config.

Rotor (``kind: rotor``): each config shaft element ``e`` (between stations e and e+1) is split into
``refine`` equal Timoshenko elements (:mod:`rotorcheck.fe.shaft`: tapered sections, shear options,
geometric stiffness of axial force and torque); further entries on the same station pair are
concentric layers whose matrices add (``system.layers``). ``station_node`` maps config stations to
mesh nodes. Discs, point masses, bearings and station springs act at station nodes; support nodes
(pedestals: stations numbered after the last shaft station, reached by a bearing's ``n_link``) carry
x and y only and follow the shaft's DOF. A bearing with ``n_link`` acts on the relative motion of its
two nodes (stiffness, damping and mass coefficients). Assembly is vectorised: element matrices are
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
import pydantic_core

from rotorcheck.config import Material, ModalDamping, RayleighDamping, ShaftElement
from rotorcheck.fe.damping import modal_damping_matrix, rayleigh_damping_matrix
from rotorcheck.fe.description import MECHANICAL_FIELDS, MechanicalDescription
from rotorcheck.fe.elements import RigidDisc, shear_coefficient
from rotorcheck.fe.lumped import build_lumped
from rotorcheck.fe.shaft import ShaftMatrices, shaft_matrices, shear_coefficient_by
from rotorcheck.fe.system import BeamElementInfo, MechanicalSystem, rotor_dof, rotor_plane_dofs

Matrices = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
_CACHE_SIZE = 64


def build_system(
    config: MechanicalDescription,
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


def _element_kappa(config: MechanicalDescription, e: ShaftElement, material: Material) -> float:
    """Shear coefficient of a config element: its own value or method, else the rig's (by the mean
    diameters of the element, as ROSS)."""
    if e.shear_coefficient is not None:
        return e.shear_coefficient
    if e.shear_method is None and config.shear_coefficient is not None:
        return config.shear_coefficient
    method = e.shear_method or config.shear_method
    od = 0.5 * (e.outer_diameter + e.outer_right)
    idm = 0.5 * (e.inner_diameter + e.inner_right)
    return float(shear_coefficient_by(method, material.nu, od, idm))


def rotor_mesh(
    config: MechanicalDescription, modulus_factors: Mapping[int, float] | None = None
) -> tuple[np.ndarray, tuple[int, ...], tuple[BeamElementInfo, ...], tuple[BeamElementInfo, ...]]:
    """Mesh of a rotor config: (node positions (m), station -> node, shaft element infos, layer infos).

    The first config element listed on a station pair is the shaft (``modulus_factors`` act on it:
    a crack is in the shaft); further elements on the same pair are concentric layers. A tapered
    element refined into ``refine`` pieces gets the linearly interpolated diameters at each cut.
    """
    factors = dict(modulus_factors or {})
    n_seg = len(config.stations) - 1
    for seg in factors:
        if not (1 <= seg <= n_seg):
            raise KeyError(f"modulus_factors: element {seg} out of range 1..{n_seg}")
    by_start: dict[int, list[ShaftElement]] = {}
    for e in config.shaft:
        by_start.setdefault(e.start, []).append(e)
    positions: list[float] = [config.stations[0]]
    station_node = [0]
    infos: list[BeamElementInfo] = []
    layers: list[BeamElementInfo] = []
    for seg in range(1, n_seg + 1):
        group = by_start[seg]
        refine = group[0].refine
        z0, z1 = config.stations[seg - 1], config.stations[seg]
        zs = np.linspace(z0, z1, refine + 1)
        first_node = len(positions) - 1
        positions.extend(float(z) for z in zs[1:])
        for layer, e in enumerate(group):
            mat = config.materials[e.material]
            E = mat.youngs_modulus * e.modulus_factor * (factors.get(seg, 1.0) if layer == 0 else 1.0)
            kappa = _element_kappa(config, e, mat)
            t = np.linspace(0.0, 1.0, refine + 1)
            od = e.outer_diameter + t * (e.outer_right - e.outer_diameter)
            idm = e.inner_diameter + t * (e.inner_right - e.inner_diameter)
            for k in range(refine):
                target = infos if layer == 0 else layers
                target.append(
                    BeamElementInfo(
                        index=len(target),
                        segment=seg,
                        node_i=first_node + k,
                        node_j=first_node + k + 1,
                        length=float(zs[k + 1] - zs[k]),
                        youngs_modulus=E,
                        shear_modulus=mat.G,
                        density=mat.density,
                        outer_diameter=float(od[k]),
                        inner_diameter=float(idm[k]),
                        poisson=mat.nu,
                        outer_diameter_right=float(od[k + 1]) if e.tapered else None,
                        inner_diameter_right=float(idm[k + 1]) if e.tapered else None,
                        kappa=kappa,
                        shear=config.shear if e.shear is None else e.shear,
                        rotary_inertia=config.rotary_inertia if e.rotary_inertia is None else e.rotary_inertia,
                        gyroscopic=config.gyroscopic if e.gyroscopic is None else e.gyroscopic,
                        axial_force=e.axial_force,
                        torque=e.torque,
                        layer=layer,
                        taper=config.tapered_element,
                    )
                )
        station_node.append(len(positions) - 1)
    return np.asarray(positions), tuple(station_node), tuple(infos), tuple(layers)


def element_matrices(infos: tuple[BeamElementInfo, ...]) -> ShaftMatrices:
    """The (ne, 8, 8) matrices of mesh elements (one implementation: :func:`rotorcheck.fe.shaft.shaft_matrices`)."""
    tapers = {i.taper for i in infos}  # one formulation per rig (RigConfig.tapered_element)
    if len(tapers) > 1:
        raise ValueError(f"elements of one call use one taper formulation, got {sorted(tapers)}")
    f = lambda name: np.array([getattr(i, name) for i in infos], dtype=float)  # noqa: E731
    kappa = np.array([
        i.kappa if i.kappa is not None else shear_coefficient(i.poisson, i.mean_outer_diameter, i.mean_inner_diameter)
        for i in infos
    ])
    return shaft_matrices(
        f("length"), f("youngs_modulus"), f("shear_modulus"), f("density"), f("outer_diameter"),
        f("inner_diameter"), f("outer_right"), f("inner_right"), kappa,
        shear=np.array([i.shear for i in infos]),
        rotary_inertia=np.array([i.rotary_inertia for i in infos]),
        gyroscopic=np.array([i.gyroscopic for i in infos]),
        axial_force=f("axial_force"),
        torque=f("torque"),
        taper=tapers.pop() if tapers else "exact",
    )


def assemble_beams(infos: tuple[BeamElementInfo, ...], n_dof: int) -> tuple[np.ndarray, ...]:
    """Global (M, G, K) of shaft elements only (dense, n_dof x n_dof); K includes the geometric
    stiffness of axial force and torque."""
    out = [np.zeros((n_dof, n_dof)) for _ in range(3)]
    if not infos:
        return tuple(out)
    mats = element_matrices(infos)
    dofs = np.stack([i.dofs for i in infos])  # (ne, 8)
    rows = np.broadcast_to(dofs[:, :, None], mats.mass.shape)
    cols = np.broadcast_to(dofs[:, None, :], mats.mass.shape)
    for A, blocks in zip(out, (mats.mass, mats.gyroscopic, mats.stiffness + mats.axial_force + mats.torque)):
        np.add.at(A, (rows, cols), blocks)
    return tuple(out)


def _node_block(A: np.ndarray, node: int, block: np.ndarray) -> None:
    A[4 * node : 4 * node + 4, 4 * node : 4 * node + 4] += block


def config_key(config: object, exclude: set[str] | None = None,
               fields: frozenset[str] | None = None) -> bytes | None:
    """The content of ``config`` (its ``fields``, default all, less ``exclude``) as JSON bytes, equal for
    equal content: floats to the last bit, infinities and NaN spelled out (not null, as ``model_dump_json``
    would, like None); None when something in it does not serialize or it is no pydantic model (then
    nothing is cached by it)."""
    include = None if fields is None else set(fields - (exclude or set()))
    try:
        return pydantic_core.to_json(config, include=include, exclude=None if include else exclude,
                                     inf_nan_mode="constants")
    except (pydantic_core.PydanticSerializationError, TypeError, ValueError):
        return None


#: the bearing-free part of rotors assembled lately (:func:`_rotor_structure`), by its key
_STRUCTURES: OrderedDict[tuple[object, ...], tuple[object, ...]] = OrderedDict()
_STRUCTURES_SIZE = 32


def _rotor_structure(config: MechanicalDescription, modulus_factors: Mapping[int, float] | None, n_sup: int) -> tuple[
        np.ndarray, tuple[int, ...], tuple[BeamElementInfo, ...], tuple[BeamElementInfo, ...], np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, tuple[tuple[str, str, int], ...], np.ndarray | None]:
    """Everything of a rotor but its bearings: the mesh, M, G, K0 (shaft, discs, point masses, springs), C0
    (springs), the features so far and the Rayleigh damping of scope "rotor". Kept for equal inputs (the
    config's content without its bearings, the modulus factors, the support nodes): a rig re-solved at other
    bearing coefficients or speeds (benign change, issue 28) assembles its shaft once; the arrays are shared
    read-only and every system copies what it changes."""
    content = config_key(config, exclude={"bearings"}, fields=MECHANICAL_FIELDS)  # what the assembly reads
    key = (content, tuple(sorted((modulus_factors or {}).items())), n_sup)
    hit = _STRUCTURES.get(key) if content is not None else None
    if hit is not None:
        _STRUCTURES.move_to_end(key)
        return hit  # type: ignore[return-value]
    positions, station_node, infos, layers = rotor_mesh(config, modulus_factors)
    n_shaft = 4 * positions.size
    n_dof = n_shaft + 2 * n_sup

    def xy(station: int) -> np.ndarray:
        return _xy(station_node, positions.size, n_sup, station)

    M, G, K0 = assemble_beams(infos + layers, n_dof)
    damping = config.damping
    # Rayleigh damping of scope "shaft_elements": sum of alpha M_e + beta K_e over the shaft elements
    C0 = (rayleigh_damping_matrix(M, K0, damping.alpha, damping.beta, symmetric=False)
          if isinstance(damping, RayleighDamping) and damping.scope == "shaft_elements" else np.zeros_like(M))
    features: list[tuple[str, str, int]] = []
    for d in config.discs:
        m, ip, it = d.inertias(config.materials)
        disc = RigidDisc(m, it, ip)
        node = station_node[d.station - 1]
        _node_block(M, node, disc.mass_matrix())
        if config.gyroscopic:
            _node_block(G, node, disc.gyroscopic())
        features.append(("disc", d.name, d.station))
    for pm in config.point_masses:
        ix = xy(pm.station)
        M[ix, ix] += pm.masses
        features.append(("point_mass", pm.name, pm.station))
    # Rayleigh damping of scope "rotor": from M and K without springs and bearings, the same at every speed
    rayleigh_rotor = (rayleigh_damping_matrix(M, K0, damping.alpha, damping.beta)
                      if isinstance(damping, RayleighDamping) and damping.scope == "rotor" else None)
    for s in config.springs:
        node = station_node[s.station - 1]
        _node_block(K0, node, np.diag([s.kxx, s.kyy, s.k_rot, s.k_rot]))
        _node_block(C0, node, np.diag([s.cxx, s.cyy, 0.0, 0.0]))
        features.append(("spring", s.name, s.station))
    for A in (positions, M, G, K0, C0, rayleigh_rotor):
        if A is not None:
            A.flags.writeable = False
    out = (positions, station_node, infos, layers, M, G, K0, C0, tuple(features), rayleigh_rotor)
    if content is not None:
        _STRUCTURES[key] = out
        if len(_STRUCTURES) > _STRUCTURES_SIZE:
            _STRUCTURES.popitem(last=False)
    return out


def _xy(station_node: tuple[int, ...], n_nodes: int, n_sup: int, station: int) -> np.ndarray:
    """The x and y DOF of a shaft station or a support node."""
    return np.array([rotor_dof(station_node, n_nodes, n_sup, station, d) for d in ("x", "y")])


def build_rotor(config: MechanicalDescription, modulus_factors: Mapping[int, float] | None = None) -> MechanicalSystem:
    """Timoshenko FE model of a ``kind: rotor`` config (see module docstring)."""
    n_sup = config.n_support_nodes
    positions, station_node, infos, layers, M, G, K0, C0, features_so_far, rayleigh_rotor = _rotor_structure(
        config, modulus_factors, n_sup)
    positions = positions.copy()  # the system's own (writable, as before)
    n_station = len(station_node)
    n_dof = M.shape[0]
    features = list(features_so_far)
    damping = config.damping

    def xy(station: int) -> np.ndarray:
        return _xy(station_node, positions.size, n_sup, station)

    bearing_dofs: list[tuple[np.ndarray, np.ndarray | None]] = []
    for b in config.bearings:
        bearing_dofs.append((xy(b.station), None if b.n_link is None else xy(b.n_link)))
        if b.station <= n_station:
            features.append(("bearing", b.name, b.station))
    bearings = tuple(config.bearings)
    planes = rotor_plane_dofs(positions.size, n_sup)
    cache: OrderedDict[tuple[float, ...], Matrices] = OrderedDict()
    names = ("kxx", "kxy", "kyx", "kyy", "cxx", "cxy", "cyx", "cyy", "mxx", "mxy", "myx", "myy")

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
        Mb = M.copy()
        for j, (a, link) in enumerate(bearing_dofs):
            co = dict(zip(names, coefficients[12 * j : 12 * j + 12]))
            for A, t in ((K, "k"), (Cb, "c"), (Mb, "m")):
                blk = np.array([[co[t + "xx"], co[t + "xy"]], [co[t + "yx"], co[t + "yy"]]])
                A[np.ix_(a, a)] += blk
                if link is not None:
                    A[np.ix_(link, link)] += blk
                    A[np.ix_(a, link)] -= blk
                    A[np.ix_(link, a)] -= blk
        if isinstance(damping, ModalDamping):
            C = Cb + modal_damping_matrix(Mb, K, damping.ratios, planes)
        elif isinstance(damping, RayleighDamping) and damping.scope != "shaft_elements":  # that one is in C0
            C = Cb + (rayleigh_rotor if rayleigh_rotor is not None
                      else rayleigh_damping_matrix(Mb, K, damping.alpha, damping.beta))
        else:
            C = Cb
        return Mb, C, G, K

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
        M_, C, G_, K = hit
        return M_.copy(), C.copy(), G_.copy(), K.copy()

    labels = tuple(
        f"n{node}.{d}" if node not in station_node else f"s{station_node.index(node) + 1}.{d}"
        for node in range(positions.size)
        for d in ("x", "y", "theta", "psi")
    ) + tuple(f"s{n_station + k + 1}.{d}" for k in range(n_sup) for d in ("x", "y"))
    return MechanicalSystem(
        kind="rotor",
        n_dof=n_dof,
        labels=labels,
        _matrices=matrices,
        station_node=station_node,
        node_positions=positions,
        elements=infos,
        layers=layers,
        n_support=n_sup,
        features=tuple(features),
        _key=key,
    )
