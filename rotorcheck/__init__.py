"""rotorcheck: robust model validation and damage identification for rotating shafts.

Implements R. Madden (2016): Timoshenko FE rotor model, noise bound, robust model validation by the
generalized structured singular value (LMI per frequency), fault detection and identification of the
local damage dynamics with an exact uncertainty bound. SI units throughout; frequencies in Hz at
interfaces.
"""

__version__ = "0.1.0"  # the one place: pyproject.toml reads it ([tool.setuptools.dynamic])
