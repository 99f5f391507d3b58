"""A recorded run's tables: the robot description in its metadata is read as any description file."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.errors import ConfigError
from omnibot.logs.run import Run


def test_the_recorded_description_is_read_and_a_key_given_twice_refused() -> None:
    run = Run(Path("run.mcap"), metadata={"omnibot": {"description": "name: omni4\nmass: 1.6\n"}})
    assert run.description() == {"name": "omni4", "mass": 1.6}
    run.metadata["omnibot"]["description"] = "name: omni4\nmass: 1.6\nmass: 16\n"
    with pytest.raises(ConfigError) as info:
        run.description()
    assert str(info.value) == (
        "invalid robot description run.mcap (omnibot metadata): mass: duplicate key on line 3 (first on line 2)"
    )
    assert Run(Path("run.mcap")).description() is None
