"""Numba's cache of the kernels: every kernel's entry stamped with every file of the family."""

from __future__ import annotations

import ast
import shutil
from pathlib import Path
from typing import Any

from omnibot.sim import kernels
from omnibot.sim.kernels import lanes
from omnibot.sim.kernels.cache import FAMILY, FROZEN, FamilyLocator, family_stamp


def test_every_kernel_is_cached_with_the_familys_stamp_where_numba_would_cache_it() -> None:
    every: tuple[Any, ...] = (
        *kernels.KERNELS,
        kernels.physics_step_parallel,
        kernels.solve_body,
        lanes.physics_run,
    )
    for kernel in every:
        locator = kernel._cache._impl.locator
        assert isinstance(locator, FamilyLocator), kernel
        own, family = locator.get_source_stamp()
        assert family == family_stamp() and own == locator._inner.get_source_stamp()
        assert locator.get_cache_path() == locator._inner.get_cache_path()


def test_a_change_to_any_file_of_the_family_changes_the_stamp(tmp_path: Path) -> None:
    """An edit of wheels.py must reach robot_step's cache entry (step.py), which compiles it in."""
    copy = tmp_path / "kernels"
    shutil.copytree(FAMILY, copy, ignore=shutil.ignore_patterns("__pycache__"))
    before = family_stamp(copy)
    assert before == family_stamp(FAMILY)
    wheels = copy / "wheels.py"
    wheels.write_text(wheels.read_text(encoding="utf-8") + "\n", encoding="utf-8")
    assert family_stamp(copy) != before


def test_functions_outside_the_family_keep_numbas_own_locator() -> None:
    def elsewhere() -> None:
        pass

    assert FamilyLocator.from_function(elsewhere, __file__) is None


def test_the_constants_kernels_import_from_outside_the_family_stamp_them(tmp_path: Path) -> None:
    """numba freezes an imported global's value into a kernel: the file that defines it is stamped
    (an edit of the floor's ROLL_SPEED_EPS must compile the kernels again)."""
    outside: set[str] = set()
    for path in FAMILY.glob("*.py"):
        imports = [
            n for n in ast.walk(ast.parse(path.read_text(encoding="utf-8"))) if isinstance(n, ast.ImportFrom)
        ]
        for node in imports:
            module = node.module or ""
            if module.startswith("omnibot.") and not module.startswith("omnibot.sim.kernels"):
                outside |= {alias.name for alias in node.names}
    defined = {
        target.id
        for path in FROZEN
        for node in ast.parse(path.read_text(encoding="utf-8")).body
        if isinstance(node, ast.Assign | ast.AnnAssign)
        for target in (node.targets if isinstance(node, ast.Assign) else [node.target])
        if isinstance(target, ast.Name)
    }
    assert outside and outside <= defined, outside - defined
    edited = tmp_path / FROZEN[0].name
    edited.write_text(FROZEN[0].read_text(encoding="utf-8") + "\n", encoding="utf-8")
    assert family_stamp(FAMILY, (edited,)) != family_stamp()
