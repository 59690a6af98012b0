"""The strict base model of every rig-file section: unknown keys are refused, values frozen."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

from rotorcheck.errors import InputError


class Strict(BaseModel):
    """Base: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class ConfigError(InputError):
    """An unusable rig file. ``str()`` names the file and the field."""
