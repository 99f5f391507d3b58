"""The shared robot options: defaults, the sim:// URL they make, outputs checked early."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from omnibot.cliargs import (
    OFF_PATH_HELP,
    add_calibration_option,
    add_off_path_option,
    add_robot_options,
    calibrated_floor,
    check_distinct,
    check_plot,
    check_sim_options,
    off_path_options,
    physics_behind,
    seed_of,
    sim_url,
)
from omnibot.errors import ConfigError
from omnibot.outputs import check_directory, check_writable


def parse(*argv: str, world: str = "empty") -> argparse.Namespace:
    p = argparse.ArgumentParser()
    add_robot_options(p, world=world)
    return p.parse_args(list(argv))


def test_defaults_make_the_simulated_robot() -> None:
    assert sim_url(parse()) == "sim://omni4?seed=1&world=empty"
    assert sim_url(parse("--robot", "omni3", "--seed", "4", "--surface", "carpet", world="room")) == (
        "sim://omni3?seed=4&world=room&surface=carpet"
    )
    assert sim_url(parse("--port", "/dev/ttyUSB0")) == "/dev/ttyUSB0"


def test_a_negative_seed_is_refused() -> None:
    assert seed_of(parse("--seed", "0")) == 0
    with pytest.raises(ConfigError, match="--seed: expected an integer >= 0, got -1"):
        seed_of(parse("--seed", "-1"))
    with pytest.raises(ConfigError, match="--seed"):
        sim_url(parse("--seed", "-1"))


def test_an_output_may_be_no_input_and_no_other_output(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "path.csv").write_text("t,x,y,theta\n")
    with pytest.raises(ConfigError, match=re.escape("--truth: ./path.csv is also PATH: give another file")):
        check_distinct([("--truth", "./path.csv")], [("PATH", tmp_path / "path.csv")])
    (tmp_path / "link.csv").symlink_to(tmp_path / "path.csv")
    with pytest.raises(ConfigError, match=re.escape("--log: link.csv is also PATH")):
        check_distinct([("--log", "link.csv")], [("PATH", "path.csv")])
    with pytest.raises(ConfigError, match=re.escape("a.csv is also --csv")):
        check_distinct([("--csv", "a.csv"), ("--commands-csv", str(tmp_path / "a.csv"))])
    check_distinct([("--out", "omni4")], [("ROBOT", "omni4")])  # a preset's name is no file
    check_distinct([("--csv", "a.csv"), ("--commands-csv", None)], [("PATH", "path.csv")])


def test_a_plot_is_named_with_a_format_matplotlib_writes(tmp_path: Path) -> None:
    check_plot(tmp_path / "p.svg", "--plot")
    check_plot(tmp_path / "p.PNG", "--plot")
    for name in ("p.txt", "p.mcap", "p"):  # matplotlib raised after the run, or wrote p.png unasked
        with pytest.raises(ConfigError, match=rf"--plot: .*{name}: the plot's format is its extension"):
            check_plot(tmp_path / name, "--plot")


def test_simulator_options_are_refused_with_a_port() -> None:
    with pytest.raises(ConfigError, match="--seed, --world shape the simulated robot"):
        check_sim_options(parse("--port", "sim://omni4", "--seed", "2", "--world", "room"))
    check_sim_options(parse("--port", "sim://omni4", "--surface", "wood"), allowed=("surface",))
    with pytest.raises(
        ConfigError, match=r"^--world: --world shapes the simulated robot; with --port put it in a sim:// URL"
    ):
        check_sim_options(parse("--port", "sim://omni4", "--world", "room"))


@pytest.mark.parametrize(
    ("url", "known"),
    [
        (None, True),
        ("sim://omni4?world=room", True),
        ("spy+faults+sim://omni3", True),
        ("uno://omni4?world=room&seed=1", True),  # the emulated UNO drives omnibot's physics
        ("/dev/ttyUSB0", False),
        ("socket://127.0.0.1:4000", False),
        ("spy+/dev/ttyACM0", False),
        ("simulator.local:4000", False),
        ("sim", False),  # a device path, no scheme
    ],
)
def test_a_link_ending_in_the_physics_knows_where_the_robot_stands(url: str | None, known: bool) -> None:
    assert physics_behind(url) is known


def test_outputs_are_checked_before_anything_runs(tmp_path: Path) -> None:
    check_writable(tmp_path / "x.csv", "--path")
    with pytest.raises(ConfigError, match=r"--path: cannot write .*: no directory"):
        check_writable(tmp_path / "new" / "deeper" / "x.csv", "--path")  # a typo is not made
    assert not (tmp_path / "new").exists() and not (tmp_path / "x.csv").exists()
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(ConfigError, match="--path: cannot write"):
        check_writable(blocker / "x.csv", "--path")
    with pytest.raises(ConfigError, match="is a directory"):
        check_writable(tmp_path, "--path")


@pytest.mark.parametrize(
    "argv",
    [
        ["record", "--path", "{missing}/taught.csv"],
        ["record", "--path", "{tmp}/taught.csv", "--log", "{missing}/run.mcap"],
        ["send", "STATUS;", "--log", "{missing}/run.mcap"],
        ["follow", "{tmp}/path.csv", "--report", "{missing}/r.json"],
    ],
)
def test_an_output_in_a_missing_directory_is_refused_before_the_robot_moves(
    argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """record --path, --log, follow's outputs: one line, status 2, before any robot is opened; no
    directory made, no (empty) file left behind."""
    from omnibot.cli import main
    from omnibot.client import session
    from omnibot.control import standard_path, write_path
    from omnibot.navigation import session as nav_session

    def no_robot(*args: object, **kwargs: object) -> None:
        raise AssertionError("a robot was opened")

    monkeypatch.setattr(nav_session, "simulated_client", no_robot)
    monkeypatch.setattr(session, "open_robot", no_robot)
    write_path(standard_path("line", size=0.5), tmp_path / "path.csv")
    missing = tmp_path / "missing"
    assert main([a.format(missing=missing, tmp=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and "no directory" in err and err.count("\n") == 1
    assert not missing.exists() and not (tmp_path / "taught.csv").exists()


def test_the_floor_a_ramp_keeps_within_is_a_calibrations() -> None:
    p = argparse.ArgumentParser()
    add_robot_options(p, world="empty")
    add_calibration_option(p)
    assert calibrated_floor(p.parse_args(["--surface", "carpet", "--calibration", "cal.yaml"])) == "carpet"
    assert calibrated_floor(p.parse_args(["--surface", "carpet"])) is None  # the floor's slip not asked
    assert calibrated_floor(p.parse_args(["--calibration", "cal.yaml"])) is None  # no floor named
    assert calibrated_floor(argparse.Namespace()) is None  # a command without the options


def test_off_path_is_the_followers_bound_unless_given() -> None:
    """``--off-path``: none given leaves the followers' own bound (the one the help names); a distance
    given reaches the follower ``follow`` and ``run --follow`` make; a bad one is refused, named."""
    from omnibot.control import OFF_PATH, standard_path
    from omnibot.navigation import follower_source
    from omnibot.robot import load_robot

    assert OFF_PATH_HELP == OFF_PATH
    p = argparse.ArgumentParser()
    add_off_path_option(p)
    assert off_path_options(p.parse_args([])) == {}
    given = off_path_options(p.parse_args(["--off-path", "1.5"]))
    assert given == {"off_path": 1.5}
    path = standard_path("line", size=0.5)
    robot = load_robot("omni4")
    assert follower_source(robot, path, 0.01).follower.off_path == OFF_PATH
    assert follower_source(robot, path, 0.01, options=given).follower.off_path == 1.5
    with pytest.raises(ConfigError, match="--off-path: expected a positive number"):
        off_path_options(p.parse_args(["--off-path", "-0.2"]))


def test_an_output_directory_is_checked_and_not_made(tmp_path: Path) -> None:
    """What mkdir would say, before the run, and nothing made (the writers make it)."""
    assert check_directory(tmp_path / "a" / "b", "--out") == tmp_path / "a" / "b"
    assert not (tmp_path / "a").exists()
    (tmp_path / "f").write_text("")
    with pytest.raises(ConfigError, match=rf"^--out: cannot make directory {tmp_path}/f: File exists$"):
        check_directory(tmp_path / "f", "--out")
    with pytest.raises(ConfigError, match=rf"^--csv: cannot make directory {tmp_path}/f/x: Not a directory$"):
        check_directory(tmp_path / "f" / "x", "--csv")
