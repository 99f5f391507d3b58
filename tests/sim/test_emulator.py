"""``omnibot sim --pty``: a real process on a pseudo-terminal, opened with pyserial, ended by SIGTERM."""

from __future__ import annotations

import csv
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import serial

from omnibot.cli import main
from omnibot.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.sim.emulator import PARENT_ENV, spawn_pty_emulator


def read_port(port: serial.Serial, marker: bytes, timeout: float = 30.0) -> bytes:
    """What the emulator's pty gives until ``marker`` arrives or ``timeout`` s of wall time pass."""
    out = b""
    deadline = time.monotonic() + timeout
    while marker not in out and time.monotonic() < deadline:
        out += port.read(64)
    return out


def test_pty_emulator_serves_the_firmware_and_writes_truth(tmp_path: Path) -> None:
    truth = tmp_path / "truth.csv"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "omnibot",
            "sim",
            "--pty",
            "--robot",
            "omni4",
            "--seed",
            "1",
            "--truth",
            str(truth),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        path = proc.stdout.readline().strip()
        assert path.startswith("/dev/")
        with serial.Serial(path, 115200, timeout=0.2) as port:
            port.write(b"HELLO;MOVE,20,40,90,0;")
            out = read_port(port, b"IDLE")
        # the power-up HELLO reaches us whole, in part or not at all, depending on when the port was
        # opened (opening it flushes what the pty holds, as a serial port's open does)
        replies = b"HELLO,2,omni4,4\r\nOK\r\nIDLE\r\n"
        assert out.endswith(replies), out
        assert b"HELLO,2,omni4,4\r\n".endswith(out[: len(out) - len(replies)]), out
        # the truth file is flushed at least every 100 ms of the emulator's time: read it until the
        # move is there (a loaded machine runs the emulator late)
        deadline = time.monotonic() + 30
        rows: list[dict[str, str]] = []
        while not (rows and float(rows[-1]["y"]) > 0.1) and time.monotonic() < deadline:
            time.sleep(0.05)
            rows = list(csv.DictReader(truth.open()))
        assert rows and float(rows[-1]["y"]) > 0.1
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    header = truth.read_text().splitlines()[0]
    assert header == "t,x,y,theta"


def test_sighup_ends_the_emulator_cleanly(tmp_path: Path) -> None:
    """Its terminal closing (SIGHUP) ends it as SIGTERM does: status 0, the truth file whole."""
    if signal.getsignal(signal.SIGHUP) == signal.SIG_IGN:
        pytest.skip("the suite runs under nohup: the emulator inherits an ignored SIGHUP and runs on")
    truth = tmp_path / "truth.csv"
    argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--baud", "0", "--truth", str(truth)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().startswith("/dev/")
    finally:
        proc.send_signal(signal.SIGHUP)
        _, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert truth.read_text().splitlines()[0] == "t,x,y,theta"


def _alive(pid: int) -> bool:
    """Whether ``pid`` is a running (not zombie) process (Linux /proc)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_an_emulator_whose_parent_was_killed_ends_by_itself() -> None:
    """``omnibot demo`` killed by SIGKILL cannot end its emulator: it used to serve nobody for ever."""
    script = (
        "import time\nfrom omnibot.sim.emulator import spawn_pty_emulator\n"
        "with spawn_pty_emulator('omni4') as path:\n    print(path, flush=True)\n    time.sleep(600)\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        assert parent.stdout.readline().startswith("/dev/")
        children = Path(f"/proc/{parent.pid}/task/{parent.pid}/children").read_text().split()
        assert len(children) == 1
        emulator = int(children[0])
    finally:
        parent.kill()
        parent.wait()
        if parent.stdout is not None:
            parent.stdout.close()
    deadline = time.monotonic() + 30
    while _alive(emulator) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = _alive(emulator)
    if left:  # this test's own grandchild
        os.kill(emulator, signal.SIGKILL)
    assert not left, "the emulator outlived the process that started it"


def test_an_emulator_whose_named_parent_is_not_its_parent_ends() -> None:
    env = {**os.environ, PARENT_ENV: "1"}  # its parent is this test, not PID 1: as if orphaned
    argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--baud", "0"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err


def test_a_fleet_on_one_pty_per_robot_shares_one_world() -> None:
    """Two robots in one room, each on its own pty: the omni4's sonar sees the omni3 in front of it."""
    argv = [sys.executable, "-m", "omnibot", "sim", "--pty", "--world", "room", "--baud", "0"]
    argv += ["--robot", "omni4?name=a&pose=1,1,0", "--robot", "omni3?name=b&pose=2.6,1.05,0&seed=7"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        lines = [proc.stdout.readline().split() for _ in range(2)]
        assert [name for name, _ in lines] == ["a", "b"]
        (_, path_a), (_, path_b) = lines
        with serial.Serial(path_a, timeout=0.2) as a, serial.Serial(path_b, timeout=0.2) as b:
            a.write(b"HELLO;SONAR,1,100,1,500,0;")
            b.write(b"HELLO;")
            out_a = out_b = b""
            deadline = time.monotonic() + 30  # generous: a loaded machine runs the emulator late
            while not (re.search(rb"RANGE,1,\d+\r\n", out_a) and b"omni3,3\r\n" in out_b):
                assert time.monotonic() < deadline, (out_a, out_b)
                out_a += a.read(64)
                out_b += b.read(64)
        assert b"HELLO,2,omni4,4\r\nOK\r\n" in out_a and b"HELLO,2,omni3,3\r\n" in out_b
        cm = int(out_a.split(b"RANGE,1,")[1].split(b"\r\n")[0])
        expected = math.hypot(2.6 - 1.1, 0.05) - 0.32  # a's sonar on its front face; b a 0.32 m circle
        assert cm == pytest.approx(expected * 100, abs=2)
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["sim", "--pty", "--robot", "omni4", "--robot", "omni3"],
            "--robot: robot 'r2' at (0, 0, 0 deg) overlaps",
        ),
        (["sim", "--pty", "--robot", "omni4", "--robot", "omni4?nmae=b"], "unknown option 'nmae' in --robot"),
        (["sim", "--pty", "--robot", "omni4", "--robot", "omni4?pose=1,1"], "expected pose=X,Y,THETA"),
        (["sim", "--pty", "--robot", "omni4?pose=1,1"], "--robot: expected pose=X,Y,THETA"),  # a fleet of one
        (
            ["sim", "--pty", "--robot", "omni4", "--robot", "omni4?name=r1&pose=1,0,0"],
            "fleet already has a robot named 'r1'",
        ),
        (
            ["sim", "--pty", "--robot", "omni4", "--robot", "omni4?pose=1,0,0", "--truth", "t.csv"],
            "--truth records",
        ),
        (["sim", "--pty", "--robot", "omni7"], "unknown robot 'omni7'"),
        (["sim", "--pty", "--surface", "ice"], "unknown surface 'ice'"),
        (["sim", "--pty", "--world", "kitchen"], "kitchen"),
        (["sim"], "add --pty"),
    ],
)
def test_bad_emulator_arguments(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def _children_of(pid: int) -> list[int]:
    """The child processes of ``pid`` (from each of its threads' ``children`` list)."""
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        found += [int(child) for child in (task / "children").read_text().split()]
    return found


def test_a_first_start_with_no_numba_cache_answers_while_the_kernels_compile(tmp_path: Path) -> None:
    """A fresh install (what `make demo` on a new clone does): the emulator answers at once, on the
    kernels' Python twins, while a process of its own compiles them (tests/sim/test_jit.py follows a
    cold start to its switch; this test ends the compiling process instead of waiting for it)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    compiling: list[int] = []
    with subprocess.Popen(
        [sys.executable, "-m", "omnibot", "sim", "--pty"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    ) as proc:
        try:
            assert proc.stdout is not None
            path = proc.stdout.readline().strip()
            assert path.startswith("/dev/"), proc.stderr.read() if proc.stderr else ""
            with RobotClient.open(path, timeout=10.0) as client:
                hello = client.hello()
                deadline = time.monotonic() + 30
                while not compiling and time.monotonic() < deadline:
                    compiling += _children_of(proc.pid)
                assert len(compiling) == 1 and _alive(compiling[0])  # still compiling, 20 s of CPU
            assert (hello.name, hello.motors) == ("omni4", 4)
        finally:
            proc.send_signal(signal.SIGTERM)
            _, err = proc.communicate(timeout=10)
            for pid in compiling:  # in a session of its own, it would finish the cache: not here
                os.kill(pid, signal.SIGKILL)
    assert proc.returncode == 0 and "Traceback" not in err


def test_a_bad_baud_rate_is_refused_before_the_pty_appears(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim", "--pty", "--baud", "-5"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "--baud: expected a baud rate >= 0" in captured.err


def test_an_unwritable_truth_file_is_refused_before_the_pty_appears(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["sim", "--pty", "--truth", str(tmp_path / "missing" / "truth.csv")]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "--truth: cannot write" in captured.err


def test_a_slow_start_is_announced_and_a_stuck_one_ends_in_a_clear_error(tmp_path: Path) -> None:
    """A child that prints no device path (here stuck opening its truth file, a FIFO nobody reads):
    the wait is announced after one second, and a start that takes longer than allowed is a
    ConfigError: the command could not start (exit status 2; the child is ended, not left behind)."""
    stuck_truth = tmp_path / "truth.csv"
    os.mkfifo(stuck_truth)
    notices: list[str] = []
    stuck = pytest.raises(ConfigError, match=r"printed no device path within 1\.5 s")
    with stuck, spawn_pty_emulator("omni4", truth=stuck_truth, notice=notices.append, start_timeout=1.5):
        pass
    assert notices == ["starting the simulated omni4 (omnibot sim --pty, up to 1.5 s)..."]


def test_a_child_that_fails_to_start_reports_its_error() -> None:
    failed = pytest.raises(ConfigError, match="did not start: unknown robot 'omni7'")
    with failed, spawn_pty_emulator("omni7"):
        pass


def test_the_spawned_emulator_runs_in_a_session_of_its_own() -> None:
    """A session (a scheduling autogroup on Linux) of its own, as if started from another terminal:
    the caller's busy processes do not take its CPU share, and it answers on its pty."""
    pids: list[int] = []
    with spawn_pty_emulator("omni4", seed=1, started=pids.append) as path:
        (pid,) = pids
        assert os.getsid(pid) == pid != os.getsid(0)
        with serial.Serial(path, 115200, timeout=0.2) as port:
            port.write(b"STATUS;")
            out = read_port(port, b"STATUS,")
        assert b"STATUS," in out
