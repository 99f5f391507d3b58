"""omnibot.control's face: its names are the defining modules' own, loaded on first use."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

from omnibot import control


@pytest.mark.parametrize(("module", "name"), [(m, n) for m, names in control._EXPORTS.items() for n in names])
def test_a_name_of_the_face_is_the_defining_modules_own(module: str, name: str) -> None:
    defining = importlib.import_module(f"omnibot.control.{module}")
    assert getattr(control, name) is getattr(defining, name)
    assert name in control.__all__


def test_a_name_the_face_lacks_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'Paths'"):
        control.Paths  # noqa: B018


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
