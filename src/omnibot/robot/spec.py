"""The base of every section of a robot description: strict and immutable."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class Spec(BaseModel):
    """Strict, immutable base: unknown keys are errors, and so is every number that is not finite
    (``.inf``, ``.nan``; the error names the key): no limit, gain or length of a robot is infinite,
    and the firmware's config could not even spell one."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
