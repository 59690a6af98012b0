"""Step 1: the nominal engineering model of a rig as an augmented plant per frequency.

One 3x3 complex matrix P(w) per frequency maps the inputs ``[u_delta, f_d, w]`` (uncertainty
output, extra force at the damage port, actuator force) to the outputs ``[y_delta, d, z]``
(uncertainty input, damage-port displacement, sensor displacement):

- validation uses ``Me = P[[0, 2]][:, [0, 2]]`` (damage channel open) with ``u_delta = gamma Delta
  y_delta`` (upper LFT);
- identification uses ``E = P[1:, 1:]`` (``E11 = H_dd``, ``E12 = H_d,in``, ``E21 = H_out,d``,
  ``E22 = H_out,in``) with the damage dynamics as a lower LFT ``f_d = D d``; a stiffness loss dk
  gives D = +dk (method.md).

Structures (``uncertainty.structure`` in the rig file):

- ``additive``: z = (G + Delta) w on the io channel;
- ``multiplicative``: z = (1 + Delta) (G w + E21 f_d) (output multiplicative);
- ``parametric``: a named parameter p enters the dynamic stiffness as Z(p + delta) = Z(p) + L delta R^T
  (rank one: a lumped mass or spring, a disc mass in one direction, a bearing coefficient).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rotorcheck.config import Port, RigConfig
from rotorcheck.errors import InputError
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import system_receptance
from rotorcheck.fe.system import MechanicalSystem

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class NominalModel:
    """The augmented plant of a rig at one speed on a frequency grid (SI, Hz)."""

    rig_id: str
    speed_rpm: float
    frequency_hz: np.ndarray  # (f,)
    P: np.ndarray  # (f, 3, 3) complex, [y_delta, d, z] <- [u_delta, f_d, w]
    structure: str  # "additive" | "multiplicative" | "parametric"
    parameter: str | None  # parametric: dotted name; gamma is then in the parameter's unit

    @property
    def me(self) -> np.ndarray:
        """Validation matrix Me (f, 2, 2): [[Me11, Me12], [Me21, Me22]] on [u_delta, w]."""
        return self.P[:, [0, 2]][:, :, [0, 2]]

    @property
    def E(self) -> np.ndarray:
        """Engineering system (f, 2, 2): [[E11, E12], [E21, E22]] on [f_d, w] -> [d, z]."""
        return self.P[:, 1:, 1:]

    @property
    def frf(self) -> np.ndarray:
        """Nominal receptance sensor/actuator G = Me22 = E22 (f,), m/N."""
        return self.P[:, 2, 2]


def _parameter_factors(
    config: RigConfig, system: MechanicalSystem, name: str, freq_hz: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``a`` (f,) and the unit vector ``r`` (n,) of a rank-one parameter ``name`` (dotted path):
    ``dZ = L delta R^T`` with ``L = a(w) r`` and ``R = r``."""
    parts = name.split(".")
    n = system.n_dof
    w2 = (TWO_PI * freq_hz) ** 2
    unit = np.zeros(n)
    if len(parts) == 3 and parts[0] == "masses" and parts[2] == "mass":
        if parts[1] not in system.mass_index:
            raise InputError(None, "uncertainty.parameter", f"unknown mass {parts[1]!r}")
        unit[system.mass_index[parts[1]]] = 1.0
        return -w2, unit
    if len(parts) == 3 and parts[0] == "lumped_springs" and parts[2] == "stiffness":
        springs = {s.name: s for s in config.lumped_springs}
        if parts[1] not in springs:
            raise InputError(None, "uncertainty.parameter", f"unknown spring {parts[1]!r}")
        a, b = springs[parts[1]].between
        if a != "ground":
            unit[system.mass_index[a]] += 1.0
        if b != "ground":
            unit[system.mass_index[b]] -= 1.0
        return np.ones_like(freq_hz), unit
    if len(parts) == 3 and parts[0] == "bearings" and parts[2] in ("kxx", "kyy"):
        bearings = {b.name: b for b in config.bearings}
        if parts[1] not in bearings:
            raise InputError(None, "uncertainty.parameter", f"unknown bearing {parts[1]!r}")
        unit[system.dof(bearings[parts[1]].station, parts[2][1])] = 1.0
        return np.ones_like(freq_hz), unit
    raise InputError(
        None,
        "uncertainty.parameter",
        f"{name!r} is not a supported rank-one parameter (masses.<m>.mass, "
        "lumped_springs.<k>.stiffness, bearings.<b>.kxx|kyy)",
    )


def nominal_model(
    config: RigConfig,
    freq_hz: np.ndarray,
    speed_rpm: float = 0.0,
    system: MechanicalSystem | None = None,
) -> NominalModel:
    """Build the augmented plant P(w) of ``config`` at ``speed_rpm`` on ``freq_hz`` (Hz).

    One receptance of the engine (:mod:`rotorcheck.fe.frf`) at the outputs [damage port, sensor
    (, R)] for the inputs [damage port, actuator (, r)] gives every entry.
    """
    sys_ = system if system is not None else build_system(config)
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    n = sys_.n_dof
    ports = config.io_ports("the nominal frequency response")
    i_in = sys_.port_dof(ports.actuator)
    i_out = sys_.port_dof(ports.sensor)
    # no damage port (validation and detection need none): the damage channel is computed at the sensor
    # and then set to NaN, so that no identification is read from it
    i_d = sys_.port_dof(config.damage.port) if config.damage is not None else i_out
    structure = config.uncertainty.structure

    outputs = np.zeros((2, n))
    outputs[0, i_d] = outputs[1, i_out] = 1.0
    inputs = np.zeros((n, 2))
    inputs[i_d, 0] = inputs[i_in, 1] = 1.0
    a = None
    if structure == "parametric":
        assert config.uncertainty.parameter is not None
        a, unit = _parameter_factors(config, sys_, config.uncertainty.parameter, f)
        outputs = np.vstack([outputs, unit])
        inputs = np.hstack([inputs, unit[:, None]])
    band = float(np.max(np.abs(f))) if f.size else None
    H = system_receptance(sys_, speed_rpm, outputs, inputs, band_hz=band).at_hz(f)  # (f, 2|3, 2|3)
    E11, E12 = H[:, 0, 0], H[:, 0, 1]
    E21, E22 = H[:, 1, 0], H[:, 1, 1]

    P = np.zeros((len(f), 3, 3), dtype=complex)
    P[:, 1, 1], P[:, 1, 2], P[:, 2, 1], P[:, 2, 2] = E11, E12, E21, E22
    if structure == "additive":
        P[:, 0, 2] = 1.0
        P[:, 2, 0] = 1.0
    elif structure == "multiplicative":
        P[:, 0, 1], P[:, 0, 2] = E21, E22
        P[:, 2, 0] = 1.0
    else:
        assert a is not None
        # -H L = -a H r: the response to the parameter's own force pattern
        P[:, 0, 0] = -a * H[:, 2, 2]
        P[:, 0, 1] = H[:, 2, 0]
        P[:, 0, 2] = H[:, 2, 1]
        P[:, 1, 0] = -a * H[:, 0, 2]
        P[:, 2, 0] = -a * H[:, 1, 2]
    if config.damage is None:
        P[:, 1, :] = np.nan
        P[:, :, 1] = np.nan
    return NominalModel(
        rig_id=config.rig_id,
        speed_rpm=float(speed_rpm),
        frequency_hz=f,
        P=P,
        structure=structure,
        parameter=config.uncertainty.parameter,
    )


@dataclass(frozen=True)
class ChannelPair:
    """One measured FRF channel: the displacement at ``output`` per unit force at ``input`` (model ports:
    a rotor station and direction, or a lumped mass); ``name`` as ``"<output channel>/<input channel>"``."""

    output: Port
    input: Port
    name: str

    def key(self) -> tuple[str, str]:
        """``(output, input)`` as ``"s6.x"``-style labels (what a baseline stores and a new sweep must match)."""
        return port_label(self.output), port_label(self.input)


def port_label(port: Port) -> str:
    """``"s<station>.<direction>"`` for a rotor port, the mass name for a lumped one."""
    return str(port.mass) if port.mass is not None else f"s{port.station}.{port.direction}"


def parse_port(text: str, option: str = "--port") -> Port:
    """A rotor port from text: ``8x``, ``s8.x`` (:func:`port_label`'s form) or ``8:y`` (station, direction);
    an InputError naming ``option`` otherwise."""
    m = re.fullmatch(r"\s*s?(\d+)\s*[.:]?\s*([xyXY])\s*", text)
    if m is None:
        raise InputError(None, option, f"{text!r} is no station and direction (e.g. 8x, s6.y)")
    return Port(station=int(m.group(1)), direction=m.group(2).lower())  # type: ignore[arg-type]


def channel_port(config: RigConfig, node: int, direction: str) -> Port:
    """The model port of a sweep channel (``node``: rotor station, or 1-based mass index of a lumped rig)."""
    if config.kind == "rotor":
        return Port(station=node, direction=direction)  # type: ignore[arg-type]
    names = [m.name for m in config.masses]
    if not 1 <= node <= len(names):
        raise InputError(None, "/channels", f"node {node} is no mass of rig {config.rig_id!r} (1..{len(names)})")
    return Port(mass=names[node - 1], direction=direction)  # type: ignore[arg-type]


def primary_pair(config: RigConfig) -> ChannelPair:
    """The rig's own actuator -> sensor channel (the ports section)."""
    return ChannelPair(config.io_ports("validation and detection").sensor,
                       config.io_ports("validation and detection").actuator, "sensor/actuator")


def model_pairs(config: RigConfig, pairs: Sequence[ChannelPair] | None) -> list[ChannelPair] | None:
    """``pairs`` as the model functions (:func:`rotorcheck.signatures.io_frf` and those built on it) take
    them: None for the rig's own actuator -> sensor pair alone (the primary path), else the list, one
    pair included (a single pair other than the primary is that pair, never the primary)."""
    if pairs is None:
        return None
    prs = list(pairs)
    if len(prs) == 1 and config.ports is not None and prs[0].key() == primary_pair(config).key():
        return None
    return prs


def pair_receptance(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, pairs: Sequence[ChannelPair],
                    system: MechanicalSystem | None = None) -> np.ndarray:
    """The model's receptance of each channel pair (f, P), m/N, from one engine receptance."""
    sys_ = system if system is not None else build_system(config)
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    outs = sorted({sys_.port_dof(p.output) for p in pairs})
    ins = sorted({sys_.port_dof(p.input) for p in pairs})
    band = float(np.max(np.abs(f))) if f.size else None
    H = system_receptance(sys_, speed_rpm, outs, ins, band_hz=band).at_hz(f)  # (f, n_out, n_in)
    return np.stack([H[:, outs.index(sys_.port_dof(p.output)), ins.index(sys_.port_dof(p.input))] for p in pairs],
                    axis=1)


def damage_direction(config: RigConfig, freq_hz: np.ndarray, speed_rpm: float, pairs: Sequence[ChannelPair],
                     system: MechanicalSystem | None = None) -> np.ndarray:
    """First-order change of each channel pair per unit damage-port stiffness change (f, P):
    ``E21_o E12_i`` (the damage port's receptance to the output times the input's to the damage port)."""
    if config.damage is None:
        raise InputError(None, "damage", "the rig has no damage port")
    d = config.damage.port
    cross = [ChannelPair(p.output, d, "") for p in pairs] + [ChannelPair(d, p.input, "") for p in pairs]
    H = pair_receptance(config, freq_hz, speed_rpm, cross, system)
    n = len(pairs)
    return H[:, :n] * H[:, n:]
