"""``--log`` on a command and ``omnibot log``'s subcommands, through ``main`` as a user runs them."""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.control import standard_path, write_path
from omnibot.logs import topics
from omnibot.logs.reader import LogFile
from omnibot.transport import format_event
from tests.logs.conftest import RecordedRun


@pytest.fixture(scope="module")
def followed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``omnibot follow --log`` of a short line on the simulated omni4 (lockstep)."""
    tmp = tmp_path_factory.mktemp("follow")
    line = tmp / "line.csv"
    write_path(standard_path("line", size=0.4), line)
    log = tmp / "follow.mcap"
    assert main(["follow", str(line), "--log", str(log), "--out", str(tmp / "out")]) == 0
    return log


def test_follow_log_holds_the_run(followed: Path) -> None:
    log = LogFile.open(followed)
    counts: dict[str, int] = {}
    for m in log.messages():
        counts[m.topic] = counts.get(m.topic, 0) + 1
    assert log.cut_short is None
    for topic in (
        topics.ODOM,
        topics.TF,
        topics.IMU,
        topics.JOINT_STATES,
        topics.CMD_VEL,
        topics.TRUTH,
        topics.LINK,
        topics.PROTOCOL,
        topics.ROBOT_DESCRIPTION,
    ):
        assert counts.get(topic, 0) > 0, topic
    assert counts[topics.ODOM] > 50 and counts[topics.CMD_VEL] > 50
    assert log.metadata["omnibot"]["robot"] == "omni4"


def test_log_info(followed: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "info", str(followed)]) == 0
    out = capsys.readouterr().out
    assert "robot     omni4" in out and "odom" in out and "nav_msgs/msg/Odometry" in out
    assert "0 link errors" in out and "telemetry" in out


def test_log_protocol_prints_what_spy_prints(
    recorded: RecordedRun, capsys: pytest.CaptureFixture[str]
) -> None:
    from omnibot.logs import load_run
    from omnibot.transport import SpyEvent

    assert main(["log", "protocol", str(recorded.path)]) == 0
    out = capsys.readouterr().out.splitlines()
    run = load_run(recorded.path)
    t0 = run.link[0][0]
    expected = [line for t, k, d, n in run.link for line in format_event(SpyEvent(t - t0, k, d, n))]  # type: ignore[arg-type]
    assert out == expected
    assert any(" TX " in line and "VEL," in line for line in out)


def test_log_export_csv(recorded: RecordedRun, tmp_path: Path) -> None:
    assert main(["log", "export", str(recorded.path), "--csv", str(tmp_path / "csv")]) == 0
    with (tmp_path / "csv" / "cmd_vel.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(recorded.vels)
    assert [round(float(r["vx"]) * 100) for r in rows] == [v.vx for v in recorded.vels]
    assert (tmp_path / "csv" / "robot.urdf").read_text().startswith("<?xml")
    for name in ("odom.csv", "truth.csv", "joint_states.csv", "imu.csv", "protocol.csv", "link.csv"):
        assert (tmp_path / "csv" / name).stat().st_size > 100, name


def test_log_plot(recorded: RecordedRun, tmp_path: Path) -> None:
    png = tmp_path / "run.png"
    assert main(["log", "plot", str(recorded.path), "-o", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_log_plot_of_a_log_without_powers_warns_of_nothing(followed: Path, tmp_path: Path) -> None:
    """follow drives VEL on the wheel loop (no powers logged): matplotlib's 'No artists with labels'
    warning reached the user's terminal."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["log", "plot", str(followed), "-o", str(tmp_path / "run.png")]) == 0


def test_log_replay_reproduces_live(followed: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "replay", str(followed)]) == 0
    assert "reproduced exactly" in capsys.readouterr().out
    assert main(["log", "replay", str(followed), "--estimator", "encoders"]) == 0
    assert main(["log", "replay", str(followed), "--estimator", "nope"]) == 2


def test_an_output_over_the_log_is_refused(followed: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The recorded log was overwritten by the replay's CSV (exit 0), or the plot failed as a bug."""
    before = followed.read_bytes()
    assert main(["log", "replay", str(followed), "--csv", str(followed)]) == 2
    assert main(["log", "plot", str(followed), "-o", str(followed)]) == 2
    err = capsys.readouterr().err
    assert f"--csv: {followed} is also FILE.mcap" in err and "the plot's format is its extension" in err
    assert "internal error" not in err
    assert followed.read_bytes() == before


def test_bad_files_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "info", str(tmp_path / "none.mcap")]) == 2
    (tmp_path / "x.mcap").write_text("not mcap")
    assert main(["log", "info", str(tmp_path / "x.mcap")]) == 2
    err = capsys.readouterr().err
    assert "no log file" in err and "is not an MCAP file" in err and "Traceback" not in err
    assert main(["send", "--log", str(tmp_path / "no" / "dir" / "x.mcap"), "STATUS"]) == 2  # not made
    assert not (tmp_path / "no").exists()
    assert main(["send", "--log", str(tmp_path), "STATUS"]) == 2
    err = capsys.readouterr().err
    assert "no directory" in err and "is a directory" in err


def test_plot_of_a_log_without_telemetry_says_no_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log, png = tmp_path / "send.mcap", tmp_path / "send.png"
    assert main(["send", "--log", str(log), "STATUS"]) == 0  # the protocol only: no TEL asked for
    capsys.readouterr()
    assert main(["log", "plot", str(log), "-o", str(png)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no data to plot" in err[0], err
    assert not png.exists()  # no empty figure
    assert main(["log", "info", str(log)]) == 0  # info has the protocol to show, and says what is missing
    assert "telemetry: no data" in capsys.readouterr().out


def test_info_of_a_log_without_messages_says_no_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from omnibot.logs import Recorder

    log = tmp_path / "empty.mcap"
    Recorder(log).close()
    assert main(["log", "info", str(log)]) == 1
    assert capsys.readouterr().err.strip() == f"omnibot: error: {log}: no data (no messages)"
