"""Packaging as users install it: the core alone (``pip install omnibot``) does what the core promises,
and a command whose extra is missing says which ``pip install 'omnibot[...]'`` to run (exit 2).

The install tests build omnibot's sdist and wheel as a release does (``python -m build``: the wheel
from the sdist) and install each with the core dependencies only into a fresh venv
(benchmarks/core_install.py, at constraints.txt's versions: pip's cache or the network); they are
marked ``install`` (``-m 'not install'`` leaves them out) and run in ``make test``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tarfile
import tomllib
from pathlib import Path

import pytest
from benchmarks.core_install import (
    CONSTRAINTS,
    CORE_IMPORT,
    ROOT,
    Dists,
    build_dists,
    clean_env,
    install_venv,
)

from omnibot.extras import COMMAND_EXTRA, EXTRA_OF, SHARED, WHAT, missing_extra

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
EXTRAS: dict[str, list[str]] = PYPROJECT["project"]["optional-dependencies"]
CORE_DISTRIBUTIONS = {"pydantic", "pyyaml", "pyserial", "tqdm"}
"""The core's own dependencies (pydantic brings a few more of its own)."""

USER_EXTRAS = ("control", "sim", "plots", "web", "teleop", "logs", "ros2", "slam")


def _name(requirement: str) -> str:
    """The distribution of a requirement string (``"numba>=0.68,<1"`` -> ``"numba"``), lower case."""
    for stop in "<>=!~[;@ ":
        requirement = requirement.split(stop, maxsplit=1)[0]
    return requirement.strip().lower().replace("_", "-")


def _pins() -> dict[str, str]:
    lines = CONSTRAINTS.read_text(encoding="utf-8").splitlines()
    pairs = (line.split("==") for line in lines if line and not line.startswith("#"))
    return {_name(name): version for name, version in pairs}


# --------------------------------------------------------------------------- pyproject and constraints


def test_the_core_depends_on_the_core_only() -> None:
    assert {_name(r) for r in PYPROJECT["project"]["dependencies"]} == CORE_DISTRIBUTIONS


def test_every_user_extra_exists_and_all_gathers_them() -> None:
    assert set(USER_EXTRAS) <= set(EXTRAS)
    (everything,) = EXTRAS["all"]
    assert everything.startswith("omnibot[") and everything.endswith("]")
    assert sorted(everything[len("omnibot[") : -1].split(",")) == sorted(USER_EXTRAS)
    assert set(WHAT) == set(USER_EXTRAS)


@pytest.mark.parametrize(
    "requirement", [*PYPROJECT["project"]["dependencies"], *(r for extra in EXTRAS.values() for r in extra)]
)
def test_requirements_are_ranges_and_constraints_pin_them(requirement: str) -> None:
    """``>=x.y,<next`` in pyproject; the exact version in constraints.txt, inside the range."""
    if requirement.startswith("omnibot["):
        return
    assert "==" not in requirement and ">=" in requirement and "<" in requirement, requirement
    name = _name(requirement)
    pinned = _pins().get(name)
    assert pinned is not None, f"{name} is not pinned in constraints.txt"
    spec = requirement[requirement.index(">=") :]
    low, high = (part.strip().lstrip(">=<").strip() for part in spec.split(","))
    assert _version(low) <= _version(pinned) < _version(high), f"{name}=={pinned} outside {spec}"


def _version(text: str) -> tuple[int, ...]:
    return tuple(int("".join(c for c in part if c.isdigit()) or 0) for part in text.split("."))


def test_every_optional_module_has_an_extra_that_installs_it() -> None:
    """omnibot.extras.EXTRA_OF names an extra whose requirements hold that module's distribution."""
    distribution = {
        "PIL": "pillow",
        "yaml": "pyyaml",
        "rplidar": "rplidar-roboticia",
    }
    for module, extra in EXTRA_OF.items():
        if module in ("llvmlite", "starlette"):  # numba's and fastapi's own dependencies
            continue
        assert distribution.get(module, module.lower()) in {_name(r) for r in EXTRAS[extra]}, module


# --------------------------------------------------------------------------- the missing-extra error


def test_missing_extra_names_the_extra() -> None:
    line = missing_extra(ModuleNotFoundError("No module named 'numba'", name="numba"))
    assert line is not None and "pip install 'omnibot[sim]'" in line
    line = missing_extra(ModuleNotFoundError("No module named 'PIL.Image'", name="PIL.Image"))
    assert line is not None and "pip install 'omnibot[slam]'" in line
    # `goto --planner rrtstar` imports OMPL's bindings on first use: it was an "internal error", exit 70
    line = missing_extra(ModuleNotFoundError("No module named 'ompl'", name="ompl"))
    assert line is not None and "pip install 'omnibot[slam]'" in line


def test_a_shared_module_names_the_commands_extra() -> None:
    """numpy comes with most extras: the line names the one of the command that missed it."""
    numpy = ModuleNotFoundError("No module named 'numpy'", name="numpy")
    for command, extra in (("sim", "sim"), ("dashboard", "web"), ("goto", "slam"), ("follow", "control")):
        line = missing_extra(numpy, command)
        assert line is not None and f"pip install 'omnibot[{extra}]'" in line, (command, line)
    assert "pip install 'omnibot[control]'" in str(missing_extra(numpy))
    # a module of one extra is that extra's whatever the command
    assert "omnibot[sim]'" in str(missing_extra(ModuleNotFoundError(name="numba"), "dashboard"))


def test_every_extra_a_shared_module_names_installs_it() -> None:
    from omnibot.cli import build_parser

    (sub,) = (a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert set(COMMAND_EXTRA) <= set(sub.choices)
    for module in SHARED:
        for extra in {EXTRA_OF[module], *COMMAND_EXTRA.values()}:
            assert module in {_name(r) for r in EXTRAS[extra]}, (module, extra)


def test_other_import_errors_are_not_a_missing_extra() -> None:
    assert missing_extra(ModuleNotFoundError("No module named 'omnibot.nope'", name="omnibot.nope")) is None
    assert missing_extra(ImportError("cannot import name 'x' from 'numba'", name="numba")) is None
    assert missing_extra(ValueError("numba")) is None


HIDE = """
import importlib.abc, json, sys
HIDDEN = set(sys.argv[1].split(","))
class Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, Hide())
for module in HIDDEN:
    sys.modules.pop(module, None)
from omnibot.cli import main
results = []
for line in json.loads(sys.argv[2]):
    try:
        status = main(line)
    except SystemExit as exc:
        status = exc.code
    results.append(status)
print(json.dumps(results))
"""
"""A child that cannot import the HIDDEN modules runs ``omnibot`` command lines in turn."""


def _hidden(modules: list[str], lines: list[list[str]], tmp_path: Path) -> tuple[list[int], str]:
    """The exit status of each of ``lines`` run without ``modules``, and the child's stderr."""
    statuses, _, stderr = _hidden_run(modules, lines, tmp_path)
    return statuses, stderr


def _hidden_run(modules: list[str], lines: list[list[str]], tmp_path: Path) -> tuple[list[int], str, str]:
    """:func:`_hidden` with the commands' stdout too (the statuses' JSON line taken off it)."""
    done = subprocess.run(
        [sys.executable, "-c", HIDE, ",".join(modules), json.dumps(lines)],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
        env={**clean_env(), "PYTHONPATH": f"{ROOT / 'src'}", "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg"},
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    *printed, statuses = done.stdout.splitlines()
    return json.loads(statuses), "\n".join(printed), done.stderr


def test_a_command_without_its_extra_says_what_to_install(tmp_path: Path) -> None:
    """Declared (``log``), started (``demo``, ``sim``) or deep in a run (``dashboard`` on sim://): one
    line naming the extra, status 2, no traceback."""
    lines = [
        ["log", "--help"],
        ["demo", "--out", str(tmp_path)],
        ["sim", "--pty"],
        ["dashboard", "--port", "sim://", "--duration", "0.1"],
        ["teleop", "--port", "sim://", "--joystick", "--duration", "0.1"],
    ]
    statuses, stderr = _hidden(sorted(EXTRA_OF), lines, tmp_path)
    assert statuses == [2] * len(lines), stderr
    assert "Traceback" not in stderr
    said = [line for line in stderr.splitlines() if "pip install 'omnibot[" in line]
    assert len(said) == len(lines), stderr
    # the dashboard's run imports the web server before anything loads the simulator's kernels (the
    # planner's reach needs only the floor model): the first extra it misses is web's
    for extra, line in zip(("logs", "sim", "sim", "web", "teleop"), said, strict=True):
        assert f"pip install 'omnibot[{extra}]'" in line, line


def test_the_core_commands_run_without_numpy(tmp_path: Path) -> None:
    """With numpy alone hidden: the core's commands run, every other names its own extra."""
    lines = [
        ["robot", "list"],
        ["robot", "show", "omni3"],
        ["kinematics", "--robot", "mecanum4", "--wheels", "1,2,3,4"],
        ["follow", "--help"],
        ["sim", "--pty"],
        ["dashboard", "--port", "sim://", "--duration", "0.1"],
        ["map", "--out", str(tmp_path / "map"), "--explore", "--duration", "0.1"],
    ]
    statuses, stderr = _hidden(["numpy"], lines, tmp_path)
    assert statuses == [0, 0, 0, 0, 2, 2, 2], stderr
    assert "Traceback" not in stderr
    said = [line for line in stderr.splitlines() if "pip install 'omnibot[" in line]
    for extra, line in zip(("sim", "web", "slam"), said, strict=True):
        assert f"pip install 'omnibot[{extra}]'" in line, line
    assert all("'numpy' is not installed" in line for line in said[:2]), said


def test_a_board_driven_with_the_control_extra_alone(tmp_path: Path) -> None:
    """``pip install 'omnibot[control]'`` (numpy, no other optional module) on a board's serial port
    (the emulator's pty, itself run with everything): the protocol, a path repeated by ``follow`` and by
    ``run``, and ``record`` listening, each to its own outcome (nobody pushed the robot: nothing
    recorded, exit 1), none to a missing extra."""
    from tests.cli.conftest import PtyRobot

    path = tmp_path / "line.csv"
    path.write_text("t,x,y,theta\n" + "".join(f"{i * 0.2:.1f},{i * 0.05:.2f},0,0\n" for i in range(11)))
    board = PtyRobot("omni4")
    try:
        lines = [
            ["send", "STATUS", "--port", board.path],
            ["follow", str(path), "--port", board.path],
            ["run", "--port", board.path, "--follow", str(path)],
            ["record", "--port", board.path, "--path", str(tmp_path / "taught.csv"), "--duration", "0.5"],
        ]
        statuses, stdout, stderr = _hidden_run(sorted(set(EXTRA_OF) - {"numpy"}), lines, tmp_path)
    finally:
        board.close()
    assert statuses == [0, 0, 0, 1], stdout + stderr
    assert "pip install" not in stdout + stderr and "Traceback" not in stderr, stderr
    assert stdout.count("follow completed") == 1 and "omnibot follow: completed" in stdout, stdout
    assert "did the robot move?" in stdout and not (tmp_path / "taught.csv").exists()


def test_figures_are_left_out_not_the_run_without_the_plots_extra(tmp_path: Path) -> None:
    """``[sim]`` without ``[plots]``: the tour prints its table and says which extra draws its plot."""
    hidden = sorted(set(EXTRA_OF) - {"numpy", "numba", "llvmlite"})
    line = ["tour", "--robot", "omni3", "--out", str(tmp_path / "out"), "--duration", "0.3"]
    statuses, stdout, stderr = _hidden_run(hidden, [line], tmp_path)
    assert statuses == [0], stderr
    assert "rotate ccw" in stdout and "plot left out: 'matplotlib' is not installed" in stdout, stdout
    assert "pip install 'omnibot[plots]'" in stdout
    assert not (tmp_path / "out").exists()  # --out DIR is made with its first file: none here


def test_every_command_declares_its_options_without_any_extra(tmp_path: Path) -> None:
    """``omnibot CMD --help`` needs at most CMD's own extra: with all hidden, each prints its help
    (0) or the missing-extra line (2), never a traceback."""
    from omnibot.cli import build_parser

    (sub,) = (a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    commands = sorted(sub.choices)
    statuses, stderr = _hidden(sorted(EXTRA_OF), [[c, "--help"] for c in commands], tmp_path)
    assert "Traceback" not in stderr
    needs = {c for c, status in zip(commands, statuses, strict=True) if status != 0}
    # logs; follow's and record's options' defaults (the planner's reach) need only the floor model,
    # not the simulator's compiled kernels
    assert needs == {"log"}, stderr
    assert statuses.count(2) == stderr.count("pip install 'omnibot[") == len(needs), stderr


# --------------------------------------------------------------------------- the core install


@pytest.fixture(scope="module")
def dists(tmp_path_factory: pytest.TempPathFactory) -> Dists:
    return build_dists(tmp_path_factory.mktemp("dist"))


@pytest.fixture(scope="module")
def core_python(dists: Dists, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return install_venv(dists.wheel, tmp_path_factory.mktemp("core") / "venv")


@pytest.fixture(scope="module")
def sdist_python(dists: Dists, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return install_venv(dists.sdist, tmp_path_factory.mktemp("sdist") / "venv")


CACHES = ("__pycache__", ".pyc", ".nbi", ".nbc", ".cache/", ".mypy_cache", ".pytest_cache", ".ruff_cache")
"""What a checkout holds that no distribution may: byte code, the simulator's compiled kernels, tool caches."""


def _package_files() -> set[str]:
    """The files of src/omnibot a build needs (its modules and package data), relative to src/."""
    src = ROOT / "src"
    files = {p.relative_to(src).as_posix() for p in (src / "omnibot").rglob("*") if p.is_file()}
    return {f for f in files if not any(c in f for c in CACHES)}


@pytest.mark.install
@pytest.mark.timeout(600)
def test_the_sdist_carries_what_a_build_needs_and_no_cache(dists: Dists) -> None:
    with tarfile.open(dists.sdist) as tar:
        top = f"{dists.sdist.name.removesuffix('.tar.gz')}/"
        names = {n.removeprefix(top) for n in tar.getnames()}
    assert {"pyproject.toml", "README.md", "PKG-INFO"} <= names
    shipped = {n.removeprefix("src/") for n in names if n.startswith("src/omnibot/")}
    needed = _package_files()
    assert {"omnibot/py.typed", "omnibot/robot/presets/omni4.yaml", "omnibot/web/static/app.js"} <= needed
    assert needed <= shipped, sorted(needed - shipped)  # presets, worlds, teleop, web assets, modules
    assert not [n for n in names if any(c in n for c in CACHES)]


def _in_core(python: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(a) for a in args],
        capture_output=True,
        text=True,
        check=False,
        cwd=python.parent,
        env={**clean_env(), "SDL_VIDEODRIVER": "dummy"},
        timeout=120,
    )


@pytest.mark.install
@pytest.mark.timeout(600)
def test_the_core_install_holds_the_core_dependencies_only(core_python: Path) -> None:
    code = (
        "import importlib.metadata as m; print(sorted(d.metadata['Name'].lower() for d in m.distributions()))"
    )
    done = _in_core(core_python, str(core_python), "-c", code)
    names = {n.replace("_", "-") for n in json.loads(done.stdout.replace("'", '"'))}
    assert CORE_DISTRIBUTIONS | {"omnibot"} <= names
    assert not names & {_name(r) for extra in USER_EXTRAS for r in EXTRAS[extra]}
    assert "numpy" not in names


@pytest.mark.install
@pytest.mark.timeout(600)
@pytest.mark.parametrize("venv", ["core_python", "sdist_python"])
def test_the_core_imports_the_client_and_loads_no_extra(venv: str, request: pytest.FixtureRequest) -> None:
    """From the wheel and from the sdist alike."""
    core_python: Path = request.getfixturevalue(venv)
    code = f"{CORE_IMPORT}; import omnibot, sys; print(omnibot.__file__); print(sorted(sys.modules))"
    done = _in_core(core_python, str(core_python), "-c", code)
    assert done.returncode == 0, done.stderr
    where, loaded = done.stdout.splitlines()
    assert str(core_python.parents[1]) in where  # the installed wheel, not this checkout
    assert not {m.split(".")[0] for m in json.loads(loaded.replace("'", '"'))} & set(EXTRA_OF)


@pytest.mark.install
@pytest.mark.timeout(600)
def test_the_core_command_line(core_python: Path) -> None:
    omnibot = core_python.parent / "omnibot"
    done = _in_core(core_python, str(omnibot), "--help")
    assert done.returncode == 0 and "COMMAND" in done.stdout, done.stderr
    done = _in_core(core_python, str(omnibot), "robot", "list")
    assert done.returncode == 0 and "omni4" in done.stdout, done.stderr
    done = _in_core(core_python, str(omnibot), "robot", "urdf", "mecanum4")
    assert done.returncode == 0 and "<robot" in done.stdout, done.stderr
    done = _in_core(core_python, str(omnibot), "robot", "show", "omni3")
    assert done.returncode == 0 and "inverse kinematics" in done.stdout, done.stderr
    done = _in_core(
        core_python, str(omnibot), "kinematics", "--robot", "omni3", "--twist", "0.2,0,0.5", "--json"
    )
    assert done.returncode == 0, done.stderr
    speeds = json.loads(done.stdout)["wheel_speeds"]
    done = _in_core(
        core_python, str(omnibot), "kinematics", "--robot", "omni3", "--wheels", *map(str, speeds)
    )
    assert done.returncode == 0 and "vx=0.2 m/s  vy=" in done.stdout, done.stderr
    for command in (["demo"], ["sim", "--pty"]):
        done = _in_core(core_python, str(omnibot), *command)
        assert done.returncode == 2, done.stderr
        (line,) = done.stderr.strip().splitlines()
        assert line.startswith("omnibot: error: ") and "pip install 'omnibot[sim]'" in line, line


@pytest.mark.install
@pytest.mark.timeout(600)
@pytest.mark.parametrize("robot", ["omni4", "omni3", "mecanum4"])
def test_the_core_generates_the_firmware_config_of_this_checkout(
    core_python: Path, robot: str, tmp_path: Path
) -> None:
    """``python -m omnibot.firmware.config`` without numpy: the same literals as here, with numpy, and
    the board's files staged."""
    done = _in_core(core_python, str(core_python), "-m", "omnibot.firmware.config", robot, "--print")
    assert done.returncode == 0, done.stderr
    here = subprocess.run(
        [sys.executable, "-m", "omnibot.firmware.config", robot, "--print"],
        capture_output=True,
        text=True,
        check=True,
        env={**clean_env(), "PYTHONPATH": str(ROOT / "src")},
    )
    assert done.stdout == here.stdout
    done = _in_core(
        core_python, str(core_python), "-m", "omnibot.firmware.config", robot, str(tmp_path / "board")
    )
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "board" / "robot_config.py").is_file()
