"""Config error messages: the bad key, where it is, and the nearest valid one; YAML with a key given
twice refused (every YAML omnibot reads goes through one loader)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

import omnibot
from omnibot.config_errors import (
    DuplicateKeyError,
    UniqueKeyLoader,
    explain,
    format_loc,
    load_yaml,
    read_yaml,
    suggest,
)
from omnibot.errors import ConfigError

SRC = Path(omnibot.__file__).resolve().parent
ROOT = Path(__file__).resolve().parents[1]


class Inner(BaseModel):
    model_config = ConfigDict(extra="forbid")
    radius: float


class Outer(BaseModel):
    model_config = ConfigDict(extra="forbid")
    wheels: tuple[Inner, ...]


def test_suggest_nearest_or_all() -> None:
    assert (
        suggest("unknown robot 'omni5'", "omni5", ["omni4", "omni3"])
        == "unknown robot 'omni5'; did you mean 'omni4'?"
    )
    assert suggest("unknown x 'zzz'", "zzz", ["b", "a"]) == "unknown x 'zzz'; expected one of: a, b"


def test_format_loc() -> None:
    assert format_loc(("wheels", 1, "radius")) == "wheels[1].radius"
    assert format_loc(()) == ""


def test_explain_lists_every_problem() -> None:
    with pytest.raises(ValidationError) as info:
        Outer.model_validate({"wheels": [{"radius": 1}, {"radus": 2}], "extra": 1})
    msg = str(explain(info.value, Outer, "thing", "t.yaml"))
    assert msg.startswith("invalid thing t.yaml:")
    assert "wheels[1].radus: unknown key; did you mean 'radius'?" in msg
    assert "wheels[1].radius: required key is missing" in msg
    assert "extra: unknown key; expected one of: wheels" in msg


# --------------------------------------------------------------------------- duplicate keys


def test_a_key_given_twice_is_refused_naming_it_and_both_lines() -> None:
    with pytest.raises(ConfigError) as info:
        load_yaml("name: a\nmass: 1\nname: b\n", "robot description", "r.yaml")
    assert (
        str(info.value) == "invalid robot description r.yaml: name: duplicate key on line 3 (first on line 1)"
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "motor:\n  gear_ratio: 10\n  pwm_bits: 8\n  gear_ratio: 1\n",
            "motor.gear_ratio: duplicate key on line 4 (first on line 2)",
        ),
        (
            "wheels:\n  - {name: m1, radius: 0.02}\n  - name: m2\n    radius: 0.02\n    radius: 0.03\n",
            "wheels[1].radius: duplicate key on line 5 (first on line 4)",
        ),
        ("a: {b: {c: 1,\n  c: 2}}\n", "a.b.c: duplicate key on line 2 (first on line 1)"),
        ("1: one\n0x1: also one\n", "1: duplicate key on line 2 (first on line 1)"),  # keys compare as loaded
        # the first repeat in the document, whatever the nesting, and how many more there are
        (
            "a:\n  x: 1\n  x: 2\nb: 1\nb: 2\nc: 1\nc: 2\n",
            "a.x: duplicate key on line 3 (first on line 2), and 2 more duplicate keys",
        ),
    ],
)
def test_nested_keys_are_named_by_their_place(text: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_yaml(text, "thing", "t.yaml")
    assert str(info.value) == f"invalid thing t.yaml: {message}"


def test_what_yaml_allows_twice_still_loads() -> None:
    # a merge key's values may be overridden, an anchor may be used twice, one key in two mappings
    text = "base: &b {x: 1, y: 2}\nmine:\n  <<: *b\n  x: 5\nagain: *b\nlist: [{x: 1}, {x: 2}]\n"
    assert load_yaml(text) == {
        "base": {"x": 1, "y": 2},
        "mine": {"x": 5, "y": 2},
        "again": {"x": 1, "y": 2},
        "list": [{"x": 1}, {"x": 2}],
    }
    assert load_yaml("a: &a [1, *a]\n")["a"][1][0] == 1  # a recursive alias: each node checked once
    assert load_yaml("") is None


def test_the_loader_raises_a_yaml_error_with_the_places() -> None:
    with pytest.raises(DuplicateKeyError) as info:
        yaml.load("a: 1\nb:\n  c: 1\n  c: 2\n", Loader=UniqueKeyLoader)
    assert isinstance(info.value, yaml.YAMLError)
    assert (info.value.key, info.value.line, info.value.again, info.value.more) == ("b.c", 3, 4, 0)


def test_text_that_is_not_yaml_says_so() -> None:
    with pytest.raises(ConfigError, match=r"^t\.yaml is not valid YAML: "):
        load_yaml("a: [1\n", "thing", "t.yaml")
    with pytest.raises(ConfigError, match="unhashable key"):
        load_yaml("? [1]\n: 2\n", "thing", "t.yaml")


def test_text_that_is_not_yaml_is_told_in_one_line_with_its_place() -> None:
    """PyYAML's own message spans four lines and names '<unicode string>': ours is one, the file's."""
    with pytest.raises(ConfigError) as info:
        load_yaml("walls: [[0,0],[1\n", "world", "w.yaml")
    assert str(info.value) == (
        "w.yaml is not valid YAML: line 2, column 1: did not find expected ',' or ']' "
        "(while parsing a flow sequence from line 1, column 15)"
    )


def test_a_file_with_a_key_given_twice_is_named(tmp_path: Path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text("a: 1\n\nb: {a: 1}\na: 2\n")
    with pytest.raises(ConfigError) as info:
        read_yaml(path, "calibration file")
    assert str(info.value) == f"invalid calibration file {path}: a: duplicate key on line 4 (first on line 1)"


SHIPPED = [
    *sorted((SRC / "robot" / "presets").glob("*.yaml")),
    *sorted((SRC / "sim" / "worlds").glob("*.yaml")),
    *sorted((SRC / "teleop").glob("*.yaml")),
    *sorted((ROOT / "tests" / "data").glob("*calibration*.yaml")),
]


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_files_without_duplicates_load_as_yaml_safe_load_loads_them(path: Path) -> None:
    assert load_yaml(path.read_text()) == yaml.safe_load(path.read_text())


def test_every_reader_of_yaml_uses_the_one_loader() -> None:
    """Only this module parses YAML: every other reads it through load_yaml or read_yaml."""
    parsing = re.compile(r"yaml\.(safe_|full_|unsafe_)?load(_all)?\(|yaml\.compose|Loader\b")
    offenders = [
        str(path.relative_to(SRC))
        for path in SRC.rglob("*.py")
        if path.name != "config_errors.py" and parsing.search(path.read_text(encoding="utf-8"))
    ]
    assert SHIPPED and offenders == []
