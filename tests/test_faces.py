"""The faces that give their names on first use (omnibot.faces.lazy_names): each name is the defining
module's own, looked up there each time, and importing the package loads none of its modules."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

LAZY_FACES = (
    "omnibot.calibration",
    "omnibot.control",
    "omnibot.demos",
    "omnibot.lidar",
    "omnibot.logs",
    "omnibot.mapping",
    "omnibot.navigation",
    "omnibot.plots",
    "omnibot.ros2",
    "omnibot.sim",
    "omnibot.teleop",
    "omnibot.uno",
    "omnibot.web",
)
"""The faces built with an ``_EXPORTS`` table (robot's two lazy names are its summary's and urdf's)."""


def exports(package: str) -> list[tuple[str, str]]:
    face = importlib.import_module(package)
    return [(module, name) for module, names in face._EXPORTS.items() for name in names]


@pytest.mark.parametrize(
    ("package", "module", "name"), [(p, m, n) for p in LAZY_FACES for m, n in exports(p)]
)
def test_a_name_of_the_face_is_the_defining_modules_own(package: str, module: str, name: str) -> None:
    face = importlib.import_module(package)
    defining = importlib.import_module(f"{package}.{module}")
    assert getattr(face, name) is getattr(defining, name)
    assert name in face.__all__


@pytest.mark.parametrize("package", LAZY_FACES)
def test_a_stand_in_on_the_defining_module_is_the_one_the_face_gives(
    package: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A test that puts a stand-in on the module that defines a name reaches every importer that takes
    the name from the face when it runs (as a function-level import does)."""
    module, name = exports(package)[0]
    stand_in = object()
    monkeypatch.setattr(f"{package}.{module}.{name}", stand_in)
    face: ModuleType = importlib.import_module(package)
    assert getattr(face, name) is stand_in


def test_importing_a_face_loads_none_of_its_modules() -> None:
    code = (
        f"import json, sys\nfor p in {LAZY_FACES!r}:\n    __import__(p)\n"
        f"print(json.dumps(sorted(m for m in sys.modules if m.startswith({LAZY_FACES!r}) and m not in {LAZY_FACES!r})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert json.loads(out) == []


def test_every_face_with_an_exports_table_is_listed() -> None:
    """A new lazy face is checked here as soon as it is written: LAZY_FACES names every package whose
    ``__init__`` has an ``_EXPORTS`` table."""
    src = Path(__file__).resolve().parents[1] / "src"
    found = sorted(
        ".".join(init.parent.relative_to(src).parts)
        for init in (src / "omnibot").rglob("__init__.py")
        if "\n_EXPORTS = " in init.read_text(encoding="utf-8")
    )
    assert found == sorted(LAZY_FACES)
