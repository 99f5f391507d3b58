"""The UNO firmware in simavr against the MicroPython firmware: same replies, same powers."""

from __future__ import annotations

import os
import re
import time

import pytest

from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes, linecheck
from omnibot.protocol.frame import encode_message
from omnibot.robot import load_robot
from omnibot.uno.emulator import UnoEmulator, UnoError
from tests.firmware.fakehal import FakeHAL

from .conftest import BUILD_IDS, BUILDS, Port, start


def checked(command: str, tag: str | None = None) -> str:
    """``command`` with a tag (if given) and its CRC-16 check suffix."""
    data = command.encode()
    return (data + linecheck.suffix(data, None if tag is None else tag.encode(), True)).decode()


# Command scripts; each line is sent as one write and answered line by line.
SCRIPT = [
    "STATUS",
    "MOVE,30000,40,0,0;STATUS;STOP",
    "MOVE,30000,-40,30,0;STATUS;STOP",
    "MOVE,-30000,60,135,50;STATUS;STOP",
    "MOVE,30000,70,-100,-99;STATUS;STOP",
    "ROTATE,30000,90;STATUS;STOP",
    "ROTATE,-30000,400;STATUS;STOP",
    "VEL,20,-30,45,1000;STATUS;STOP",
    "VEL,0,0,-200,1000;STATUS;STOP",
    # an open-loop VEL: a wheel below the K_l tables' dead band is set to 0, WARN 12 once a VEL stream
    "VEL,20,10,0,500;STATUS;VEL,20,10,0,500;VEL,5,0,0,500;STATUS;VEL,0,10,0,500;STATUS;STOP",
    "MODE,2;VEL,20,10,0,500;STOP;MODE,0",  # the closed loop drives the slow wheels instead
    "POWER,1000,10,-20,30,-255;STATUS;STOP",
    "CAL,0,0,0,2000;CAL,1,0,0,1100;CAL,10,-1,0,0;CAL,10,0,40,1400;CAL,10,1,255,1050;CAL,11,-1,45,0",
    "CAL,11,0,40,1100;CAL,11,1,255,1000;CAL,12,-2,0,0;CAL,3,0,0,385;CAL,20,0,60,1050;CAL,20,1,200,980",
    "MOVE,30000,40,20,0;STATUS;STOP",
    "MOVE,30000,80,70,10;STATUS;STOP",
    # a third K_l curve at 90 (a mecanum base folds from its x axis: sideways and 135 = 45 mirrored)
    "CAL,12,-1,90,0;CAL,12,0,40,1600;MOVE,30000,40,90,0;STATUS;STOP;MOVE,30000,40,135,0;STATUS;STOP",
    "MOVE,30000,40,-60,0;STATUS;STOP;CAL,12,-2,0,0",
    "VEL,30,4,0,500;STATUS;VEL,30,1,0,500;STATUS;STOP",  # the dead band of the tables just written
    "CAL,12,-1,40,0;CAL,11,-1,50,0;CAL,10,5,3,4;CAL,21,0,0,0;CAL,6,0,-1,0",
    # roller drag (at the encoders' origin: phase 0) with its coast table
    "CAL,4,0,0,150;CAL,4,1,0,-80;CAL,5,2,0,90;CAL,4,3,0,40;CAL,6,0,30,200;CAL,6,1,80,-100",
    "MOVE,100,40,0,0;STATUS;STOP",
    "MOVE,30000,60,60,0;STATUS;STOP",
    "VEL,-30,20,0,1000;STATUS;STOP",
    # the motor map's speed terms (CAL table 7), a motor beyond the robot's, a course beyond 90
    "CAL,7,1,0,1000;CAL,7,3,0,-500;MOVE,30000,40,0,0;STATUS;STOP;VEL,-30,20,0,1000;STATUS;STOP",
    "CAL,7,4,0,1;CAL,7,0,2,1;CAL,11,-1,91,0;CAL,7,1,0,0;CAL,7,3,0,0;MOVE,30000,40,0,0;STATUS;STOP",
    "MOVE,500,40,0,0;MOVE,1,29,0,0;DELTA,1000,0,0,0,0;ROTATE,90,0;POWER,0,1,1,1,1;VEL,0,0,0,0",
    "SONAR,2,60,0,0,0;SONAR,1,59,0,0,0;TELEM,5,1;TELEM,100,256;MODE,64;HELLO,2;HELLO,5,1",
    "FOO;MOVE,x,1,1,1;move , 1 , +40 , 0 , -0;STATUS,1;MOVE,40000,1,1,1;" + "9" * 70,
    "STOP;STATUS",
    # the sonar stop's guard: uncovered travel refused with MODE bit 3 (ERROR 41), or limited (WARN 15)
    "SONAR,1,60,0,0,25;MODE,8;MOVE,30000,40,90,0;VEL,0,30,0,100;MOVE,30000,40,0,0;STATUS;STOP",
    "MODE,0;MOVE,30000,100,90,0;STATUS;STOP;SONAR,1,0,0,0,0;MOVE,30000,100,90,0;STATUS;STOP",
    # a motion that turns uncovered while running is stopped (WARN 16)
    "SONAR,1,60,0,0,25;MODE,8;MOVE,30000,40,0,0;DELTA,0,0,90,0,1;STATUS;MODE,0;SONAR,1,0,0,0,0;STOP",
    # separators (VT and FF are not spaces), syntax before ranges, INF tokens where allowed
    "MOVE,\x0b1,40,0,0;\x0b;MOVE,1,40,0,0\x0c;\t ;MOVE,99999,x,0,0;MOVE,99999,40,0,0;SONAR,1,inf,0,0,0",
    "MOVE,inf,60,0,0;STATUS;STOP;ROTATE,-Inf,90;STATUS;STOP;ROTATE,+INF,90;STOP;MOVE,1,INF,0,0",
    "DELTA,0,0,0,0,INF;STOP;DELTA,0,0,0,0,-INF;DELTA,0,0,0,inf,0;POWER,INF,1,1,1,1;MOVE,INFX,40,0,0",
    # tags and checks: echoed in the reply; a bad check is ERROR 26 untagged; not a suffix: refused
    "HELLO#1;" + checked("HELLO", "2") + ";" + checked("STATUS") + ";MOVE,2,40,0,0#17;STOP#9999",
    checked("MOVE,30000,40,0,0", "3") + ";" + checked("STATUS", "4") + ";" + checked("STOP", "5"),
    "STATUS*0000;STATUS#1*0000;FOO#6;MOVE,1#7;STATUS#12345;STATUS#;STATUS*12G4;#5;" + checked("", "8"),
    checked("MOVE,99999,40,0,0", "33") + ";" + checked("VEL,1,1,1,0") + ";" + checked("DELTA,1,1") + ";",
    "STOP;STATUS",
    # sequenced text (MODE bit 5): a duplicate answered from the kept reply (DELTA once, ERROR 35
    # again), one out of order (STATUS#8 before #7) dropped unanswered, STOP and MODE taken anyway
    ";".join([checked("MODE,48", "5"), *[checked("DELTA,400,40,0,0,0", "6")] * 2]),
    ";".join([checked("STATUS", "8"), checked("STATUS", "7"), *[checked("DELTA,0,0,0,0,-1", "8")] * 2]),
    ";".join([checked("STOP", "20"), checked("MODE,0", "21")]),
]
# What the Mega runs beyond the UNO (docs/uno.md, "The Arduino Mega 2560"), against the same firmware.
MEGA_SCRIPT = [
    # protocol versions 3 and 4: the highest shared one answers; VEL takes 4, 5 or 7 parameters
    "HELLO,2,3;HELLO,2,3,4;HELLO,4,5;HELLO;HELLO,3",
    "VEL,30,0,45,100,140,-20,300;STOP;VEL,10,0,0,100,140;STOP;VEL,10,0,0,100,1,2;VEL,1,2,3,4,5,6,7,8",
    # the closed loop feeds a VEL's planned acceleration forward: the second VEL's powers hold it
    # (the speed loop's correction is still 0 then, a control period is 10 ms)
    "MODE,2;VEL,30,40,0,200;VEL,30,40,0,200,150;STATUS;STOP;MODE,0",
    "MODE,2;VEL,30,40,0,200;VEL,30,40,0,200,-150;STATUS;STOP;MODE,0",
    "MODE,2;VEL,30,0,45,200;VEL,30,0,45,200,140,-20,300;STATUS;STOP;MODE,0",
    "MODE,2;VEL,0,0,90,200;VEL,0,0,90,200,0,0,-400;STATUS;STOP;MODE,0",
    "VEL,30,40,0,200;VEL,30,40,0,200,150;STATUS;STOP",  # open loop: A changes nothing
    # the calibrated reach (CAL table 8): an open-loop MOVE asked faster runs at it, WARN 18
    "CAL,8,0,0,60;CAL,8,1,45,40;MOVE,30000,80,0,0;STATUS;STOP;MOVE,30000,80,30,0;STATUS;STOP",
    "MOVE,30000,50,-170,0;STATUS;STOP;MOVE,30000,80,0,0;DELTA,0,0,30,0,1;STATUS;STOP",
    "MOVE,30000,30,45,0;STATUS;STOP;CAL,8,0,91,50;CAL,8,0,-1,50;CAL,8,0,0,-5;CAL,8,2,0,50;CAL,8,1,0,50",
    "MODE,2;MOVE,30000,80,30,0;STATUS;STOP;MODE,0;CAL,8,0,0,0;MOVE,30000,80,30,0;STATUS;STOP",
    # the floor's creep for the closed-loop landing (CAL table 9): roll, combined, scale, ramp; bad ones
    "CAL,9,0,0,500;CAL,9,1,0,3300;CAL,9,2,0,10500;CAL,9,3,0,770;CAL,9,2,0,4000;CAL,9,3,0,-1;CAL,9,4,0,1;"
    "CAL,9,0,1,5;CAL,9,1,0,-1",
    # MODE 2: a MOVE lands, its plan starting at the crawl (2 cm/s of the 60 asked): its first powers
    "MODE,2;MOVE,100,60,0,0;MOVE,100,60,0,0;STATUS;STOP;CAL,9,0,0,0;CAL,9,1,0,0;CAL,9,2,0,10000;CAL,9,3,0,0;MODE,0",
]
AFTER_IDLE = ("IDLE", f"WARN,{codes.W_SHORT},{codes.TEXTS[codes.W_SHORT]}")
"""What follows a motion's end, which the reference (time standing still) never reaches: IDLE, and on
the Mega a MOVE's progress check (WARN 17: the emulated wheels stand still)."""
POWERS = re.compile(r"POWER((?:,-?\d+)+);")


def reference(robot: str, script: list[str] = SCRIPT) -> list[list[str]]:
    """The MicroPython firmware's replies to each line of ``script`` (time stands still), without the
    IDLE events: on the UNO time runs, and a short MOVE may end between two replies (AFTER_IDLE)."""
    config = build_config(load_robot(robot))
    hal = FakeHAL(config["motors"], len(config["sonar_period_min_ms"]))
    ctrl = Controller(hal, config)
    hal.lines()
    out: list[list[str]] = []
    for text in script:
        hal.send(text + "\n")
        ctrl.poll()
        out.append([line for line in hal.lines() if line != "IDLE"])
    return out


def split_powers(line: str) -> tuple[str, list[int]]:
    m = POWERS.search(line)
    if not m:
        return line, []
    return line[: m.start(1)] + line[m.end(1) :], [int(v) for v in m.group(1)[1:].split(",")]


def test_same_replies_and_powers_as_the_micropython_firmware(uno: tuple[UnoEmulator, Port]) -> None:
    same_as_micropython(*uno, SCRIPT)


@pytest.mark.parametrize("robot", ["omni4", "mecanum4"])
def test_the_mega_runs_versions_3_and_4_and_the_reach_as_the_micropython_firmware(robot: str) -> None:
    emu, port = start(robot, range_cm=100, board="mega")
    try:
        same_as_micropython(emu, port, MEGA_SCRIPT)
    finally:
        port.close()
        emu.close()


def same_as_micropython(emu: UnoEmulator, port: Port, script: list[str]) -> None:
    """Each line of ``script`` gets the MicroPython firmware's replies, powers within one count."""
    expected: list[str] = []
    got: list[str] = []
    for text, replies in zip(script, reference(emu.robot, script), strict=True):
        expected += replies
        got += port.ask(text, len(replies), skip=AFTER_IDLE)
    for g, e in zip(got, expected, strict=True):
        g_text, g_powers = split_powers(g)
        e_text, e_powers = split_powers(e)
        assert g_text == e_text
        # single-precision floats and round-half-away-from-zero against Python's doubles and round()
        assert all(abs(a - b) <= 1 for a, b in zip(g_powers, e_powers, strict=True)), (g, e)


@pytest.mark.parametrize("board", ["uno", "mega"])
def test_calibration_survives_a_power_cycle(board: str) -> None:
    emu, port = start("omni4", board=board)
    try:
        before = port.ask("MOVE,30000,40,30,0;STATUS;STOP", 4)[1]
        assert port.ask("CAL,0,0,0,2000;MOVE,30000,40,30,0;STATUS;STOP", 5)[2] != before
        changed = port.ask("MOVE,30000,40,30,0;STATUS;STOP", 4)[1]
        emu.command("reset")
        assert port.lines(1) == [f"HELLO,{codes.PROTOCOL_VERSION},omni4,4"]
        assert port.ask("MOVE,30000,40,30,0;STATUS;STOP", 4)[1] == changed  # K from the EEPROM
        port.ask("CAL,0,0,0,1449")  # the preset's K again
    finally:
        port.close()
        emu.close()


@pytest.mark.parametrize(("board", "ram"), [("uno", 2048), ("mega", 8192)])
def test_static_ram_and_measured_stack_fit(board: str, ram: int) -> None:
    emu, port = start("omni4", range_cm=100, board=board)
    try:
        port.ask("SONAR,1,60,0,500,20;TELEM,10,255", 2)  # the sonar stop armed: the guard runs
        port.write("MOVE,2,40,0,0;DELTA,0,0,10,0,10;VEL,30,30,100,200\n")
        port.lines(3)
        time.sleep(0.3)
        port.ask("STOP;TELEM,0,0;SONAR,1,0,0,0,0", 3)
        # and a binary session: frames in and out, TEL frames, events
        port.ask("MODE,4")
        for k, frame in enumerate(
            [
                encode_message(codes.HELLO, 1, [codes.PROTOCOL_VERSION], sync=True),
                encode_message(codes.TELEM, 2, [10, 255]),
                encode_message(codes.MOVE, 3, [10, 40, 30, 20]),
                encode_message(codes.STATUS, 4),
                encode_message(codes.TELEM, 5, [0, 0]),
            ]
        ):
            os.write(port.fd, frame)
            time.sleep(0.05 if k != 2 else 0.3)
    finally:
        port.close()
        emu.close()
    report = (emu.elf.parent / "size.txt").read_text()
    static = int(re.search(rf"static RAM (\d+) of {ram}", report).group(1))  # type: ignore[union-attr]
    assert static <= 0.75 * ram
    assert emu.stack_bytes is not None and 0 < emu.stack_bytes < ram - static - 64, (static, emu.stack_bytes)


@pytest.mark.parametrize(("robot", "board"), BUILDS, ids=BUILD_IDS)
def test_hello_names_the_robot(robot: str, board: str) -> None:
    emu, port = start(robot, board=board)
    try:
        assert port.ask("HELLO") == [f"HELLO,{codes.PROTOCOL_VERSION},{robot},4"]
    finally:
        port.close()
        emu.close()


@pytest.mark.parametrize("robot", ["omni4", "mecanum4"])
def test_the_uno_speaks_version_2_only_and_refuses_vels_acceleration(robot: str) -> None:
    """It has no room for VEL's planned acceleration (docs/uno.md): asked for 2 and 3 it agrees on
    2, so a host sends no A, and a VEL with A typed by hand is refused, never half read; nor for
    the reach: CAL table 8 is ERROR 38 (the Mega takes both, MEGA_SCRIPT)."""
    emu, port = start(robot)
    try:
        assert port.ask("HELLO,2,3") == [f"HELLO,2,{robot},4"]
        assert port.ask("VEL,10,0,0,100,140") == ["ERROR,24,wrong number of parameters"]
        # held for 1 s (VEL's longest): a STOP later than a 100 ms hold's end (a loaded host) found it
        # already stopped by the watchdog and answered IDLE before OK
        assert port.ask("VEL,10,0,0,1000") == ["OK"]
        assert port.ask("STOP", 2) == ["OK", "IDLE"]
        assert port.ask("CAL,8,0,0,60") == [f"ERROR,38,{codes.TEXTS[codes.E_CALIBRATION]}"]
    finally:
        port.close()
        emu.close()


@pytest.mark.parametrize(
    ("board", "cps", "short"),
    [("mega", 0, True), ("mega", 300, True), ("mega", 4000, False), ("uno", 0, False)],
)
def test_a_move_short_on_its_encoders_warns_on_the_mega(board: str, cps: float, short: bool) -> None:
    """The MOVE progress check (progress.py, WARN 17 after IDLE): once the wheels stand still after
    a MOVE, a travel on the encoders short of its distance by more than 10 % is said. Encoders that
    do not turn or turn slowly (``cps`` counts/s at full power) fall short; turning fast, they do
    not. The UNO has no room for the check: it says nothing."""
    emu, port = start("omni4", board=board, encoder_cps=cps or None)
    try:
        assert port.ask("MOVE,20,40,0,0", 2) == ["OK", "IDLE"]
        time.sleep(0.2)  # the coast: judged once no count moved for 10 ms
        got = port.ask("STATUS", 2 if short else 1)
    finally:
        port.close()
        emu.close()
    warn = f"WARN,{codes.W_SHORT},{codes.TEXTS[codes.W_SHORT]}"
    assert got[0] == warn if short else got[0].startswith("STATUS,1,"), got


@pytest.mark.parametrize(("robot", "board"), BUILDS, ids=BUILD_IDS)
def test_each_motor_drives_its_own_pins(robot: str, board: str) -> None:
    """POWER reaches every motor's EN (PWM duty) and IN1/IN2 (direction) pins of the robot's wiring."""
    emu, port = start(robot, report=True, board=board)
    try:
        powers = [100, -50, 30, -255]
        assert port.ask("POWER,200," + ",".join(str(p) for p in powers)) == ["OK"]
        t0, duties = emu.duties()
        while duties != powers:  # the four motors may be set across two reports
            t0, duties = emu.duties()
        t1, duties = emu.duties()  # POWER's 200 ms are over: the motors stop
        while duties != [0, 0, 0, 0]:
            _, duties = emu.duties()
        assert 0.19 <= (t1 - t0) / 1e6 <= 0.21  # emulated time
    finally:
        port.close()
        emu.close()


@pytest.mark.parametrize(("robot", "board"), BUILDS, ids=BUILD_IDS)
def test_each_encoder_counts_its_own_wheel(robot: str, board: str) -> None:
    """Each wheel's encoder pin reaches its own count (TEL's encoder group), in the direction of its
    motor's power: the wheels turn at 100, 200, 300 and 400 counts/s."""
    emu, port = start(robot, board=board)
    try:
        emu.command("wheels 100 200 300 400")
        assert port.ask("POWER,1000,100,-100,100,-100") == ["OK"]
        time.sleep(0.5)
        port.ask(f"TELEM,100,{codes.TEL_ENCODERS}")
        tel = port.lines(1)[0].split(",")
        port.ask("TELEM,0,0;STOP", 2, skip=("IDLE",))
    finally:
        port.close()
        emu.close()
    assert tel[0] == "TEL" and tel[3] == "4"  # time, mask, then the four encoder counts
    counts = [int(v) for v in tel[4:8]]
    assert [c > 0 for c in counts] == [True, False, True, False], counts
    magnitudes = [abs(c) for c in counts]
    assert 0 < magnitudes[0] < magnitudes[1] < magnitudes[2] < magnitudes[3], counts


@pytest.mark.parametrize("board", ["uno", "mega"])
def test_a_vels_watchdog_on_the_closed_loop_brakes_to_rest_on_the_mega(board: str) -> None:
    """A VEL not refreshed on the closed loop (MODE 2): the UNO cuts the motors when its watchdog
    runs out (100 ms); the Mega, as the MicroPython firmware (motion.py brake_to_rest), slews the
    twist down at omni4's acceleration limit (0.4 m/s at 2 m/s^2: 0.2 s, the powers falling step by
    step) and ends the VEL (IDLE) once the wheels stand still. The emulated wheels turn with the duty."""
    emu, port = start("omni4", report=True, board=board, encoder_cps=2600)
    try:
        assert port.ask("MODE,2") == ["OK"]
        port.write("VEL,40,0,0,100\n")
        t0, duties = emu.duties()
        t, driven = t0, []
        # every report until none comes for 1 s: on the Mega the loop's powers pass through 0 on their
        # way down (a report of all zeros at about 0.27 s), so the first zero report is not the end
        while True:
            try:
                t, duties = emu.duties(timeout=1.0)
            except UnoError:
                break
            driven.append(abs(duties[1]))
        assert not any(duties), duties
        assert port.lines(2) == ["OK", "IDLE"]
    finally:
        port.close()
        emu.close()
    seconds = (t - t0) / 1e6  # emulated
    if board == "uno":
        assert 0.09 <= seconds <= 0.12, seconds
    else:
        assert 0.28 <= seconds <= 1.0, seconds
        assert len(set(driven)) >= 10, driven  # stepped down, not cut
