"""Config error messages: the bad key, where it is, and the nearest valid one."""

from __future__ import annotations

import pytest
from pydantic import BaseModel, ConfigDict, ValidationError

from omnibot.config_errors import explain, format_loc, suggest


class Inner(BaseModel):
    model_config = ConfigDict(extra="forbid")
    radius: float


class Outer(BaseModel):
    model_config = ConfigDict(extra="forbid")
    wheels: tuple[Inner, ...]


def test_suggest_nearest_or_all() -> None:
    assert (
        suggest("unknown robot 'omni5'", "omni5", ["omni4", "omni3"])
        == "unknown robot 'omni5'; did you mean 'omni4'?"
    )
    assert suggest("unknown x 'zzz'", "zzz", ["b", "a"]) == "unknown x 'zzz'; expected one of: a, b"


def test_format_loc() -> None:
    assert format_loc(("wheels", 1, "radius")) == "wheels[1].radius"
    assert format_loc(()) == ""


def test_explain_lists_every_problem() -> None:
    with pytest.raises(ValidationError) as info:
        Outer.model_validate({"wheels": [{"radius": 1}, {"radus": 2}], "extra": 1})
    msg = str(explain(info.value, Outer, "thing", "t.yaml"))
    assert msg.startswith("invalid thing t.yaml:")
    assert "wheels[1].radus: unknown key; did you mean 'radius'?" in msg
    assert "wheels[1].radius: required key is missing" in msg
    assert "extra: unknown key; expected one of: wheels" in msg
