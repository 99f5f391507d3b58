"""omnibot.control's face: a name loads its own subpackage only (tests/test_faces.py checks that each
name is the defining module's own)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from omnibot import control


def test_a_name_the_face_lacks_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'Paths'"):
        control.Paths  # type: ignore[attr-defined]  # noqa: B018  (mypy rejects it too)


def test_a_name_of_the_face_loads_its_own_subpackage_only() -> None:
    """read_path loads control.paths, not the planner's reach, the followers or the PID."""
    code = (
        "import json, sys, omnibot.control\n"
        "from omnibot.control import read_path\n"
        "print(json.dumps([m for m in sys.modules if m.startswith('omnibot.control')]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    loaded = set(json.loads(out))
    assert "omnibot.control.paths.files" in loaded
    assert not loaded & {"omnibot.control.reach", "omnibot.control.followers", "omnibot.control.pid"}
