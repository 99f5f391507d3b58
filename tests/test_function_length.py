"""No function of src/omnibot is longer than :data:`MAX_LINES` lines, from its ``def`` to its last
line (signature and docstring included, decorators not; a nested function counts on its own and in
the function around it). Long functions are split into named pieces (docs/architecture.md,
"Function length").

:data:`LONG` lists the functions that were longer when the rule came, in modules other work owned
then, each with its length: it only ratchets down. A listed function may not grow; one that shrinks
has its entry lowered to its new length, and taken out once it fits; no function joins the list.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
ROOT = "omnibot"
MAX_LINES = 60

LONG: dict[str, int] = {}
"""``module:qualified name`` -> its length in lines when it was listed (or last shortened)."""


def _functions(
    tree: ast.AST, prefix: str = ""
) -> Iterator[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    """Every function under ``tree`` with its qualified name (``Class.method``, ``outer.inner``)."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            name = f"{prefix}{node.name}"
            if not isinstance(node, ast.ClassDef):
                yield name, node
            yield from _functions(node, f"{name}.")
        else:
            yield from _functions(node, prefix)


def lengths(source: str, module: str) -> dict[str, int]:
    """``module:qualified name`` -> lines from ``def`` to the function's last line, of every function
    in ``source``."""
    return {
        f"{module}:{name}": (node.end_lineno or node.lineno) - node.lineno + 1
        for name, node in _functions(ast.parse(source))
    }


def all_lengths() -> dict[str, int]:
    """:func:`lengths` of every module of src/omnibot."""
    out: dict[str, int] = {}
    for path in sorted((SRC / ROOT).rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out.update(lengths(path.read_text(encoding="utf-8"), ".".join(parts)))
    return out


def test_lengths_are_counted_from_def_to_the_last_line() -> None:
    source = "class A:\n    def f(self):\n        def g():\n            return 1\n\n        return g\n\n\nasync def h(): pass\n"
    assert lengths(source, "m") == {"m:A.f": 5, "m:A.f.g": 2, "m:h": 1}


def test_no_function_is_longer_than_the_limit() -> None:
    found = all_lengths()
    new = sorted(f"{name}: {n} lines" for name, n in found.items() if n > MAX_LINES and name not in LONG)
    assert not new, f"functions over {MAX_LINES} lines (split them into named pieces):\n  " + "\n  ".join(new)
    grew = sorted(
        f"{name}: {found[name]} lines, listed at {n}" for name, n in LONG.items() if found.get(name, 0) > n
    )
    assert not grew, "listed long functions that grew (split them instead):\n  " + "\n  ".join(grew)


def test_the_list_of_long_functions_only_shrinks() -> None:
    """An entry whose function is gone or fits comes out; one that shrank is lowered to its length."""
    found = all_lengths()
    stale = sorted(
        f"{name}: " + ("gone" if name not in found else f"{found[name]} lines (listed at {n})")
        for name, n in LONG.items()
        if found.get(name, 0) < n
    )
    assert not stale, (
        f"update LONG (take out what is gone or fits in {MAX_LINES} lines, lower the rest):\n  "
        + "\n  ".join(stale)
    )
