"""A rig's assembled model at one speed as one object: :class:`Rig`.

It carries the rig description, the speed and the benign state (speed offset, sensor and actuator gains) and
builds its mechanical system once; receptances of any channel pairs, the rig with an element's stiffness
lost or benign parameters applied, its ports and candidate elements follow from it.

>>> from rotorcheck.config import load_config
>>> from rotorcheck.resources import configs_dir
>>> rig = Rig(load_config(configs_dir() / "crack_rig.yaml"), speed_rpm=1000.0)
>>> rig.candidate_elements
(1, 2, 3, 4, 5, 6, 7, 8, 9)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rotorcheck.config import DamagePort, Ports, RigConfig
from rotorcheck.fe.assembly import build_system
from rotorcheck.fe.system import MechanicalSystem
from rotorcheck.nominal import ChannelPair, pair_receptance, primary_pair
from rotorcheck.signatures import candidate_elements, with_element_loss
from rotorcheck.variability import with_benign


@dataclass(frozen=True)
class Rig:
    """The model of one rig description at ``speed_rpm`` (rpm), in a benign state: ``speed_offset_rpm`` adds
    to the spin speed, ``sensor_gain`` multiplies the measured output and ``actuator_gain`` the applied force
    (1 and 1: as described)."""

    config: RigConfig
    speed_rpm: float = 0.0
    speed_offset_rpm: float = 0.0
    sensor_gain: float = 1.0
    actuator_gain: float = 1.0

    @cached_property
    def system(self) -> MechanicalSystem:
        """The assembled mechanical system (built on first use, then kept)."""
        return build_system(self.config)

    @property
    def ports(self) -> Ports | None:
        """The actuator and sensor (None: a rig for modal analysis only)."""
        return self.config.ports

    @property
    def damage_port(self) -> DamagePort | None:
        """Where the damage dynamics are identified (None: no damage port)."""
        return self.config.damage

    @property
    def candidate_elements(self) -> tuple[int, ...]:
        """Every shaft element (1-based) a local stiffness loss may sit in; none for a lumped rig."""
        return candidate_elements(self.config)

    def receptance(self, freq_hz: np.ndarray, pairs: Sequence[ChannelPair] | None = None) -> np.ndarray:
        """Receptance of each channel pair (default: the rig's actuator -> sensor) on ``freq_hz`` (Hz), (f, P)
        m/N, at the speed plus its offset, scaled by the sensor and actuator gains."""
        use = list(pairs) if pairs is not None else [primary_pair(self.config)]
        h = pair_receptance(self.config, freq_hz, self.speed_rpm + self.speed_offset_rpm, use, self.system)
        return h * (self.sensor_gain * self.actuator_gain)

    def with_element_loss(self, element: int, loss: float) -> Rig:
        """The rig with shaft ``element`` (1-based) losing the fraction ``loss`` of its stiffness (E x (1 - loss))."""
        return Rig(with_element_loss(self.config, element, loss), self.speed_rpm, self.speed_offset_rpm,
                   self.sensor_gain, self.actuator_gain)

    def with_benign(self, values: Mapping[str, float]) -> Rig:
        """The rig with benign parameter values applied (names of its ``variability`` section; relative changes
        for factors, offsets in their unit; :func:`rotorcheck.variability.with_benign`)."""
        cfg, speed, sensor, actuator = with_benign(self.config, values)
        return Rig(cfg, self.speed_rpm, self.speed_offset_rpm + speed, self.sensor_gain * sensor,
                   self.actuator_gain * actuator)
