"""The command line: main(argv) called directly."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from omnibot.cli import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["kinematics", "--twist", "1,2"],
            "--twist: expected 3 numbers (comma- or space-separated), got '1,2'",
        ),
        (["kinematics", "--twist", "a,b,c"], "expected 3 numbers"),
        (["kinematics", "--twist", "1,nan,0"], "expected 3 numbers"),
        (["kinematics", "--twist", "1", "2", "3", "4"], "got '1 2 3 4'"),
        (["kinematics", "--wheels", "-1", "1", "1"], "--wheels: expected 4 numbers"),
        (
            ["kinematics", "--twist", "1e308,1e308,0"],
            "--twist: the result overflows (it is not a finite number)",
        ),
        (["kinematics", "--twist", "0", "0", "1e308", "--json"], "--twist: the result overflows"),
        (["kinematics", "--twist", "-1e308", "0", "1e308"], "--twist: the result overflows"),
        (["kinematics", "--robot", "omni5"], "unknown robot 'omni5'; did you mean 'omni4'?"),
        (["robot", "show", "nope.yaml"], "cannot read robot description nope.yaml"),
        (["tour", "--duration", "-1"], "--duration: expected a positive number, got -1"),
        (["send", "STATUS", "--timeout", "-1"], "--timeout: expected a positive number, got -1"),
        (["send", "STATUS", "--idle-timeout", "0"], "--idle-timeout: expected a positive number, got 0"),
        (["console", "--timeout", "nan"], "--timeout: expected a positive number, got nan"),
    ],
)
def test_bad_input_is_a_clear_error(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and message in err
    assert "Traceback" not in err


def test_a_reader_that_goes_away_ends_the_command_quietly() -> None:
    """``omnibot robot show omni4 | head -1``: no BrokenPipeError, status 141 as for SIGPIPE."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "omnibot", "robot", "show", "omni4"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader is gone before the first byte
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.wait(timeout=60) == 141
    assert err == ""


@pytest.mark.parametrize("argv", [["robot", "list"], ["sim", "--pty"]])
def test_a_closed_standard_output_is_a_one_line_error(argv: list[str]) -> None:
    """``omnibot robot list >&-`` failed as a bug (exit 70); ``sim --pty`` served a pty nobody was told of."""
    command = shlex.join([sys.executable, "-m", "omnibot", *argv])
    proc = subprocess.run(
        ["sh", "-c", f"exec {command} >&-"], check=False, capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2, proc.stderr
    assert (
        proc.stderr == "omnibot: error: standard output is closed; give it a file (>/dev/null to discard)\n"
    )


NOT_UTF8 = b"name: caf\xe9\n"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["robot", "show", "{bad}"], "cannot read robot description {bad}: not UTF-8 text (byte 9)"),
        (["sim", "--pty", "--world", "{bad}"], "cannot read world {bad}: not UTF-8 text"),
        (
            ["teleop", "--port", "sim://omni4", "--config", "{bad}"],
            "cannot read teleop config {bad}: not UTF-8",
        ),
        (["follow", "{path}", "--calibration", "{bad}"], "cannot read calibration file {bad}: not UTF-8"),
        (["follow", "{bad}"], "{bad}: not a text (UTF-8) file"),
    ],
)
def test_a_file_that_is_not_utf8_is_a_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    bad = tmp_path / "latin1.yaml"
    bad.write_bytes(NOT_UTF8)
    path = tmp_path / "line.csv"
    path.write_text("t,x,y,theta\n0,0,0,0\n1,0.5,0,0\n", encoding="utf-8")
    names = {"bad": str(bad), "path": str(path)}
    assert main([a.format(**names) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and message.format(**names) in err
    assert err.count("\n") == 1 and "Traceback" not in err


DUPLICATE = "name: a\n\nname: b\n"


@pytest.mark.parametrize(
    ("argv", "what"),
    [
        (["robot", "show", "{bad}"], "robot description"),
        (["sim", "--pty", "--world", "{bad}"], "world"),
        (["teleop", "--port", "sim://omni4", "--config", "{bad}"], "teleop config"),
        (["dashboard", "--http-port", "0", "--config", "{bad}"], "teleop config"),
        (["follow", "{path}", "--calibration", "{bad}"], "calibration file"),
    ],
)
def test_a_file_that_gives_a_key_twice_is_a_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], what: str
) -> None:
    bad = tmp_path / "twice.yaml"
    bad.write_text(DUPLICATE, encoding="utf-8")
    path = tmp_path / "line.csv"
    path.write_text("t,x,y,theta\n0,0,0,0\n1,0.5,0,0\n", encoding="utf-8")
    assert main([a.format(bad=bad, path=path) for a in argv]) == 2
    assert capsys.readouterr().err == (
        f"omnibot: error: invalid {what} {bad}: name: duplicate key on line 3 (first on line 1)\n"
    )


def test_seed_003s_parameter_file_as_printed_is_refused_by_the_command() -> None:
    """``omnibot teleop --config`` with seed 003's file pasted as the seed prints it: exit 2 and one
    line naming the key and both lines, before anything is opened (it used to drive without x)."""
    printed = Path(__file__).resolve().parent / "data" / "seed003_teleop_as_printed.yaml"
    proc = subprocess.run(
        [sys.executable, "-m", "omnibot", "teleop", "--keyboard", "--config", str(printed)],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr == (
        f"omnibot: error: invalid teleop config {printed}: teleop_node.ros__parameters.axis_linear: "
        "duplicate key on line 18 (first on line 11), and 2 more duplicate keys\n"
    )


def test_an_output_folder_that_cannot_be_made_is_a_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "file").write_text("")
    out = tmp_path / "file" / "plots"
    assert main(["tour", "--robot", "omni4", "--duration", "0.1", "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"omnibot: error: --out: cannot make directory {out}: Not a directory\n"


@pytest.mark.parametrize(
    "argv",
    [
        ["map", "--explore", "--port", "sim://omni9", "--duration", "1"],
        ["calibrate", "--quick", "--robot", "omni9"],
        ["demo", "--port", "sim://omni9"],
        ["follow", "{path}", "--port", "sim://omni9"],
    ],
    ids=["map", "calibrate", "demo", "follow"],
)
def test_a_command_that_cannot_start_leaves_no_output_folder(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--out DIR`` is checked before the run and made only when a file goes into it: a command
    refused (here for a robot that does not exist) leaves none."""
    path = tmp_path / "path.csv"
    path.write_text("x,y\n0,0\n1,0\n")
    out = tmp_path / "new" / "out"
    assert main([*(a.format(path=path) for a in argv), "--out", str(out)]) == 2
    assert capsys.readouterr().err.startswith("omnibot: error: ")
    assert not (tmp_path / "new").exists()


def test_the_commands_whose_world_is_the_room_are_the_ones_docs_cli_md_names() -> None:
    """docs/cli.md's --world row names every command that stands the simulated robot in the room
    by default (the others: the empty floor)."""
    from omnibot.apps.subcommands import Commands
    from omnibot.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, Commands))
    sub.fill_all()
    in_room = {name for name, p in sub.choices.items() if p.get_default("default_world") == "room"}
    doc = (Path(__file__).parents[1] / "docs" / "cli.md").read_text(encoding="utf-8")
    row = next(line for line in doc.splitlines() if line.startswith("| `--world NAME"))
    listed = row.rsplit("| `empty`; `room` for ", 1)[1].split(" (they need walls)")[0]
    assert set(re.findall(r"`([a-z0-9]+)`", listed)) == in_room


def test_a_full_standard_output_is_a_one_line_error() -> None:
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [sys.executable, "-m", "omnibot", "robot", "urdf", "omni4"],
            check=False,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
        )
    assert proc.returncode == 2
    assert proc.stderr == "omnibot: error: cannot write the output: No space left on device\n"


WALLED = "name: walled\nwalls:\n  - {shape: rectangle, min: [-0.01, -0.01], max: [3.0, 3.0]}\n"
"""A world without a start of its own whose wall runs through the origin, where the robot would stand."""


@pytest.mark.parametrize(
    "argv",
    [
        ["record", "--path", "{tmp}/r.csv", "--world", "{walled}"],
        ["follow", "{path}", "--world", "{walled}"],
        ["run", "--follow", "{path}", "--world", "{walled}", "--duration", "1"],
        ["calibrate", "--world", "{walled}", "--out", "{tmp}/cal"],
        ["send", "STATUS;", "--port", "sim://omni4?world={walled}"],
        ["demo", "--world", "{walled}", "--out", "{tmp}/demo"],
        ["demo", "--robot", "{tmp}/bad.yaml", "--out", "{tmp}/demo"],
        ["send", "STATUS;", "--port", "{tmp}/no-such-port"],
        ["send", "STATUS;", "--port", "sim://omni4", "--robot", "omni3"],
        ["follow", "{tmp}/missing.csv"],
    ],
)
def test_a_command_that_could_not_start_exits_2_with_one_line(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """docs/cli.md: 2 it could not start (bad arguments or files, the wrong robot, a link that cannot be
    opened). A start pose in a wall (SimulationError) and an emulator that did not start (LinkError)
    were failed runs, exit 1."""
    from omnibot.control import standard_path, write_path

    (tmp_path / "walled.yaml").write_text(WALLED)
    (tmp_path / "bad.yaml").write_text("name: bad\nwheels: 3\n")
    write_path(standard_path("line", size=0.5), tmp_path / "path.csv")
    names = {"tmp": tmp_path, "walled": tmp_path / "walled.yaml", "path": tmp_path / "path.csv"}
    assert main([a.format(**names) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("omnibot: error: ") and err.count("\n") == 1, err


def test_send_takes_options_among_its_commands_and_keeps_their_order(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["send", "STATUS;", "--port", "sim://omni4", "MOVE,2,40,0,0;", "--timeout", "2", "STOP;"]
    assert main(argv) == 0
    sent = [line for line in capsys.readouterr().out.splitlines() if line.startswith("-> ")]
    assert sent == ["-> STATUS", "-> MOVE,2,40,0,0", "-> STOP"]
    with pytest.raises(SystemExit) as exit_:
        main(["send", "STATUS;", "--prot", "sim://omni4"])
    assert exit_.value.code == 2
    assert "unrecognized arguments: --prot sim://omni4" in capsys.readouterr().err
