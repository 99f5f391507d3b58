"""Run the firmware on a FakeHAL from a command script; the same file runs in CPython and MicroPython.

Usage: ``<python> mp_driver.py SCRIPT`` with ``robot_config.py``, the staged ``omnibot`` package and
``tests.firmware.fakehal`` importable. Script lines: ``> text`` sends text plus LF; ``>> text`` sends it with no
terminator; ``@ N`` polls for N ms (1 ms steps); ``range S CM`` sets a sonar's echo; ``gyro MDPS``
sets the gyro rate; ``battery MV`` sets the battery's reading; ``enc GAIN`` makes the encoders follow the powers (FakeHAL ``enc_gain``); ``hex HEX`` sends raw bytes (binary frames). Every line the controller writes is printed as ``<ms> <line>``, then the final
motor powers as ``powers p1,...``.
"""

import sys

from omnibot.firmware.controller import Controller
from tests.firmware.fakehal import FakeHAL, advance


def main(path: str) -> None:
    config = __import__("robot_config").CONFIG
    hal = FakeHAL(config["motors"], len(config["sonar_period_min_ms"]))
    ctrl = Controller(hal, config)

    def flush() -> None:
        data = hal.take()
        if b"\x00" in data:  # binary frames: print them as hex
            print(str(ctrl.now_ms) + " hex " + data.hex())
            return
        for line in data.decode().split("\r\n")[:-1]:
            print(str(ctrl.now_ms) + " " + line)

    flush()
    with open(path) as f:
        script = f.read()
    for raw in script.split("\n"):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith(">>"):
            hal.send(line[2:].strip())
            ctrl.poll()
        elif line.startswith(">"):
            hal.send(line[1:].strip() + "\n")
            ctrl.poll()
        elif line.startswith("hex"):
            hal.rx += bytes.fromhex(line[3:].strip())
            ctrl.poll()
        elif line.startswith("@"):
            advance(ctrl, hal, int(line[1:]))
        elif line.startswith("range"):
            _, s, cm = line.split()
            if int(s) < len(hal.ranges):
                hal.ranges[int(s)] = int(cm)
        elif line.startswith("gyro"):
            hal.gyro = int(line.split()[1])
        elif line.startswith("battery"):
            hal.battery = int(line.split()[1])
        elif line.startswith("enc"):
            hal.enc_gain = float(line.split()[1])
        flush()
    print("powers " + ",".join([str(p) for p in hal.powers]))


if __name__ == "__main__":
    main(sys.argv[1])
