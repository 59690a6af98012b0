"""Play a stepped-sine measurement on a rig config (usually a "truth" rig) and return a Sweep.

The rig's ``measurement`` section sets force, periods, settling, noise, unbalance and
misalignment. A fault named in the rig's ``faults`` section changes the plant:

- ``crack`` with ``model: open`` and ``spring_change``: a time-invariant changed model;
- ``crack`` with a breathing model: the linear time-periodic cracked rotor by harmonic balance
  (tones at f + k * speed), see :mod:`rotorcheck.faults` and :mod:`rotorcheck.sim.plants`.

A time-invariant plant is the FE engine's receptance (:mod:`rotorcheck.fe.frf`) from the actuator to
the sensor.

Several inputs (:func:`simulate_rig_patterns`): the caller names the actuator and sensor ports
(config :class:`~rotorcheck.config.Port` s, e.g. the AMB's x and y axes at station 8 and two
sensors in x and y); the actuators are driven one at a time (pattern ``e`` drives actuator ``e``),
giving a version-2 run with ``n_exc = n_in`` (:func:`rotorcheck.sim.simulator.simulate_fast_patterns`).

Synchronous disturbances (absolute time t, shaft angle Omega t): unbalance ``m e Omega^2`` rotating
forward at 1X at its station, phase from +x towards +y; misalignment a forward-rotating 2X force of
``force_2x (speed / 1000 rpm)^2`` at its station. Their steady-state responses are added as fixed
tones, which the lock-in sees as leaks near kX.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rotorcheck import __version__
from rotorcheck.config import Crack, Port, RigConfig
from rotorcheck.errors import InputError
from rotorcheck.faults.harmonic_balance import misalignment_force, unbalance_force
from rotorcheck.faults.kinds import fault_model
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.frf import system_receptance
from rotorcheck.fe.system import RPM_TO_RAD_S, MechanicalSystem
from rotorcheck.sim.plants import simulator_disturbances, simulator_plant
from rotorcheck.sim.simulator import (
    Plant,
    StepSettings,
    Tone,
    receptance_plant,
    receptance_plants,
    response_tones,
    simulate_fast,
    simulate_fast_patterns,
)
from rotorcheck.sweep.format import Channel, Run, Sweep


@dataclass(frozen=True)
class RigPlant:
    """What the simulator needs from a rig at one speed: the plant and the disturbance tones (m)."""

    plant: Plant
    disturbances: list[Tone]
    system: MechanicalSystem
    in_dof: int
    out_dof: int


def rig_channels(config: RigConfig) -> list[Channel]:
    """The sweep's channel table for the rig's actuator and sensor ports."""
    return port_channels(config, [config.io_ports("a simulated sweep").actuator],
                         [config.io_ports("a simulated sweep").sensor])


def port_channels(config: RigConfig, actuators: Sequence[Port], sensors: Sequence[Port]) -> list[Channel]:
    """Channel table for the given actuator (force inputs) and sensor (displacement outputs) ports,
    inputs first, in the order given: ``force_<where>_<dir>``, ``disp_<where>_<dir>``."""
    def node(port: object) -> int:
        if config.kind == "lumped":
            names = [m.name for m in config.masses]
            return names.index(getattr(port, "mass", "")) + 1
        return int(getattr(port, "station", 0))

    chans = []
    for a in actuators:
        where_a = a.mass or f"s{node(a)}"
        chans.append(Channel(f"force_{where_a}_{a.direction}", "input", node(a), a.direction, "force", "N"))
    for s in sensors:
        where_s = s.mass or f"s{node(s)}"
        chans.append(Channel(f"disp_{where_s}_{s.direction}", "output", node(s), s.direction, "displacement", "m"))
    return chans


def synchronous_forces(config: RigConfig, system: MechanicalSystem, speed_rpm: float) -> list[Tone]:
    """Unbalance (1X) and misalignment (2X) force tones, vectors of length n_dof (N)."""
    if config.kind != "rotor" or speed_rpm == 0.0:
        return []
    f1 = speed_rpm / 60.0
    tones = [Tone(f1, unbalance_force(system, u.station, u.amount, u.phase, speed_rpm))
             for u in config.measurement.unbalance]
    mis = config.measurement.misalignment
    if mis is not None and mis.force_2x > 0:
        tones.append(Tone(2.0 * f1, misalignment_force(system, mis, speed_rpm)))
    return tones


def _rig_system(config: RigConfig, fault: str | None) -> tuple[MechanicalSystem, Crack | None]:
    """The rig's system with a time-invariant fault built in, and the breathing crack (or None)."""
    spec = None
    if fault is not None:
        if fault not in config.faults:
            known = ", ".join(config.faults) or "none"
            msg = f"rig {config.rig_id!r} has no fault {fault!r} (known: {known})"
            raise InputError(None, "--fault", msg)
        spec = config.faults[fault]
    if spec is None:
        return build_system(config), None
    model = fault_model(spec)
    change = model.built_in(spec)
    system = build_system(config, modulus_factors=change.modulus_factors or None,
                          stiffness_overrides=change.stiffness_overrides or None)
    breathing = model.time_varying(spec)
    return system, breathing


def rig_plant(
    config: RigConfig,
    speed_rpm: float,
    fault: str | None = None,
    n_harmonics: int = 8,
    band_hz: float | None = None,
) -> RigPlant:
    """The rig (optionally with a named fault) as a simulator plant at ``speed_rpm``; ``band_hz``:
    the highest excitation frequency that will be asked (lets a large mesh reduce once)."""
    system, breathing = _rig_system(config, fault)
    ports = config.io_ports("the simulator")
    in_dof = system.port_dof(ports.actuator)
    out_dof = system.port_dof(ports.sensor)
    if breathing is not None:
        plant = simulator_plant(system, breathing, speed_rpm, in_dof, [out_dof], n_harmonics)
    else:
        plant = receptance_plant(system_receptance(system, speed_rpm, [out_dof], [in_dof], band_hz=band_hz),
                                 name="matrix")
    disturbances = _disturbances(config, system, breathing, speed_rpm, [out_dof], n_harmonics)
    return RigPlant(plant, disturbances, system, in_dof, out_dof)


def _disturbances(config: RigConfig, system: MechanicalSystem, breathing: Crack | None, speed_rpm: float,
                  out_dofs: list[int], n_harmonics: int) -> list[Tone]:
    """Synchronous output tones (m) at ``out_dofs``: unbalance, misalignment and a breathing crack's
    harmonics (rotor at speed), else the LTI responses to the synchronous forces."""
    if config.kind == "rotor" and speed_rpm != 0.0:
        return simulator_disturbances(system, breathing, speed_rpm, out_dofs, config.measurement.unbalance,
                                      config.measurement.misalignment, n_harmonics)
    forces = synchronous_forces(config, system, speed_rpm)
    disturbances: list[Tone] = []
    if forces:
        M, C, G, K = system.matrices(speed_rpm)
        c_out = np.zeros((len(out_dofs), system.n_dof))
        for r, d in enumerate(out_dofs):
            c_out[r, d] = 1.0
        disturbances = response_tones(M, C + speed_rpm * RPM_TO_RAD_S * G, K, c_out, forces)
    return disturbances


@dataclass(frozen=True)
class RigPlants:
    """A rig with several actuators: one plant per actuator (outputs at every sensor), the
    disturbance tones at the sensors (m), the system and the actuator/sensor DOFs."""

    plants: list[Plant]
    disturbances: list[Tone]
    system: MechanicalSystem
    in_dofs: list[int]
    out_dofs: list[int]


def rig_plants(
    config: RigConfig,
    speed_rpm: float,
    actuators: Sequence[Port],
    sensors: Sequence[Port],
    fault: str | None = None,
    n_harmonics: int = 8,
    band_hz: float | None = None,
) -> RigPlants:
    """:func:`rig_plant` for several actuator and sensor ports (one plant per actuator)."""
    system, breathing = _rig_system(config, fault)
    in_dofs = [system.port_dof(a) for a in actuators]
    out_dofs = [system.port_dof(s) for s in sensors]
    if breathing is not None:
        plants = [simulator_plant(system, breathing, speed_rpm, d, out_dofs, n_harmonics) for d in in_dofs]
    else:
        rec = system_receptance(system, speed_rpm, out_dofs, in_dofs, band_hz=band_hz)
        plants = receptance_plants(rec, name="matrix")
    disturbances = _disturbances(config, system, breathing, speed_rpm, out_dofs, n_harmonics)
    return RigPlants(plants, disturbances, system, in_dofs, out_dofs)


def at_shaft_angle(rp: RigPlant, speed_rpm: float, shaft_angle_rad: float) -> RigPlant:
    """The same rig with the shaft at ``shaft_angle_rad`` (rad) at the sweep's t = 0.

    Everything that turns with the shaft (unbalance, misalignment, a crack's orientation) is shifted
    in time by ``theta0 / Omega`` while the excitation is not; a tone at ``f + k * speed`` (plant
    sideband) or ``k * speed`` (synchronous disturbance) then gains the factor ``exp(j k theta0)``
    (time-shift of a linear time-periodic system). ``theta0 = 0`` is a key-phasor-triggered sweep.
    """
    if shaft_angle_rad == 0.0 or speed_rpm == 0.0:
        return rp
    plant = _turned_plant(rp.plant, speed_rpm, shaft_angle_rad)
    dist = _turned_tones(rp.disturbances, speed_rpm, shaft_angle_rad)
    return RigPlant(plant, dist, rp.system, rp.in_dof, rp.out_dof)


def _order(offset_hz: np.ndarray, speed_rpm: float) -> np.ndarray:
    return np.rint(np.asarray(offset_hz, dtype=float) / (speed_rpm / 60.0))


def _turned_plant(base: Plant, speed_rpm: float, shaft_angle_rad: float) -> Plant:
    """``base`` with its sideband tones (order k = offset / speed) times ``exp(j k theta0)``."""
    def tones(f_hz: float) -> tuple[np.ndarray, np.ndarray]:
        tf, ta = base.tones(f_hz)
        tf = np.asarray(tf, dtype=float).reshape(-1)
        ta = np.asarray(ta, dtype=complex).reshape(tf.size, base.n_out)
        return tf, ta * np.exp(1j * _order(tf - f_hz, speed_rpm) * shaft_angle_rad)[:, None]

    return Plant(tones, base.n_out, base.name)


def _turned_tones(tones: list[Tone], speed_rpm: float, shaft_angle_rad: float) -> list[Tone]:
    """Synchronous tones (order k = freq / speed) times ``exp(j k theta0)``."""
    return [Tone(d.freq_hz, np.asarray(d.amplitude) * np.exp(1j * float(_order(np.asarray(d.freq_hz), speed_rpm)) *
                                                            shaft_angle_rad))
            for d in tones]


def step_settings(config: RigConfig, keep_periods: bool = True) -> StepSettings:
    """Stepped-sine settings from the rig's ``measurement`` section (per-period phasors kept unless
    ``keep_periods`` is False: they let the analysis remove shaft-speed harmonics)."""
    m = config.measurement
    return StepSettings(
        n_periods=m.n_periods,
        settle_periods=m.settle_periods,
        samples_per_period=m.samples_per_period,
        force_amplitude=m.force_amplitude,
        output_noise_std=m.output_noise_std,
        input_noise_std=m.input_noise_std,
        keep_periods=keep_periods,
        sideband_orders=tuple(m.sideband_orders),
    )


def shaft_angle_from(spec: str | float, seed: int) -> float:
    """Start angle (rad) from ``"random"`` (uniform over a turn, drawn from ``seed``: reproducible)
    or a number in degrees."""
    if isinstance(spec, str) and spec.strip().lower() == "random":
        return float(np.random.default_rng([int(seed), 0x5A4F]).uniform(0.0, 2.0 * np.pi))
    try:
        deg = float(spec)
    except ValueError:
        raise InputError(None, "--shaft-angle", f"expected degrees or 'random', got {spec!r}") from None
    if not np.isfinite(deg):
        raise InputError(None, "--shaft-angle", f"must be finite, got {spec!r}")
    return float(np.radians(deg))


def simulate_rig(
    config: RigConfig,
    freq_hz: np.ndarray,
    speed_rpm: float = 0.0,
    fault: str | None = None,
    seed: int = 0,
    run_id: str | None = None,
    created_utc: str = "2026-01-01T00:00:00Z",
    n_harmonics: int = 8,
    settings: StepSettings | None = None,
    shaft_angle_rad: float = 0.0,
) -> Sweep:
    """Simulated stepped-sine sweep of ``config`` (seeded, deterministic) as a one-run Sweep.

    ``shaft_angle_rad``: shaft angle at the sweep's start (0: key-phasor triggered; any other value
    a free-running start, see :func:`at_shaft_angle`). Per-period phasors are stored when
    ``settings.keep_periods``.
    """
    f = np.asarray(freq_hz, dtype=float)
    band = float(np.max(f)) if f.size else None
    rp = at_shaft_angle(rig_plant(config, speed_rpm, fault, n_harmonics, band), speed_rpm, shaft_angle_rad)
    st = settings if settings is not None else step_settings(config)
    res = simulate_fast(rp.plant, f, st, rp.disturbances, rng=seed, speed_rpm=speed_rpm,
                        shaft_angle_rad=shaft_angle_rad)
    what, n_per = _what(fault), _periods(st)
    notes = (f"{what}; seed {seed}; {n_per} periods; noise std {st.output_noise_std} m/sample; "
             f"shaft angle at start {np.degrees(shaft_angle_rad):.6g} deg")
    channels = rig_channels(config)
    rid = run_id or f"{speed_rpm:g}rpm"
    run = res.to_run(rid, speed_rpm, channels=channels if st.keep_periods else None, notes=notes)
    return _simulated(config, channels, run, created_utc, what)


def _what(fault: str | None) -> str:
    return f"fault {fault!r}" if fault else "healthy"


def _periods(st: StepSettings) -> str:
    return str(st.n_periods) if isinstance(st.n_periods, int) else f"{min(st.n_periods)}-{max(st.n_periods)}"


def _simulated(config: RigConfig, channels: list[Channel], run: Run, created_utc: str, what: str) -> Sweep:
    """A one-run simulated Sweep; its generator string names the rig, its hash and ``what``."""
    generator = f"rotorcheck {__version__} simulate (rig {config.rig_id} sha256 {config.sha256()[:12]}, {what})"
    return Sweep(rig_id=config.rig_id, source="simulated", generator=generator, created_utc=created_utc,
                 channels=channels, runs={run.run_id: run})


def simulate_rig_patterns(
    config: RigConfig,
    freq_hz: np.ndarray,
    actuators: Sequence[Port],
    sensors: Sequence[Port] | None = None,
    speed_rpm: float = 0.0,
    fault: str | None = None,
    seed: int = 0,
    run_id: str | None = None,
    created_utc: str = "2026-01-01T00:00:00Z",
    n_harmonics: int = 8,
    settings: StepSettings | None = None,
    shaft_angle_rad: float = 0.0,
) -> Sweep:
    """Simulated stepped-sine sweep of ``config`` with several actuators driven one at a time
    (seeded, deterministic) as a one-run version-2 Sweep (``n_exc = n_in = len(actuators)``).

    ``actuators``/``sensors``: config ports (``sensors`` default: the rig's sensor port); the
    channel table is :func:`port_channels`. Otherwise as :func:`simulate_rig` (the rig's
    measurement section, faults, shaft angle at the start).
    """
    if len(actuators) == 0:
        raise InputError(None, "actuators", "no actuator ports")
    sens = list(sensors) if sensors is not None else [config.io_ports("the simulator").sensor]
    f = np.asarray(freq_hz, dtype=float)
    band = float(np.max(f)) if f.size else None
    rp = rig_plants(config, speed_rpm, actuators, sens, fault, n_harmonics, band)
    plants, dist = rp.plants, rp.disturbances
    if shaft_angle_rad != 0.0 and speed_rpm != 0.0:
        plants = [_turned_plant(p, speed_rpm, shaft_angle_rad) for p in plants]
        dist = _turned_tones(dist, speed_rpm, shaft_angle_rad)
    st = settings if settings is not None else step_settings(config)
    res = simulate_fast_patterns(plants, f, st, dist, rng=seed, speed_rpm=speed_rpm, shaft_angle_rad=shaft_angle_rad)
    what, n_per = _what(fault), _periods(st)
    channels = port_channels(config, actuators, sens)
    notes = (f"{what}; seed {seed}; {len(actuators)} actuators driven one at a time "
             f"({', '.join(c.name for c in channels if c.role == 'input')}); {n_per} periods; "
             f"noise std {st.output_noise_std} m/sample; shaft angle at start {np.degrees(shaft_angle_rad):.6g} deg")
    rid = run_id or f"{speed_rpm:g}rpm"
    run = res.to_run(rid, speed_rpm, channels=channels if st.keep_periods else None, notes=notes)
    return _simulated(config, channels, run, created_utc, f"{what}, {len(actuators)} actuators")
