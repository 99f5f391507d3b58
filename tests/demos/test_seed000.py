"""The main job: seed 000's examples through the whole stack, judged against ground truth."""

from __future__ import annotations

import re
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.demos import seed000
from omnibot.demos.seed000 import run_demo, with_world


def achieved(report: str, example: int) -> str:
    block = report.split(f"\n{example}. ", 1)[1]
    return re.search(r"achieved:\s+(.*)", block).group(1)  # type: ignore[union-attr]


def number(text: str, pattern: str) -> float:
    return float(re.search(pattern, text).group(1))  # type: ignore[union-attr]


class CountingBar:
    """Stands in for the terminal's progress bar."""

    def __init__(self) -> None:
        self.n, self.postfixes = 0, list[str]()

    def update(self, n: float | None = 1) -> None:
        self.n += int(n or 0)

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        self.postfixes.append(s)


def test_demo_in_lockstep_meets_the_seed_examples(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    bars: list[tuple[float | None, CountingBar]] = []

    @contextmanager
    def progress_bar(desc: str, total: float | None, unit: str = "it") -> Iterator[CountingBar]:
        bars.append((total, CountingBar()))
        yield bars[-1][1]

    monkeypatch.setattr(seed000, "progress_bar", progress_bar)
    out = tmp_path / "out"  # made when the demo writes its files
    report, ok = run_demo("sim://omni4?world=room&seed=1", "omni4", out)
    assert ok
    [(total, bar)] = bars  # the bar counts the examples really run, each named while it runs
    assert total == bar.n == len(bar.postfixes) == 5 and bar.postfixes[0] == "circle, heading held"
    circle = achieved(report, 1)
    assert number(circle, r"ends ([\d.]+) cm") < 5.0
    assert abs(number(circle, r"heading ([+-][\d.]+) deg")) < 3.0
    seed_spin = achieved(report, 2)
    assert 30 < number(seed_spin, r"path bend \+?([+-]?[\d.]+) deg") < 120  # seed's C=-40 bends left
    straight = achieved(report, 3)
    assert abs(number(straight, r"path bend ([+-][\d.]+) deg")) < 15
    turned = number(straight, r"body turned ([+-][\d.]+) deg")
    assert -340 < turned < -260  # -200 deg/s for 1.5 s
    # the commanded line gives the same quantity in the same unit: degrees of body turn
    commanded = re.search(r"commanded: (.*)", report.split("\n3. ", 1)[1]).group(1)  # type: ignore[union-attr]
    assert abs(number(commanded, r"body turns ([+-][\d.]+) deg ") - turned) < 40
    rotate = achieved(report, 4)
    assert abs(abs(number(rotate, r"heading ([+-]?[\d.]+) deg")) - 180) < 8
    approach = achieved(report, 5)
    assert approach.startswith("stopped")
    # front 10 cm ahead of the centre; the stop allows for a wall met at a slant, so it stops early
    assert 15 < number(approach, r"centre ([\d.]+) cm from the wall") < 60
    assert (out / "demo_trajectory.png").stat().st_size > 20_000
    assert (out / "demo_truth.csv").read_text().startswith("t,x,y,theta\n")


def test_demo_command_through_the_pty_emulator(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "via client -> text protocol -> pty (115200 baud) -> firmware -> simulator" in out
    assert achieved(out, 5).startswith("stopped")
    assert abs(number(achieved(out, 3), r"path bend ([+-][\d.]+) deg")) < 15


def test_demo_bad_port_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--port", "bogus://x", "--out", str(tmp_path)]) == 2
    assert "omnibot: error:" in capsys.readouterr().err


def test_demo_on_a_sim_port_without_a_world_has_its_wall_and_turns_the_short_way(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """sim://omni4 names no world: the demo's own (the room) is used, so the rotation faces a wall
    and the sonar approach ends in its emergency stop; the rotation is never more than half a turn,
    and the heading it aims at is printed wrapped (the spins before leave it at -500 degrees)."""
    assert main(["demo", "--port", "sim://omni4", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "sim://omni4?world=room" in out
    line = next(x for x in out.splitlines() if "rotate to face the wall" in x)
    turn = float(line.split("ROTATE,")[1].split(",")[0])
    assert abs(turn) <= 180
    aim = out.split(line)[1].splitlines()[1]
    assert "commanded: heading" in aim and -180 <= float(aim.split("heading ")[1].split(" deg")[0]) <= 180


def test_a_sim_port_keeps_the_world_it_names() -> None:
    assert with_world("sim://omni4", "room") == "sim://omni4?world=room"
    assert with_world("spy+sim://omni4?seed=2", "room") == "spy+sim://omni4?seed=2&world=room"
    assert with_world("sim://omni4?world=empty", "room") == "sim://omni4?world=empty"
    assert with_world("sim://omni4?fleet=a", "room") == "sim://omni4?fleet=a"
    assert with_world("/dev/ttyUSB0", "room") == "/dev/ttyUSB0"


def test_demo_in_a_world_without_walls_says_the_example_needs_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    main(["demo", "--port", "sim://omni4?world=empty", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "no wall known; facing a wall needs a world with walls" in out
    line = next(x for x in out.splitlines() if "rotate to face the wall" in x)
    assert abs(float(line.split("ROTATE,")[1].split(",")[0])) <= 180


def test_the_pty_demos_log_holds_the_emulators_truth_on_the_links_clock(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --log`` on the pty emulator: the truth of the emulator's file goes into the log (it had
    none: the truth was only in demo_truth.csv), each row at the link time the telemetry places the
    controller's clock at, so the truth starts moving when the estimate does."""
    from omnibot.logs import load_run

    log = tmp_path / "demo.mcap"
    assert main(["demo", "--out", str(tmp_path), "--log", str(log)]) == 0
    capsys.readouterr()
    run = load_run(log)
    rows = (tmp_path / "demo_truth.csv").read_text().splitlines()[1:]
    assert len(run.truth) == len(rows) > 500  # 10 ms apart
    assert [round(r[1], 4) for r in run.truth[::100]] == [float(r.split(",")[1]) for r in rows[::100]]

    def moved(track: Sequence[tuple[float, ...]], metres: float) -> float:
        x0, y0 = track[0][1:3]
        return next(t for t, x, y, *_ in track if (x - x0) ** 2 + (y - y0) ** 2 > metres**2)

    # the odometry has not drifted yet when the robot first moves 5 cm: the two agree on when
    assert abs(moved(run.truth, 0.05) - moved(run.estimate, 0.05)) < 0.05
