"""The Arduino boards the AVR firmware is built for: their pins, timers and the robots' wiring (CPython).

:data:`UNO_WIRING` and :data:`MEGA_WIRING` give each robot's pins on the Arduino UNO and the Arduino
Mega 2560; :func:`pin_fields` checks a wiring against its board's pins and timers and writes the
header's pin map (avrgen.py), :func:`board_source` the same wiring for the emulator harness
(``generated/<robot>.board``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from omnibot.errors import ConfigError

EEPROM_BYTES = 1024  # ATmega328P (the ATmega2560 has 4 KB; the calibration store takes the first 1 KB)
BOARDS = ("uno", "mega")
"""The boards the firmware is built for: the Arduino UNO (ATmega328P) and the Arduino Mega 2560
(ATmega2560, ``make -C firmware-avr BOARD=mega``): the same firmware, each with its own pin map."""

# Arduino UNO pins (D0..D13, A0..A5) -> (port letter, bit).
_PORTS = {**{f"D{i}": ("D", i) for i in range(8)}, **{f"D{i}": ("B", i - 8) for i in range(8, 14)}}
_PORTS.update({f"A{i}": ("C", i) for i in range(6)})
# Arduino Mega 2560 pins (D0..D53, A0..A15) -> (port letter, bit), from its schematic.
_MEGA_LOW = "E0 E1 E4 E5 G5 E3 H3 H4 H5 H6 B4 B5 B6 B7 J1 J0 H1 H0 D3 D2 D1 D0"  # D0..D21
_MEGA_PORTS = {f"D{i}": (p[0], int(p[1])) for i, p in enumerate(_MEGA_LOW.split(" "))}
_MEGA_PORTS.update({f"D{22 + i}": ("A", i) for i in range(8)})
_MEGA_PORTS.update({f"D{30 + i}": ("C", 7 - i) for i in range(8)})
_MEGA_PORTS.update({"D38": ("D", 7), "D39": ("G", 2), "D40": ("G", 1), "D41": ("G", 0)})
_MEGA_PORTS.update({f"D{42 + i}": ("L", 7 - i) for i in range(8)})
_MEGA_PORTS.update({f"D{50 + i}": ("B", 3 - i) for i in range(4)})
_MEGA_PORTS.update({f"A{i}": ("F", i) for i in range(8)})
_MEGA_PORTS.update({f"A{8 + i}": ("K", i) for i in range(8)})

# The wiring of an UNO with two L298 boards (EN = PWM, IN1/IN2 = direction) and, on seed 000's robot,
# an HC-SR04 sonar. Motors in the robot description's wheel order. The PWM pins are the four of
# timers 0 and 2 (timer 1 is the clock and times the sonar echo by input capture on D8); encoders
# are single-channel (their direction is that of the motor's power), read by pin-change interrupts;
# the battery divider is on ADC7 (the SMD UNO and the Nano have it; a DIP UNO reads 0 there).
UNO_WIRING: dict[str, dict[str, Any]] = {
    # seed 000 names no pins ("connected to Arduino GPIO pins"): this is ours
    "omni4": {
        "pwm": ["D3", "D5", "D6", "D11"],  # OC2B, OC0B, OC0A, OC2A
        "in1": ["D2", "D7", "A1", "D12"],
        "in2": ["D4", "A0", "A2", "D13"],
        "sonar_trig": "D9",
        "sonar_echo": "D8",  # ICP1
        "encoders": ["D10", "A3", "A4", "A5"],
        "battery_adc": 7,
    },
    # seed 003 (section 4.3), wheels left_front, right_front, right_back, left_back: its enable pins
    # 5, 6, 11 and its direction pins as they are, except that left_back's enable moves from D10
    # (timer 1, our clock) to D3 and motor A's IN1 from D3 to D10
    "mecanum4": {
        "pwm": ["D5", "D6", "D11", "D3"],
        "in1": ["D10", "D8", "D2", "D9"],
        "in2": ["D4", "D7", "D13", "D12"],
        "sonar_trig": None,
        "sonar_echo": None,
        "encoders": ["A0", "A1", "A2", "A3"],
        "battery_adc": 7,
    },
}
# The Mega's wiring (ours; docs/uno.md): each motor keeps its UNO timer output (timers 0 and 2 on
# D4, D13, D10, D9), the direction pins are D22..D29 (port A), the encoders D53..D50 (PB0..PB3,
# PCINT0..3: one pin-change group, the one simavr 1.6 models on this chip; A8..A15, PCINT16..23,
# work as well on a board), the clock is timer 5 and times the echo on D48 (ICP5: the Mega's ICP1,
# PD4, is on no header), the sonar's trigger D47; the battery divider on A7 (every Mega has it).
_MEGA_PWM = {"D3": "D9", "D5": "D4", "D6": "D13", "D11": "D10"}
"""The Mega's pin of each UNO PWM pin's timer output (OC2B, OC0B, OC0A, OC2A)."""
MEGA_WIRING: dict[str, dict[str, Any]] = {
    robot: {
        "pwm": [_MEGA_PWM[pin] for pin in uno["pwm"]],
        "in1": ["D22", "D24", "D26", "D28"],
        "in2": ["D23", "D25", "D27", "D29"],
        "sonar_trig": "D47" if uno["sonar_trig"] else None,
        "sonar_echo": "D48" if uno["sonar_echo"] else None,  # ICP5
        "encoders": ["D53", "D52", "D51", "D50"],
        "battery_adc": 7,
    }
    for robot, uno in UNO_WIRING.items()
}
# Timer/compare register of each PWM pin.
_PWM_REGS = {"D3": ("OCR2B", "TCCR2A", "COM2B1"), "D5": ("OCR0B", "TCCR0A", "COM0B1")}
_PWM_REGS.update({"D6": ("OCR0A", "TCCR0A", "COM0A1"), "D11": ("OCR2A", "TCCR2A", "COM2A1")})
_MEGA_PWM_REGS = {mega: _PWM_REGS[uno] for uno, mega in _MEGA_PWM.items()}
# Pin-change interrupt group of each port (PCINT0..7 = PB, 8..14 = PC, 16..23 = PD).
_PCINT = {"B": (0, 0), "C": (1, 8), "D": (2, 16)}
# The Mega's: PCINT0..7 = PB, 9..15 = PJ0..6 (8 is PE0, the UART's RX), 16..23 = PK (A8..A15).
_MEGA_PCINT = {"B": (0, 0), "J": (1, 9), "K": (2, 16)}
# Data-space addresses of the registers the emulator harness reads: the same on both chips for
# ports B, C, D and timers 0 and 2; the ATmega2560's ports H..L are above the I/O space.
_ADDR = {"PORTB": 0x25, "PORTC": 0x28, "PORTD": 0x2B, "TCCR0A": 0x44, "OCR0A": 0x47, "OCR0B": 0x48}
_ADDR.update({"TCCR2A": 0xB0, "OCR2A": 0xB3, "OCR2B": 0xB4})
_MEGA_ADDR = {**_ADDR, "PORTA": 0x22, "PORTE": 0x2E, "PORTF": 0x31, "PORTG": 0x34, "PORTH": 0x102}
_MEGA_ADDR.update({"PORTJ": 0x105, "PORTK": 0x108, "PORTL": 0x10B})
_COM_BITS = {"COM0A1": 7, "COM0B1": 5, "COM2A1": 7, "COM2B1": 5}


@dataclass(frozen=True)
class Board:
    """One Arduino board: its chip, pins, timers and what the harness must know of it."""

    name: str
    title: str
    mcu: str
    ports: dict[str, tuple[str, int]]
    wiring: dict[str, dict[str, Any]]
    pwm_regs: dict[str, tuple[str, str, str]]
    pcint: dict[str, tuple[int, int]]
    addr: dict[str, int]
    echo: str  # the clock timer's input-capture pin: the sonar's echo must be there
    extint: tuple[
        tuple[str, int], ...
    ]  # the external interrupts' pins, INT0 first (the harness unhooks them)
    pin_names: str


_BOARDS = {
    "uno": Board(
        "uno",
        "Arduino UNO",
        "atmega328p",
        _PORTS,
        UNO_WIRING,
        _PWM_REGS,
        _PCINT,
        _ADDR,
        "D8",
        (("D", 2), ("D", 3)),
        "D0..D13, A0..A5",
    ),
    "mega": Board(
        "mega",
        "Arduino Mega 2560",
        "atmega2560",
        _MEGA_PORTS,
        MEGA_WIRING,
        _MEGA_PWM_REGS,
        _MEGA_PCINT,
        _MEGA_ADDR,
        "D48",
        (("D", 0), ("D", 1), ("D", 2), ("D", 3), ("E", 4), ("E", 5), ("E", 6), ("E", 7)),
        "D0..D53, A0..A15",
    ),
}


def board(name: str) -> Board:
    """The board called ``name`` (``uno`` or ``mega``)."""
    if name not in _BOARDS:
        raise ConfigError(f"no board {name!r}: the firmware is built for {', '.join(BOARDS)}", key="board")
    return _BOARDS[name]


def pin(name: str, b: Board = _BOARDS["uno"]) -> tuple[str, int]:
    """The (port letter, bit) of a pin of board ``b``; a ConfigError naming the board's pins."""
    if name not in b.ports:
        raise ConfigError(f"{name!r} is not an {b.title} pin ({b.pin_names})", key="pins")
    return b.ports[name]


def _port_bit(name: str, port: str, bit: int) -> str:
    """``<name>_PORT``, ``_DDR`` and ``_BIT`` of an output pin."""
    return f"#define {name}_PORT PORT{port}\n#define {name}_DDR DDR{port}\n#define {name}_BIT {bit}"


def _motor_pins(b: Board, pins: dict[str, Any], i: int) -> str:
    """Motor ``i``'s PWM pin and timer, direction pins and encoder pin-change interrupt."""
    pwm = pins["pwm"][i]
    if pwm not in b.pwm_regs:
        raise ConfigError(f"{pwm} is not a PWM pin of timers 0 and 2 on the {b.title}", key="pins")
    ocr, tccr, com = b.pwm_regs[pwm]
    lines = [
        _port_bit(f"M{i}_PWM", *pin(pwm, b)),
        f"#define M{i}_OCR {ocr}\n#define M{i}_TCCR {tccr}\n#define M{i}_COM {com}",
    ]
    lines += [_port_bit(f"M{i}_{side.upper()}", *pin(pins[side][i], b)) for side in ("in1", "in2")]
    port, bit = pin(pins["encoders"][i], b)
    if port not in b.pcint:
        raise ConfigError(f"encoder pin {pins['encoders'][i]} has no pin-change interrupt", key="pins")
    group, base = b.pcint[port]
    lines.append(f"#define M{i}_ENC_PIN PIN{port}\n#define M{i}_ENC_BIT {bit}\n#define M{i}_ENC_PCIE {group}")
    lines.append(f"#define M{i}_ENC_PCMSK PCMSK{group}\n#define M{i}_ENC_PCINT {base + bit}")
    return "\n".join(lines)


def pin_fields(b: Board, robot_name: str, n: int, sonars: int) -> dict[str, object]:
    """The board's pin map of the robot's wiring, checked against the board's pins and timers."""
    pins = b.wiring.get(robot_name)
    if pins is None:
        raise ConfigError(f"no {b.title} wiring for {robot_name!r} (it has {', '.join(b.wiring)})")
    if sonars and pins["sonar_trig"] is None:
        raise ConfigError(f"{robot_name} has a sonar but its {b.title} wiring none", key="sonars")
    lines = [_motor_pins(b, pins, i) for i in range(n)]
    if sonars:
        lines.append(_port_bit("SONAR_TRIG", *pin(pins["sonar_trig"], b)))
        if pins["sonar_echo"] != b.echo:
            raise ConfigError(
                f"the sonar echo must be on {b.echo} (the clock timer's input capture on the {b.title})",
                key="pins",
            )
    return {"board_title": b.title, "pin_map": "\n".join(lines), "battery_adc": pins["battery_adc"]}


def board_source(robot_name: str, board_name: str = "uno") -> str:
    """The text of ``firmware-avr/generated/<robot>.board``: the robot's wiring for the emulator
    harness (firmware-avr/unosim ``--board``), as data-space register addresses and port bits."""
    b = board(board_name)
    pins = b.wiring[robot_name]
    short = b.title.removeprefix("Arduino ")
    out = [
        f"# {short} wiring of {robot_name} for firmware-avr/unosim, generated by python -m omnibot.firmware.avrgen"
    ]
    if b.name != "uno":  # the harness's defaults are the UNO's: its chip, INT0 and INT1 on D2 and D3
        out.append(f"mcu {b.mcu}")
    out.append("# motor OCR TCCR COM-bit IN1-PORT IN1-bit IN2-PORT IN2-bit (addresses in hex)")
    for i, pwm in enumerate(pins["pwm"]):
        ocr, tccr, com = b.pwm_regs[pwm]
        p1, b1 = pin(pins["in1"][i], b)
        p2, b2 = pin(pins["in2"][i], b)
        a = b.addr
        regs = (a[ocr], a[tccr], _COM_BITS[com], a[f"PORT{p1}"], b1, a[f"PORT{p2}"], b2)
        out.append("motor {:x} {:x} {} {:x} {} {:x} {}".format(*regs))
    for enc in pins["encoders"]:
        out.append("encoder {} {}".format(*pin(enc, b)))
    if pins["sonar_trig"] is not None:
        out.append("trigger {} {}".format(*pin(pins["sonar_trig"], b)))
        out.append("echo {} {}".format(*pin(pins["sonar_echo"], b)))
    out.append(f"battery {pins['battery_adc']}")
    if b.name != "uno":
        out.append(
            "# the external interrupts' pins, INT0 first: unused here, unhooked (simavr polls their level)"
        )
        out += [f"extint {port} {bit}" for port, bit in b.extint]
    return "\n".join(out) + "\n"
