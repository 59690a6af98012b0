"""Quantity types of the rig file: a number in SI or a string with a unit (``"16 mm"``), by dimension."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BeforeValidator

from rotorcheck.units import parse_quantity


def _q(dimension: str) -> Any:
    return BeforeValidator(lambda v: parse_quantity(v, dimension))


Length = Annotated[float, _q("length")]


Mass = Annotated[float, _q("mass")]


Density = Annotated[float, _q("density")]


Pressure = Annotated[float, _q("pressure")]


Stiffness = Annotated[float, _q("stiffness")]


Damping = Annotated[float, _q("damping")]


Inertia = Annotated[float, _q("inertia")]


FrequencyHz = Annotated[float, _q("frequency")]


SpeedRpm = Annotated[float, _q("speed")]


Force = Annotated[float, _q("force")]


Moment = Annotated[float, _q("moment")]


Unbalance = Annotated[float, _q("unbalance")]


Angle = Annotated[float, _q("angle")]


Ratio = Annotated[float, _q("dimensionless")]

