"""The import graph of src/omnibot, read from the modules' syntax trees: no cycles between modules,
the packages in the storeys docs/architecture.md draws (each imports only from its own storey and
below, with no cycle between packages; the runtime, a library, only what its row of the narrow table
lists), and the pure modules (fits, kinematics, codecs, the
firmware...) never load the client or a transport. Each package has a face (``__all__`` in its
``__init__``: the names it re-exports and the submodules other packages use): every name in it
exists, and another package imports only the submodules it names.

A package whose face re-exports names (``from omnibot.client import RobotClient``) is imported
through it: another package names its module only for a submodule the face lists and takes no
names from (``omnibot.robot.kinematics``), not ``from omnibot.client.client import RobotClient``.
tests/ are held to the same rules, each test module as part of the package it tests (tests/sim/...
as ``omnibot.sim``: its own internals are open to it), the modules no face gives listed in
``TEST_REACHES``; benchmarks/ too (outside every package: ``BENCHMARK_REACHES``).

Edges: every ``import`` and ``from ... import`` of an omnibot module, at module level and inside
functions alike (a lazy import still runs when its function does, so it closes a cycle as surely as
one at the top), except those under ``if TYPE_CHECKING:`` (never run). ``from pkg import name``
is an edge to ``pkg.name`` when that is a module, else to ``pkg`` (and, when ``pkg``'s ``__init__``
gives ``name`` on first use through a module ``__getattr__``, to the module of ``pkg`` it comes
from: read from the ``if TYPE_CHECKING:`` import that types it). Imports made by
``importlib.import_module`` with a computed name are invisible here.

For cycles a submodule's implicit import of its own package's ``__init__`` is not an edge (a
package that imports its submodules is the usual layout, not a loop; import-linter counts the
same way). For purity it is: importing ``omnibot.client.events`` runs ``omnibot/client/__init__.py``,
which loads the client.
"""

from __future__ import annotations

import ast
import importlib
import re
from collections.abc import Callable, Iterable, Iterator
from functools import cache
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
ARCHITECTURE = SRC.parent / "docs" / "architecture.md"
ROOT = "omnibot"

ALLOWED_CYCLES: dict[frozenset[str], str] = {
    # control/followers: base.py's follower registry imports its own package lazily (in
    # make_follower/follower_names) so that the built-in followers are registered on first use, and
    # the package's __init__ imports base and every follower.
    frozenset(
        {
            "omnibot.control.followers",
            "omnibot.control.followers.base",
            "omnibot.control.followers.pure_pursuit",
            "omnibot.control.followers.seed002",
            "omnibot.control.followers.tracker",
        }
    ): "followers registry <-> its package (lazy import in base.py)",
}
"""Module cycles found when this test was written (owned by other work in progress:
do not add to this list, take entries out as they are untangled). Each is the exact set of modules
of one strongly connected component, so a new module or import joining one fails the test too."""

PURE: tuple[str, ...] = (
    "omnibot.calibration.accuracy",
    "omnibot.calibration.calfile",
    "omnibot.calibration.coastfit",
    "omnibot.calibration.fits",
    "omnibot.calibration.gyro",
    "omnibot.calibration.motorfit",
    "omnibot.calibration.patterns",
    "omnibot.calibration.perturb",
    "omnibot.calibration.plan",
    "omnibot.calibration.rates",
    "omnibot.calibration.results",
    "omnibot.calibration.rollerfit",
    "omnibot.calibration.runs",
    "omnibot.calibration.tables",
    "omnibot.calibration.umbmark",
    "omnibot.calibration.verdict",
    "omnibot.control.paths",
    "omnibot.control.pid",
    "omnibot.control.followers",
    "omnibot.control.reach",
    "omnibot.estimation",
    "omnibot.firmware",
    "omnibot.floor",
    "omnibot.protocol",
    "omnibot.robot.calibration_spec",
    "omnibot.robot.description",
    "omnibot.robot.kinematics",
    "omnibot.robot.parts",
    "omnibot.robot.sensors",
    "omnibot.robot.spec",
)
"""Modules (and packages, with every module under them) that compute or encode and do no I/O on a
link: they must not load the client or a transport, not even through another module."""

IO_PACKAGES = ("omnibot.client", "omnibot.transport")


def module_files() -> dict[str, Path]:
    """Every module of src/omnibot by its dotted name (a package by its ``__init__.py``)."""
    out = {}
    for path in sorted((SRC / ROOT).rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = module_files()


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """The import statements under ``node``, skipping ``if TYPE_CHECKING:`` bodies."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.Import | ast.ImportFrom):
            yield child
        elif isinstance(child, ast.If) and _type_checking(child):
            for other in child.orelse:
                yield from _walk_stmt(other)
        else:
            yield from _walk(child)


def _walk_stmt(stmt: ast.stmt) -> Iterator[ast.Import | ast.ImportFrom]:
    if isinstance(stmt, ast.Import | ast.ImportFrom):
        yield stmt
    else:
        yield from _walk(stmt)


def _from_module(name: str, node: ast.ImportFrom) -> str:
    """The module a ``from ... import`` in module ``name`` reads, relative imports resolved."""
    if not node.level:
        return node.module or ""
    package = name.split(".") if MODULES[name].name == "__init__.py" else name.split(".")[:-1]
    base = package[: len(package) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


@cache
def _tree(name: str) -> ast.Module:
    path = MODULES[name]
    return ast.parse(path.read_text(encoding="utf-8"), str(path))


def _under(module: str, prefixes: tuple[str, ...]) -> bool:
    return any(module == p or module.startswith(p + ".") for p in prefixes)


def _defines_getattr(node: ast.stmt) -> bool:
    """``def __getattr__`` or ``__getattr__ = ...`` (omnibot.faces.lazy_names), at the top or under
    ``if not TYPE_CHECKING:`` (so that type checkers see the names' own imports)."""
    if isinstance(node, ast.FunctionDef):
        return node.name == "__getattr__"
    if isinstance(node, ast.If) and isinstance(node.test, ast.UnaryOp) and isinstance(node.test.op, ast.Not):
        hidden = ast.If(test=node.test.operand, body=[], orelse=[])
        return _type_checking(hidden) and any(_defines_getattr(child) for child in node.body)
    return isinstance(node, ast.Assign) and any(
        isinstance(t, ast.Name) and t.id == "__getattr__" for t in node.targets
    )


def lazy_names(package: str) -> dict[str, str]:
    """The names ``package``'s ``__init__`` gives on first use (a module ``__getattr__``, PEP 562),
    each with the package's own module it comes from (read from the ``if TYPE_CHECKING:`` imports
    that type them)."""
    tree = _tree(package)
    if not any(_defines_getattr(n) for n in tree.body):
        return {}
    out: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and _type_checking(node):
            for child in node.body:
                if isinstance(child, ast.ImportFrom) and _under(_from_module(package, child), (package,)):
                    out.update((alias.name, _from_module(package, child)) for alias in child.names)
    return out


def imports_of(name: str) -> set[str]:
    """The omnibot modules ``name`` imports (see the module docstring)."""
    return targets_of(_tree(name), lambda node: _from_module(name, node)) - {name}


def targets_of(tree: ast.Module, resolve: Callable[[ast.ImportFrom], str]) -> set[str]:
    """The omnibot modules the imports of ``tree`` name (``resolve``: the module a ``from ...
    import`` reads)."""
    out: set[str] = set()
    for node in _walk(tree):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
            continue
        module = resolve(node)
        lazy = LAZY.get(module, {})
        for alias in node.names:
            sub = f"{module}.{alias.name}"
            out.add(sub if sub in MODULES else module)
            if alias.name in lazy:
                out.add(lazy[alias.name])
    return {m for m in out if m in MODULES}


LAZY = {name: lazy_names(name) for name, path in MODULES.items() if path.name == "__init__.py"}
GRAPH = {name: imports_of(name) for name in MODULES}


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan, iteratively)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(frozenset(component))
    return found


def loop_through(component: frozenset[str], graph: dict[str, set[str]]) -> list[str]:
    """One closed path through a component, for the failure message."""
    start = min(component)
    path, seen = [start], {start}
    while True:
        nxt = sorted(m for m in graph[path[-1]] if m in component)
        back = [m for m in nxt if m in seen]
        if back:
            return [*path[path.index(back[0]) :], back[0]]
        path.append(next(m for m in nxt if m not in seen))
        seen.add(path[-1])


def with_packages(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The graph with each import also running its target's packages' ``__init__``."""
    out = {}
    for name, targets in graph.items():
        parents = {".".join(t.split(".")[:k]) for t in targets for k in range(1, t.count(".") + 1)}
        out[name] = targets | {p for p in parents if p in MODULES}
    return out


def loads(name: str, graph: dict[str, set[str]]) -> dict[str, str]:
    """Every module importing ``name`` loads, each with the module that imported it."""
    via = {p: name for p in with_packages({name: {name}})[name] if p != name}  # its own packages
    todo = [name, *via]
    while todo:
        current = todo.pop()
        for target in sorted(graph[current]):
            if target not in via and target != name:
                via[target] = current
                todo.append(target)
    return via


def chain(name: str, target: str, via: dict[str, str]) -> str:
    out = [target]
    while out[-1] != name:
        out.append(via[out[-1]])
    return " -> ".join(reversed(out))


def test_the_graph_is_read() -> None:
    """The reader sees top-level, lazy, relative and ``from pkg import module`` imports, and skips
    TYPE_CHECKING ones (checked on modules whose imports are known)."""
    assert "omnibot.calibration.session" in GRAPH["omnibot.apps.calibrate"]  # lazy, in run()
    assert "omnibot.client" in GRAPH["omnibot.calibration.session"]  # from pkg import name
    assert "omnibot.control.reach" in GRAPH["omnibot.estimation.stall"]  # a lazy face's name
    assert "omnibot.control.followers" in GRAPH["omnibot.control.followers.base"]  # from pkg import mod
    assert "omnibot.client.events" not in GRAPH["omnibot.calibration.umbmark"]  # TYPE_CHECKING only
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [frozenset("abc")]


def test_no_import_cycles() -> None:
    found = {c: loop_through(c, GRAPH) for c in cycles(GRAPH)}
    new = [" -> ".join(loop) for c, loop in found.items() if c not in ALLOWED_CYCLES]
    assert not new, "import cycles:\n  " + "\n  ".join(new)
    gone = [why for c, why in ALLOWED_CYCLES.items() if c not in found]
    assert not gone, "no longer a cycle (take it out of ALLOWED_CYCLES): " + "; ".join(gone)


def test_calibration_has_no_cycle_at_all() -> None:
    assert not [c for c in cycles(GRAPH) if any(m.startswith("omnibot.calibration") for m in c)]


@pytest.mark.parametrize("name", [m for m in MODULES if _under(m, PURE)])
def test_pure_modules_load_no_client_or_transport(name: str) -> None:
    graph = with_packages(GRAPH)
    via = loads(name, graph)
    bad = [chain(name, m, via) for m in sorted(via) if _under(m, IO_PACKAGES)]
    assert not bad, f"{name} loads the client or a transport:\n  " + "\n  ".join(bad[:3])


def test_the_pure_list_names_real_modules() -> None:
    assert all(p in MODULES for p in PURE)


def test_nothing_imports_the_apps() -> None:
    """``omnibot.apps`` holds composition roots only: the command line (the apps storey: ``cli``)
    reaches them, no library below imports them."""
    assert "omnibot.apps.mapping" in MODULES
    top = STOREYS[-1][1]
    bad = sorted(
        f"{name} -> {target}"
        for name, targets in GRAPH.items()
        if package_of(name) not in top
        for target in targets
        if _under(target, ("omnibot.apps",))
    )
    assert not bad, "imports of omnibot.apps:\n  " + "\n  ".join(bad)


COMMAND_LINE_TOOLS: dict[str, str] = {
    "omnibot.firmware.avrgen": "python -m: the AVR firmware's headers, written beside their generator",
    "omnibot.firmware.avrsketch": "python -m: the UNO firmware as an Arduino sketch folder",
    "omnibot.firmware.config": "python -m: a board's config and files from a robot description",
    "omnibot.uno.emulator": "python -m: the emulated UNO on a pty",
    "omnibot.uno.hil": "python -m: the emulated UNO with the simulator's physics in the loop",
}
"""Library modules that parse a command line all the same: the ``python -m`` tools of the firmware
and the UNO, each keeping its small ``main`` beside the code it drives (docs/architecture.md). The
list only shrinks: a new command's options are the apps'."""


def parses_options(tree: ast.Module) -> bool:
    """The module imports ``argparse`` (anywhere, type-only imports too: a library given an
    ``argparse.Namespace`` is handling options)."""
    return any(
        (isinstance(node, ast.Import) and any(alias.name == "argparse" for alias in node.names))
        or (isinstance(node, ast.ImportFrom) and node.module == "argparse" and not node.level)
        for node in ast.walk(tree)
    )


def test_only_the_apps_parse_a_command_line() -> None:
    """Option parsing and ``argparse.Namespace`` handling are the apps storey's (``omnibot.apps``,
    ``cli``, ``cliargs``): no library imports ``argparse`` but the tools of ``COMMAND_LINE_TOOLS``."""
    assert parses_options(ast.parse("def f():\n    from argparse import Namespace"))
    assert not parses_options(ast.parse("import argparsed\nfrom .argparse import x"))
    top = STOREYS[-1][1]
    found = sorted(m for m in MODULES if package_of(m) not in top and parses_options(_tree(m)))
    new = [m for m in found if m not in COMMAND_LINE_TOOLS]
    assert not new, "library modules that parse a command line (move it to omnibot.apps):\n  " + "\n  ".join(
        new
    )
    gone = [m for m in COMMAND_LINE_TOOLS if m not in found]
    assert not gone, "no longer parse a command line (take them out of COMMAND_LINE_TOOLS): " + ", ".join(
        gone
    )


# --------------------------------------------------------------------------- packages and storeys


def read_storeys(text: str) -> list[tuple[str, list[str]]]:
    """docs/architecture.md's storeys, bottom first: (name, packages) from the picture between the
    ``<!-- storeys`` and ``<!-- /storeys -->`` markers (``omnibot`` is the package's own
    ``__init__``, the others are ``omnibot.<name>``)."""
    start = text.index("<!-- storeys")
    block = text[start : text.index("<!-- /storeys -->", start)]
    rows: dict[int, tuple[str, list[str]]] = {}
    for line in block.splitlines():
        match = re.fullmatch(r"\s*(\d+)\s+(\S+(?: \S+)*)\s{2,}(\S.*)", line)
        if match:
            names = match[3].split()
            rows[int(match[1])] = (match[2], [ROOT if n == ROOT else f"{ROOT}.{n}" for n in names])
    assert sorted(rows) == list(range(len(rows))), "storeys numbered 0, 1, 2 ... from the bottom"
    return [rows[k] for k in sorted(rows)]


STOREYS = read_storeys(ARCHITECTURE.read_text(encoding="utf-8"))
LEVEL = {package: level for level, (_, packages) in enumerate(STOREYS) for package in packages}


def package_of(module: str) -> str:
    """The storey's package ``module`` belongs to (the longest one that holds it)."""
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in LEVEL:
            return ".".join(parts[:k])
    raise KeyError(f"{module} is in no storey of docs/architecture.md: add its package to the picture")


def upward(graph: dict[str, set[str]]) -> list[str]:
    """Every import ``a -> b`` of a package from a higher storey than its own."""
    return sorted(
        f"{name} -> {target}"
        for name, targets in graph.items()
        for target in targets
        if LEVEL[package_of(target)] > LEVEL[package_of(name)]
    )


def package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The storeys' packages and the imports between them."""
    out: dict[str, set[str]] = {p: set() for p in LEVEL}
    for name, targets in graph.items():
        for target in targets:
            a, b = package_of(name), package_of(target)
            if a != b:
                out[a].add(b)
    return out


def test_the_storeys_are_read() -> None:
    assert STOREYS[0][0] == "foundation" and ROOT in STOREYS[0][1]
    assert STOREYS[-1][0] == "apps" and "omnibot.apps" in STOREYS[-1][1]
    assert package_of("omnibot.control.followers.base") == "omnibot.control"
    assert package_of("omnibot.cli") == "omnibot.cli" and package_of("omnibot") == ROOT
    assert upward({"omnibot.motion": {"omnibot.apps.run"}, "omnibot.apps.run": {"omnibot.motion"}}) == [
        "omnibot.motion -> omnibot.apps.run"
    ]
    assert upward({"omnibot.ros2.bridge": {"omnibot.cliargs"}}) == ["omnibot.ros2.bridge -> omnibot.cliargs"]
    assert cycles(
        package_graph({"omnibot.sim.x": {"omnibot.client.y"}, "omnibot.client.y": {"omnibot.sim.x"}})
    )


def test_every_package_is_in_a_storey() -> None:
    loose = sorted({m for m in MODULES if not any(_under(m, (p,)) for p in LEVEL)})
    assert not loose, "modules in no storey of docs/architecture.md: " + ", ".join(loose)
    ghosts = sorted(p for p in LEVEL if p not in MODULES)
    assert not ghosts, "storeys name packages that do not exist: " + ", ".join(ghosts)


def test_packages_import_only_downward() -> None:
    """No import goes up a storey: a library never reaches the apps (``cliargs`` included) or a
    storey above its own."""
    found = upward(GRAPH)
    assert not found, "imports from a higher storey (docs/architecture.md):\n  " + "\n  ".join(found)


def test_no_package_cycle() -> None:
    """No cycle between packages, within a storey either."""
    graph = package_graph(GRAPH)
    found = [" -> ".join(loop_through(c, graph)) for c in cycles(graph)]
    assert not found, "package cycles:\n  " + "\n  ".join(found)


def read_narrow(text: str) -> dict[str, set[str]]:
    """docs/architecture.md's packages held narrower than their storey: each with the packages it may
    import besides the foundation's, from the table between the ``<!-- narrow`` and ``<!-- /narrow
    -->`` markers (one row per package: its name, then those it may import, without ``omnibot.``)."""
    start = text.index("<!-- narrow")
    block = text[start : text.index("<!-- /narrow -->", start)]
    out: dict[str, set[str]] = {}
    for line in block.splitlines():
        match = re.fullmatch(r"\s*([a-z0-9_]+)((?:\s+[a-z0-9_]+)+)\s*", line)
        if match:
            out[f"{ROOT}.{match[1]}"] = {f"{ROOT}.{n}" for n in match[2].split()}
    return out


NARROW = read_narrow(ARCHITECTURE.read_text(encoding="utf-8"))


def beyond(graph: dict[str, set[str]], narrow: dict[str, set[str]]) -> list[str]:
    """Every import ``a -> b`` of a package of ``narrow`` from one it may not import (the
    foundation's packages are open to all)."""
    foundation = set(STOREYS[0][1])
    return sorted(
        f"{name} -> {target}"
        for name, targets in graph.items()
        if package_of(name) in narrow
        for target in targets
        if package_of(target) != package_of(name)
        and package_of(target) not in narrow[package_of(name)] | foundation
    )


def test_the_runtime_is_a_library() -> None:
    """The runtime imports the client, the protocol, estimation, control, the robot's description and
    the shared types: nothing of a front end (teleop's sources, navigation's following), of a link
    (transport: the client owns it) or of a log (a recording is handed in)."""
    assert beyond({"omnibot.runtime.sources": {"omnibot.teleop"}}, NARROW) == [
        "omnibot.runtime.sources -> omnibot.teleop"
    ]
    allowed = NARROW["omnibot.runtime"]
    assert allowed <= {f"{ROOT}.{n}" for n in ("client", "protocol", "estimation", "control", "robot")}
    found = beyond(GRAPH, NARROW)
    assert not found, "imports beyond what docs/architecture.md lets the package import:\n  " + "\n  ".join(
        found
    )


# --------------------------------------------------------------------------- package faces


PACKAGES = sorted(m for m, p in MODULES.items() if p.name == "__init__.py")


def face_of(package: str) -> list[str] | None:
    """The names of ``package``'s ``__all__`` (a literal list of strings in its ``__init__``), None
    without one."""
    for node in _tree(package).body:
        if not isinstance(node, ast.Assign | ast.AnnAssign):
            continue
        targets = [node.target] if isinstance(node, ast.AnnAssign) else node.targets
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            value = node.value
            assert isinstance(value, ast.List | ast.Tuple), f"{package}.__all__ is not a literal list"
            names = [e.value for e in value.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
            assert len(names) == len(value.elts), f"{package}.__all__ holds something else than names"
            return names
    return None


def face_crossings(graph: dict[str, set[str]]) -> list[str]:
    """Every import ``a -> p.x...`` from outside the package ``p`` into its submodule ``x`` that
    ``p.__all__`` does not name (the root package ``omnibot`` aside: the storeys rule it)."""
    out = []
    for name, targets in graph.items():
        for target in targets:
            for package in PACKAGES:
                if package == ROOT or not _under(target, (package,)) or target == package:
                    continue
                if _under(name, (package,)):
                    continue
                first = target[len(package) + 1 :].split(".")[0]
                if first not in (face_of(package) or []):
                    out.append(f"{name} -> {target} ({package}.__all__ lacks {first!r})")
    return sorted(out)


def test_every_package_has_a_face() -> None:
    """Each package's ``__init__`` has ``__all__``: the names it re-exports and the submodules other
    packages use."""
    missing = [p for p in PACKAGES if face_of(p) is None]
    assert not missing, "packages without __all__ in their __init__: " + ", ".join(missing)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_name_of_a_face_exists(package: str) -> None:
    """A name of ``__all__`` is a submodule of the package or an attribute of it once imported (the
    ``__init__``'s own names, lazy ones included)."""
    module = importlib.import_module(package)
    ghosts = [n for n in face_of(package) or [] if f"{package}.{n}" not in MODULES and not hasattr(module, n)]
    assert not ghosts, f"{package}.__all__ names what does not exist: {', '.join(ghosts)}"


def test_packages_import_each_other_through_their_faces() -> None:
    """Another package imports a package's submodule only when its ``__all__`` names it (a module
    left out of ``__all__`` is the package's own business)."""
    assert face_crossings({"omnibot.motion": {"omnibot.sim.hidden"}}) == [
        "omnibot.motion -> omnibot.sim.hidden (omnibot.sim.__all__ lacks 'hidden')"
    ]
    bad = face_crossings(GRAPH)
    assert not bad, (
        "imports of modules outside their package's face (add them to __all__):\n  " + "\n  ".join(bad)
    )


SUBMODULE_FACES: tuple[str, ...] = (
    "omnibot.apps",
    "omnibot.firmware",
    "omnibot.protocol",
)
"""Storey packages whose faces list submodules only, so that other packages still import names from
those submodules: firmware's and protocol's by design (their ``__init__`` is copied to boards), the
others until their faces re-export their names. Take each out once its face does, never add one: a
new package's face re-exports the names other packages use."""


@cache
def faced_packages() -> dict[str, set[str]]:
    """Each storey package whose face re-exports names, with the submodules its ``__init__`` takes
    names from (under ``if TYPE_CHECKING:`` too: a lazy face names them there)."""
    out = {}
    for package in LEVEL:
        face = face_of(package) or []
        if package == ROOT or all(f"{package}.{n}" in MODULES for n in face):
            continue
        nodes = [n for n in ast.walk(_tree(package)) if isinstance(n, ast.ImportFrom)]
        sources = {_from_module(package, n) for n in nodes}
        out[package] = {m for m in sources if _under(m, (package,)) and m != package}
    return out


def from_imports() -> Iterator[tuple[str, str, list[str]]]:
    """(importer, module, names) of every ``from omnibot... import`` (type-only ones too: a type is
    named through the face as well)."""
    for name in MODULES:
        for node in ast.walk(_tree(name)):
            if isinstance(node, ast.ImportFrom):
                yield name, _from_module(name, node), [alias.name for alias in node.names]


def around_faces(statements: Iterable[tuple[str, str, list[str]]]) -> list[str]:
    """Every ``from p.x import names`` from outside the package ``p`` whose face re-exports names,
    when the face re-exports one of ``names`` or takes names from ``p.x``."""
    faced = faced_packages()
    out = []
    for name, module, names in statements:
        package = next((p for p in faced if _under(module, (p,)) and module != p), None)
        if package is None or _under(name, (package,)):
            continue
        face = face_of(package) or []
        listed = [n for n in names if n in face and f"{package}.{n}" not in MODULES]
        head = f"{name}: from {module} import {', '.join(names)}"
        if listed:
            out.append(f"{head}: import {', '.join(listed)} from {package} (its face)")
        elif _under(module, tuple(faced[package])):
            out.append(f"{head}: add {', '.join(names)} to {package}.__all__ and import from {package}")
    return sorted(out)


def test_packages_import_re_exported_names_from_the_face() -> None:
    """Another package takes a re-exported name from the face, not from the module that defines it,
    and a name of a module the face re-exports from goes through the face too."""
    assert around_faces([("omnibot.motion", "omnibot.client.client", ["RobotClient"])]) == [
        "omnibot.motion: from omnibot.client.client import RobotClient: import RobotClient from"
        " omnibot.client (its face)"
    ]
    assert around_faces([("omnibot.apps.run", "omnibot.robot.kinematics", ["world_to_body"])]) == []
    assert around_faces([("omnibot.apps.run", "omnibot.robot.description", ["Unlisted"])]) == [
        "omnibot.apps.run: from omnibot.robot.description import Unlisted: add Unlisted to"
        " omnibot.robot.__all__ and import from omnibot.robot"
    ]
    assert around_faces([("omnibot.ros2.goal", "omnibot.mapping.grid", ["OccupancyGrid"])]) == [
        "omnibot.ros2.goal: from omnibot.mapping.grid import OccupancyGrid: import OccupancyGrid from"
        " omnibot.mapping (its face)"
    ]
    faced = {
        "omnibot.client",
        "omnibot.logs",
        "omnibot.mapping",
        "omnibot.navigation",
        "omnibot.robot",
        "omnibot.runtime",
    }
    assert faced <= set(faced_packages())
    bad = around_faces(from_imports())
    assert not bad, "imports around a package's face:\n  " + "\n  ".join(bad)


def test_faces_re_export_names() -> None:
    """Every storey package's face re-exports the names other packages use, but those of
    ``SUBMODULE_FACES`` (the list only shrinks)."""
    faced = faced_packages()
    bare = sorted(
        p for p in LEVEL if p != ROOT and p in MODULES and MODULES[p].name == "__init__.py" and p not in faced
    )
    new = [p for p in bare if p not in SUBMODULE_FACES]
    assert not new, "faces that list submodules only (re-export the names other packages use): " + ", ".join(
        new
    )
    done = [p for p in SUBMODULE_FACES if p not in bare]
    assert not done, "faces that re-export names now (take them out of SUBMODULE_FACES): " + ", ".join(done)


# --------------------------------------------------------------------------- the tests through the faces


TESTS = SRC.parent / "tests"
BENCHMARKS = SRC.parent / "benchmarks"

TEST_REACHES: dict[str, tuple[str, tuple[str, ...]]] = {
    "omnibot.apps.calibrate": (
        "runs the subcommand's own run() with a scripted prompt",
        ("cli/test_outcomes.py",),
    ),
    "omnibot.apps.run": ("patches compose() in the module that defines it", ("cli/test_run.py",)),
    "omnibot.calibration.accuracy": (
        "builds accuracy rows by hand to check what omnibot calibrate reports",
        ("apps/test_calibrate.py", "cli/test_outcomes.py"),
    ),
    "omnibot.calibration.calfile": ("parses a calibration file's text", ("apps/test_calibrate.py",)),
    "omnibot.calibration.results": ("builds a surface session by hand", ("cli/test_outcomes.py",)),
    "omnibot.calibration.truth": (
        "the simulator behind a client, as the truths find it",
        ("transport/test_device.py",),
    ),
    "omnibot.calibration.verdict": (
        "the verdict's parts and noise floors the expected verdicts are derived from",
        ("apps/test_calibrate.py", "cli/test_outcomes.py"),
    ),
    "omnibot.client.wire": ("encodes binary frames for the UNO's parser", ("uno/test_binary.py",)),
    "omnibot.control.followers.base": (
        "the planner's wheel-use bound the expectation is derived from",
        ("benchmarks/test_seed002_run.py",),
    ),
    "omnibot.control.paths.standard": ("the standard paths' swing angle", ("navigation/test_runner.py",)),
    "omnibot.control.reach": (
        "the planner's speed bounds the expectations are derived from",
        ("benchmarks/test_seed002_run.py", "navigation/test_runner.py"),
    ),
    "omnibot.firmware.avrsketch": (
        "the UNO's Arduino sketch, generated from the firmware's sources",
        ("uno/test_sketch.py",),
    ),
    "omnibot.firmware.parser": ("fuzzes the firmware's parser itself", ("fuzz/targets.py",)),
    "omnibot.firmware.unixhal": (
        "runs the MicroPython firmware on the host's unix port, as a board would",
        ("contract/run_unix.py",),
    ),
    "omnibot.lidar.rplidar_codec": (
        "speaks the RPLIDAR protocol to the emulated scanner",
        ("sim/test_emulator_scanner.py",),
    ),
    "omnibot.logs.reader": (
        "reads back, record by record, the log a command wrote",
        ("apps/test_log.py", "apps/test_teleop.py"),
    ),
    "omnibot.logs.rosmsg": (
        "builds the messages the recorder writes (twist, odometry) to compare the bridge's with",
        ("ros2/test_cmd_vel.py", "ros2/test_frames.py", "ros2/test_types.py"),
    ),
    "omnibot.logs.recording": (
        "binds the Foxglove server of a recording by hand",
        ("apps/test_recording.py",),
    ),
    "omnibot.mapping.score": (
        "the map scores and the world rasterised (world_grid): the tests' and benchmarks' yardstick",
        (
            "apps/test_goto.py",
            "logs/test_slamscore.py",
            "navigation/test_goto.py",
            "navigation/test_goto_source.py",
            "ros2/test_goal.py",
            "ros2/test_navigate.py",
            "ros2/test_rclpy_goal_pose.py",
        ),
    ),
    "omnibot.navigation.session": (
        "the limits omnibot follow gives a robot's follower (and its simulated run), to build the same",
        (
            "control/test_profile.py",
            "control/test_tracker_heading.py",
            "runtime/test_frontends.py",
            "runtime/test_runtime.py",
            "runtime/test_sources.py",
            "runtime/test_standstill.py",
        ),
    ),
    "omnibot.robot.description": (
        "the presets' directory (PRESET_DIR): the tests go through every preset file",
        (
            "apps/test_mapping.py",
            "cli/test_grammar.py",
            "client/test_session.py",
            "firmware/test_config.py",
            "ros2/test_assembly.py",
            "sim/test_physics.py",
        ),
    ),
    "omnibot.runtime.core": (
        "the latched emergency stop's notice, as the page shows it",
        ("navigation/test_webteach.py",),
    ),
    "omnibot.uno.hil": ("the UNO in the loop with the simulator's sonar", ("contract/test_sonar_stop.py",)),
    "omnibot.web.link": (
        "drives the dashboard's robot link with the page's messages, without the server",
        ("navigation/test_webteach.py", "runtime/test_frontends.py"),
    ),
    "omnibot.web.messages": (
        "the page's messages to the dashboard's robot link",
        ("navigation/test_webteach.py", "runtime/test_frontends.py"),
    ),
}
"""Modules of other packages that tests import names or modules from which no face gives (each with
why, and the test modules, under tests/, that do): take a test module out once it goes through a
face, never add one. A name a face re-exports is always taken from the face."""

BENCHMARK_REACHES: dict[str, tuple[str, tuple[str, ...]]] = {
    "omnibot.calibration.accuracy": ("the reach the accuracy plan checks", ("motor_model.py",)),
    "omnibot.calibration.slip": ("the slip runs' speed", ("slip_courses.py",)),
    "omnibot.calibration.motorfit": ("fits the motor model it measures", ("motor_model.py",)),
    "omnibot.calibration.motors": ("balances the motors' model as the calibration does", ("motor_model.py",)),
    "omnibot.calibration.patterns": (
        "the calibration patterns' geometry",
        ("idle_phase.py", "motor_model.py"),
    ),
    "omnibot.calibration.runner": (
        "runs the calibration's commands (its Runner) by hand",
        ("idle_phase.py", "motor_model.py"),
    ),
    "omnibot.calibration.seedterms": (
        "seed 000's K_r and K_t read off a calibration",
        ("seed000_figures.py",),
    ),
    "omnibot.calibration.tap": ("the calibration's telemetry tap", ("idle_phase.py", "lockstep_tick.py")),
    "omnibot.calibration.verdict": ("the verdict's error measure", ("idle_phase.py",)),
    "omnibot.client.wire": ("frames bytes by hand to attack the controller", ("attack_suite.py",)),
    "omnibot.control.followers.base": (
        "the planner's margins the figures are judged against",
        ("seed002_run.py", "tracking.py"),
    ),
    "omnibot.control.paths.generator": (
        "the closed, figure-eight and random paths it tracks",
        ("tracking.py",),
    ),
    "omnibot.control.paths.standard": (
        "the standard paths' random ones and swing",
        ("odometry_drift.py", "tracking.py"),
    ),
    "omnibot.control.reach": (
        "the planner's speed bounds and the floor's grip the figures are judged against",
        ("seed002_run.py", "tracking.py"),
    ),
    "omnibot.estimation.odometry": ("the odometry's count deltas", ("slip_flag.py",)),
    "omnibot.estimation.wheelslip": ("the slip check's window", ("slip_flag.py",)),
    "omnibot.logs.live": (
        "the Foxglove live server, measured and attacked",
        ("attack_suite.py", "foxglove_live.py"),
    ),
    "omnibot.logs.reader": ("reads back the log it measures", ("log_cost.py",)),
    "omnibot.logs.rosmsg": ("builds the twist messages it sends", ("speed_accuracy.py",)),
    "omnibot.logs.topics": ("the topics it counts", ("log_cost.py",)),
    "omnibot.mapping.deskew": ("the SLAM's parts measured alone", ("slam_synthetic.py",)),
    "omnibot.mapping.mapper": ("the mapper measured alone", ("mapping_localise.py", "mapping_mapper.py")),
    "omnibot.mapping.matcher": ("the scan matcher measured alone", ("scan_matching.py",)),
    "omnibot.mapping.planner": ("the planners and their cost weight, compared", ("planner.py",)),
    "omnibot.mapping.score": (
        "the map scores and the world rasterised: the benchmarks' yardstick",
        ("mapping_mapper.py", "planner.py", "slam_bench.py"),
    ),
    "omnibot.mapping.se2": (
        "the pose algebra the errors are measured with",
        ("mapping_localise.py", "scan_matching.py", "slam_synthetic.py"),
    ),
    "omnibot.mapping.slam": ("the SLAM's parts measured alone", ("slam_synthetic.py",)),
    "omnibot.navigation.goto": ("goto() (its module's name shadows it in the face)", ("goto.py",)),
    "omnibot.navigation.plot": ("plots the runs", ("tracking.py",)),
    "omnibot.navigation.session": (
        "the follower limits and the simulated follow omnibot follow runs",
        ("odometry_drift.py", "off_path.py", "seed002_run.py", "slip_flag.py", "tracking.py"),
    ),
    "omnibot.navigation.slipcal": (
        "the floor's slip calibration on the simulator",
        ("move_landing.py", "slip_courses.py", "speed_accuracy.py", "tracking.py"),
    ),
    "omnibot.ros2.cmd_vel": ("the stamped twist's type name", ("speed_accuracy.py",)),
    "omnibot.ros2.netns": (
        "the private network namespaces DDS runs in",
        ("attack_suite.py", "netns.py", "ros2_latency.py"),
    ),
    "omnibot.ros2.types": ("builds the DDS samples it sends", ("speed_accuracy.py",)),
    "omnibot.transport.faults": (
        "the fault injection's channels, driven directly",
        ("attack_suite.py", "link_faults.py"),
    ),
}
"""The same for benchmarks/ (the benchmarks under benchmarks/): a benchmark measures a package's parts
alone, so it reaches further in than a test of another package does."""


def held_as(path: Path) -> str:
    """The importer a test module is held as: ``omnibot.<name>`` for tests/<name>/... when that is a
    storey package (its tests use its internals, its subpackages' too, as its own modules do), else
    the module's own dotted name (tests/contract, tests/fuzz, tests/benchmarks, tests/test_*.py and
    benchmarks/: outside every package)."""
    parts = path.relative_to(TESTS.parent).with_suffix("").parts
    package = f"{ROOT}.{parts[1]}"
    return package if len(parts) > 2 and package in LEVEL else ".".join(parts)


def reaches(tree: ast.Module, home: str) -> list[tuple[str, str]]:
    """(module, what is wrong) for each import of a test module (its syntax tree, the importer it is
    held as) around another package's face: the rules above for src/ (:func:`face_crossings`,
    :func:`around_faces`)."""
    targets = targets_of(tree, lambda node: "" if node.level else node.module or "")
    out = [(t, bad) for t in sorted(targets) if not _under(t, (home,)) for bad in face_crossings({home: {t}})]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and not node.level and node.module:
            statement = (home, node.module, [alias.name for alias in node.names])
            out += [(node.module, bad) for bad in around_faces([statement])]
    return out


@cache
def reaches_in(folder: Path) -> tuple[tuple[str, str, str], ...]:
    """(module under ``folder``, the module it imports, what is wrong) for every import of tests/ or
    benchmarks/ around a face."""
    out = []
    for path in sorted(folder.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        out += [(str(path.relative_to(folder)), module, why) for module, why in reaches(tree, held_as(path))]
    return tuple(out)


def test_the_tests_are_held_as_their_package() -> None:
    assert held_as(TESTS / "sim" / "test_kernels.py") == "omnibot.sim"
    assert held_as(TESTS / "contract" / "conftest.py") == "tests.contract.conftest"
    assert held_as(TESTS / "test_cli.py") == "tests.test_cli"
    own = ast.parse("from omnibot.control.paths.generator import x\nfrom omnibot.control.reach import y")
    assert reaches(own, "omnibot.control") == []
    around = ast.parse("from omnibot.client.client import RobotClient")
    assert reaches(around, "tests.x") == [
        (
            "omnibot.client.client",
            "tests.x: from omnibot.client.client import RobotClient: import RobotClient from"
            " omnibot.client (its face)",
        )
    ]
    hidden = ast.parse("from omnibot.mapping import grid, score")
    assert reaches(hidden, "tests.x") == [
        ("omnibot.mapping.score", "tests.x -> omnibot.mapping.score (omnibot.mapping.__all__ lacks 'score')")
    ]


@pytest.mark.parametrize("folder", [TESTS, BENCHMARKS], ids=["tests", "benchmarks"])
def test_tests_and_benchmarks_take_re_exported_names_from_the_face(folder: Path) -> None:
    """A test or a benchmark outside a package takes the names its face re-exports from the face, as
    src/ does."""
    bad = [
        f"{folder.name}/{module}: {why}"
        for module, _, why in reaches_in(folder)
        if why.endswith("(its face)")
    ]
    assert not bad, "imports around a package's face:\n  " + "\n  ".join(bad)


@pytest.mark.parametrize(
    ("folder", "listed"),
    [(TESTS, TEST_REACHES), (BENCHMARKS, BENCHMARK_REACHES)],
    ids=["tests", "benchmarks"],
)
def test_tests_and_benchmarks_reach_other_packages_internals_only_where_listed(
    folder: Path, listed: dict[str, tuple[str, tuple[str, ...]]]
) -> None:
    """A test or a benchmark outside a package imports what its face does not give only as
    TEST_REACHES or BENCHMARK_REACHES lists (the lists only shrink)."""
    found = {
        (where, module): why for where, module, why in reaches_in(folder) if not why.endswith("(its face)")
    }
    allowed = {(where, module) for module, (_, wheres) in listed.items() for where in wheres}
    new = [f"{w}: {found[w, m]}" for w, m in sorted(found) if (w, m) not in allowed]
    assert not new, f"{folder.name}/ imports another package's internals (use its face):\n  " + "\n  ".join(
        new
    )
    gone = [f"{w} -> {m}" for w, m in sorted(allowed - set(found))]
    assert not gone, "no longer imported around a face (take them out of the list): " + "; ".join(gone)
