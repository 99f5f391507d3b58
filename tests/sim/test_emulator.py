"""``omnibot sim --pty``: a real process on a pseudo-terminal, opened with pyserial, ended by SIGTERM."""

from __future__ import annotations

import csv
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import serial

from omnibot.cli import main


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
            out = b""
            deadline = time.monotonic() + 10
            while b"IDLE" not in out and time.monotonic() < deadline:
                out += port.read(64)
        # the power-up HELLO may or may not reach us, depending on when the port was opened
        assert out.removeprefix(b"HELLO,2,omni4,4\r\n") == b"HELLO,2,omni4,4\r\nOK\r\nIDLE\r\n"
        time.sleep(0.25)  # the truth file is flushed at least every 100 ms
        rows = list(csv.DictReader(truth.open()))
        assert rows and float(rows[-1]["y"]) > 0.1
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    header = truth.read_text().splitlines()[0]
    assert header == "t,x,y,theta"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["sim", "--pty", "--robot", "omni7"], "unknown robot 'omni7'"),
        (["sim", "--pty", "--surface", "ice"], "unknown surface 'ice'"),
        (["sim", "--pty", "--world", "kitchen"], "kitchen"),
        (["sim"], "add --pty"),
    ],
)
def test_bad_emulator_arguments(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err
