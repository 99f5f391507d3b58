"""Config errors that name the bad key and suggest the right one (robot descriptions, worlds, ...).

Every YAML omnibot reads goes through :func:`load_yaml` (:func:`read_yaml` for a file): PyYAML's safe
loader, except that a mapping that gives a key twice is refused (``yaml.safe_load`` keeps the last
one and drops the first without a word)::

    invalid robot description mine.yaml: wheels[1].radius: duplicate key on line 14 (first on line 12)

``explain(error, root, what, source)`` turns a pydantic ValidationError of a strict model tree
(``extra="forbid"``) into one :class:`~omnibot.errors.ConfigError` listing every problem::

    invalid robot description broken.yaml:
      wheels[1].radus: unknown key; did you mean 'radius'?
      wheels[1].radius: required key is missing
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError

from omnibot.errors import ConfigError

_MERGE = "tag:yaml.org,2002:merge"


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """A mapping gives ``key`` (its path from the document's root) on ``line`` and again on
    ``again`` (1-based lines): the first repeat in the document; ``more`` repeats follow it."""

    def __init__(self, key: str, first: yaml.Node, second: yaml.Node, more: int = 0) -> None:
        super().__init__(
            f"while constructing a mapping with the key {key}",
            first.start_mark,
            "found it again",
            second.start_mark,
        )
        self.key = key
        self.line = first.start_mark.line + 1
        self.again = second.start_mark.line + 1
        self.more = more


class UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """``yaml.SafeLoader`` (libyaml's parser where PyYAML has it: the three presets in 5 ms of CPU
    instead of 25, the same data) that raises :class:`DuplicateKeyError` for a mapping with a key given twice
    (keys compare as the values they load as: ``1`` and ``0x1`` are one key). Keys merged in with
    ``<<`` may be overridden, as YAML's merge keys intend."""

    def construct_document(self, node: yaml.Node) -> Any:
        """Check every mapping of the document before constructing it."""
        repeats: list[tuple[str, yaml.Node, yaml.Node]] = []
        todo: list[tuple[yaml.Node, str]] = [(node, "")]
        seen: set[int] = set()  # each node once: anchors and aliases (even recursive ones)
        while todo:
            current, path = todo.pop()
            if id(current) in seen:
                continue
            seen.add(id(current))
            if isinstance(current, yaml.MappingNode):
                todo += self._check_mapping(current, path, repeats)
            elif isinstance(current, yaml.SequenceNode):
                todo += [(item, f"{path}[{i}]") for i, item in enumerate(current.value)]
        if repeats:
            key, first, second = min(repeats, key=lambda r: r[2].start_mark.index)
            raise DuplicateKeyError(key, first, second, len(repeats) - 1)
        return super().construct_document(node)

    def _check_mapping(
        self, node: yaml.MappingNode, path: str, repeats: list[tuple[str, yaml.Node, yaml.Node]]
    ) -> list[tuple[yaml.Node, str]]:
        """The mapping's values with their paths; each repeated key (path, first, repeat) to ``repeats``."""
        firsts: dict[Any, yaml.Node] = {}
        children = []
        for key_node, value_node in node.value:
            if key_node.tag == _MERGE:
                children.append((value_node, path))
                continue
            key = self.construct_object(key_node, deep=True)
            name = f"{path}.{key}" if path else str(key)
            try:
                first = firsts.setdefault(key, key_node)
            except TypeError:  # an unhashable key: the constructor reports it
                first = key_node
            if first is not key_node:
                repeats.append((name, first, key_node))
            children.append((value_node, name))
        return children


def load_yaml(text: str, what: str = "", source: str = "") -> Any:
    """Parse YAML ``text`` (one document) with :class:`UniqueKeyLoader`; ConfigError naming ``what``
    and ``source`` (a file name) when it is not YAML or gives a key twice."""
    try:
        return yaml.load(text, Loader=UniqueKeyLoader)
    except DuplicateKeyError as exc:
        head = " ".join(part for part in ("invalid", what, source) if part)
        more = f", and {exc.more} more duplicate key{'s' if exc.more > 1 else ''}" if exc.more else ""
        raise ConfigError(
            f"{head}: {exc.key}: duplicate key on line {exc.again} (first on line {exc.line}){more}"
        ) from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{source or what or 'the text'} is not valid YAML: {_yaml_problem(exc)}") from None


def _yaml_problem(exc: yaml.YAMLError) -> str:
    """PyYAML's error in one line, its places as the file's lines and columns (from 1); its own
    text spans several lines and names the parsed string ('<unicode string>'), not the file."""
    if not isinstance(exc, yaml.MarkedYAMLError) or exc.problem_mark is None:
        return str(exc)
    place = f"line {exc.problem_mark.line + 1}, column {exc.problem_mark.column + 1}"
    context = ""
    if exc.context:
        mark = exc.context_mark
        start = f" from line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        context = f" ({exc.context}{start})"
    return f"{place}: {exc.problem}{context}"


def read_yaml(path: str | Path, what: str) -> Any:
    """The parsed content of a YAML file (:func:`load_yaml`); ConfigError naming ``what`` and the file
    when it cannot be read, is not UTF-8 text, is not YAML or gives a key twice (validating the content
    is the caller's)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read {what} {path}: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"cannot read {what} {path}: not UTF-8 text (byte {exc.start})") from None
    return load_yaml(text, what, str(path))


def suggest(what: str, given: str, choices: Iterable[str]) -> str:
    """``what`` plus the nearest choice (``; did you mean 'x'?``) or the list of valid ones."""
    options = list(choices)
    close = difflib.get_close_matches(given, options, n=1, cutoff=0.5)
    hint = f"; did you mean '{close[0]}'?" if close else f"; expected one of: {', '.join(sorted(options))}"
    return what + hint


def _is_model(obj: Any) -> bool:
    return isinstance(obj, type) and issubclass(obj, BaseModel)


def _models_in(annotation: Any) -> Iterable[Any]:
    if _is_model(annotation):
        yield annotation
    for arg in getattr(annotation, "__args__", ()):
        yield from _models_in(arg)


def model_at(root: type[BaseModel], loc: tuple[int | str, ...]) -> type[BaseModel] | None:
    """The model class that owns the mapping at a validation-error location below ``root``."""
    model: Any = root
    for part in loc:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part) if _is_model(model) else None
        if field is None:
            return None
        model = next(iter(_models_in(field.annotation)), None)
    return model if _is_model(model) else None


def format_loc(loc: tuple[int | str, ...]) -> str:
    """``('wheels', 1, 'radius')`` -> ``wheels[1].radius`` (pydantic's validator tags left out)."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif not (part.startswith("function-") or part.startswith("tuple[")):
            out += f".{part}" if out else part
    return out


def explain(
    error: ValidationError,
    root: type[BaseModel],
    what: str,
    source: str = "",
    extra_keys: Mapping[type[BaseModel], Iterable[str]] | None = None,
) -> ConfigError:
    """One ConfigError for every problem in ``error``; ``extra_keys`` are valid keys a model accepts
    beyond its fields (e.g. the description's top-level ``motor`` merged by a before-validator)."""
    lines = []
    for item in error.errors():
        loc = tuple(item["loc"])
        key = format_loc(loc) or "(top level)"
        given = item.get("input")
        if item["type"] == "extra_forbidden":
            owner = model_at(root, loc[:-1])
            valid = list(owner.model_fields) if owner else []
            if owner is not None and extra_keys:
                valid += list(extra_keys.get(owner, ()))
            lines.append(f"{key}: " + suggest("unknown key", str(loc[-1]), valid))
        elif item["type"] == "missing":
            lines.append(f"{key}: required key is missing")
        elif item["type"] == "literal_error" and isinstance(given, str):
            choices = re.findall(r"'([^']*)'", str(item.get("ctx", {}).get("expected", "")))
            lines.append(f"{key}: " + suggest(f"unknown value {given!r}", given, choices))
        else:
            msg = item["msg"].removeprefix("Value error, ")
            shown = "" if isinstance(given, Mapping | list) else f" (got {given!r})"
            lines.append(f"{key}: {msg}{shown}")
    head = f"invalid {what} {source}" if source else f"invalid {what}"
    return ConfigError(head + ":\n  " + "\n  ".join(lines))
