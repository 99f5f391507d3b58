"""Config errors that name the bad key and suggest the right one (robot descriptions, worlds, ...).

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


def read_yaml(path: str | Path, what: str) -> Any:
    """The parsed content of a YAML file; ConfigError naming ``what`` and the file when it cannot be
    read, is not UTF-8 text or is not YAML (validating the content is the caller's)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read {what} {path}: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"cannot read {what} {path}: not UTF-8 text (byte {exc.start})") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path} is not valid YAML: {exc}") from None


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
