"""The AVR firmware's headers, generated from the protocol and the robot description (CPython).

One source of truth: ``firmware-avr/generated/<robot>.h`` holds the protocol codes and texts
(:mod:`omnibot.protocol.codes`), the robot's limits, the rim-speed matrix in fixed point, the
default calibration tables (all from :func:`omnibot.firmware.config.build_config`, as the
MicroPython firmware gets them) and the UNO pin map of the robot's wiring (:data:`UNO_WIRING`);
``<robot>.board`` gives the same wiring to the emulator harness. The Arduino Mega 2560's are in
``generated/mega/``, with its pin map (:data:`MEGA_WIRING`).
The header's text is the template ``avrgen_header.h.in`` beside this module (:data:`HEADER_TEMPLATE`);
the Mega's ends with ``avrgen_features.h.in`` (:data:`FEATURES_TEMPLATE`), what it runs beyond the
UNO; both are filled in by the short functions below. ``tests/firmware/test_avrgen.py`` fails when a checked-in
header is stale.

::

    python -m omnibot.firmware.avrgen                       # rewrite every generated file
    python -m omnibot.firmware.avrgen omni4                 # print one robot's UNO header
    python -m omnibot.firmware.avrgen omni4 --board mega    # ... its Mega header
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from string import Template
from typing import Any

from omnibot.errors import ConfigError
from omnibot.firmware import landing, motion_brake, motion_landing, safety, speedctl
from omnibot.firmware.config import build_config
from omnibot.protocol import codes
from omnibot.robot import RobotDescription, load_robot

ROOT = Path(__file__).resolve().parents[3]
OUT_DIR = ROOT / "firmware-avr" / "generated"
ROBOTS = ("omni4", "mecanum4")  # seed 000's robot and seed 003's
NOT_SENT = frozenset({codes.W_SHORT, codes.W_REACH, codes.W_NO_GYRO})
"""Codes the UNO never sends, so their texts stay out of its flash: WARN 17's encoder progress check
(firmware/progress.py) and WARN 18's calibrated reach (CAL table 8, firmware/motion_commands.py) are the
MicroPython firmware's and the Mega's only (omni4's UNO image has no room for them: the Mega's header
adds their texts, :data:`FEATURE_TEXTS`); WARN 10 is a board's gyro (neither wiring has one)."""
INT16_MAX = 32767
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


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _pin(name: str, b: Board = _BOARDS["uno"]) -> tuple[str, int]:
    if name not in b.ports:
        raise ConfigError(f"{name!r} is not an {b.title} pin ({b.pin_names})", key="pins")
    return b.ports[name]


def _table_rows(t: list[list[float]], xscale: float, yscale: float) -> tuple[int, list[str]]:
    xs, ys = t
    if len(xs) > codes.CAL_KNOTS_MAX:
        raise ConfigError(f"{len(xs)} knots, the UNO holds {codes.CAL_KNOTS_MAX}", key="calibration")
    rows = [f"{{{round(x * xscale)}, {round(y * yscale)}}}" for x, y in zip(xs, ys, strict=True)]
    rows += ["{0, 0}"] * (codes.CAL_KNOTS_MAX - len(xs))
    return len(xs), rows


def _fixed_shift(rows: list[list[float]]) -> int:
    """The largest shift that keeps every value of ``rows`` times 2**shift inside int16."""
    peak = max(abs(v) for row in rows for v in row) or 1.0
    return max(0, min(14, math.floor(math.log2(INT16_MAX / peak))))


HEADER_TEMPLATE = Path(__file__).with_name("avrgen_header.h.in")
"""The generated header's text with ``${field}`` for what the robot and the protocol fill in
(:class:`string.Template`; shipped beside this module as package data)."""


@cache
def _header_template() -> Template:
    return Template(HEADER_TEMPLATE.read_text(encoding="utf-8"))


def _f(value: float) -> str:
    """A C float literal that reads back as ``value`` exactly."""
    return f"{float(value)!r}f"


def _list(values: Iterable[object]) -> str:
    return ", ".join(str(v) for v in values)


def _defines(prefix: str, keys: Iterable[str]) -> str:
    """``#define <prefix><KEY> <codes.KEY>`` for each key."""
    return "\n".join(f"#define {prefix}{key} {getattr(codes, key)}" for key in keys)


def _checked_counts(cfg: dict[str, Any]) -> tuple[int, int]:
    """The robot's motors and sonars, refused when the UNO firmware cannot hold them or its K_l."""
    n = int(cfg["motors"])
    if n > codes.MOTORS_MAX:
        raise ConfigError(f"{n} motors, the UNO firmware drives {codes.MOTORS_MAX}", key="wheels")
    sonars = len(cfg["sonar_period_min_ms"])
    if sonars > 1:
        raise ConfigError(f"{sonars} sonars, the UNO wiring has one", key="sonars")
    if not all(0 <= round(c) <= codes.CAL_COURSE_MAX for c in cfg["kl_courses"]):
        raise ConfigError(f"K_l courses must lie within 0..{codes.CAL_COURSE_MAX} degrees", key="calibration")
    if len(cfg["kl_courses"]) > codes.CAL_KL_CURVES:
        raise ConfigError(
            f"{len(cfg['kl_courses'])} K_l curves, at most {codes.CAL_KL_CURVES}", key="calibration"
        )
    return n, sonars


_BINARY_TYPES = (
    "ACK",
    "OK",
    "ERROR",
    "HELLO_REPLY",
    "STATUS_REPLY",
    "RANGE",
    "WARN",
    "ERROR_EVENT",
    "IDLE",
    "TEL",
)
_FRAMING = ("FRAME_SYNC", "FRAME_MAX", "SEQ_MAX", "WINDOW_MIN", "WINDOW", "RETRY_TIMEOUT_MS", "RETRIES")


def _protocol_fields(n: int) -> dict[str, object]:
    """The protocol's codes, keywords and texts (codes.py) for a robot of ``n`` motors."""
    prefixed = sorted(k for k in vars(codes) if k.startswith(("W_", "E_", "STATE_", "MODE_", "TEL_", "CAL_")))
    first = ("PROTOCOL_VERSION", "INF", "PARAMS_MAX", "LINE_MAX", "EVENT_LINE_MAX", "POWER_MAX")
    texts = {c: t for c, t in sorted(codes.TEXTS.items()) if c not in NOT_SENT}
    return {
        "protocol": _defines("P_", (*first, *prefixed)),
        "commands": "\n".join(f"#define K_{name} {kid}" for name, kid in codes.COMMANDS.items()),
        "command_count": len(codes.COMMANDS),
        "binary": _defines("T_", _BINARY_TYPES)
        + "\n"
        + _defines("P_", (*_FRAMING, "TEXT_SEQ_WINDOW", "TEXT_SEQ_MAX")),
        "keywords": "\n".join(_keyword(name, kid, n) for name, kid in codes.COMMANDS.items()),
        "texts": _text_defines(texts),
        "text_count": len(texts),
        "code_texts": _code_texts(texts),
    }


def _text_defines(texts: Iterable[int]) -> str:
    """``TEXT_<code>``, the PROGMEM string of each code's text (codes.TEXTS)."""
    return "\n".join(f"static const char TEXT_{c}[] PROGMEM = {_c_string(codes.TEXTS[c])};" for c in texts)


def _code_texts(texts: Iterable[int]) -> str:
    """The rows of a CodeText table: ``{code, TEXT_<code>}`` for each code."""
    return ", ".join(f"{{{c}, TEXT_{c}}}" for c in texts)


def _keyword(name: str, kid: int, n: int) -> str:
    """One row of KEYWORDS: the keyword, its id, fewest and most parameters, its INF parameter."""
    lo, hi = codes.PARAM_COUNTS[kid]
    if kid == codes.POWER:
        lo = hi = n + 1
    elif kid == codes.VEL:
        hi = 4  # protocol version 2 only: no room for VEL's acceleration (docs/uno.md)
    inf = codes.INF_PARAMS.get(kid, -1) + 1
    return f"    {{{_c_string(name)}, {kid}, {lo}, {hi}, {inf}}},"


def _robot_fields(name: str, cfg: dict[str, Any], n: int, sonars: int) -> dict[str, object]:
    """The robot's sizes, link, limits (as the integer checks of motion.py) and wheel-speed loop."""
    lmax, vmin, vmax = float(cfg["distance_max_cm"]), float(cfg["speed_min_cms"]), float(cfg["speed_max_cms"])
    cmax, fmax = float(cfg["curvature_max"]), float(cfg["rate_max_dps"])
    cpr = [int(c) for c in cfg["encoder_cpr"]]
    band = float(cfg["speed_band"])
    return {
        "robot_name": _c_string(name),
        "motors": n,
        "sonars": sonars,
        "sonar_period_min": max(60, *cfg["sonar_period_min_ms"]) if sonars else 60,
        **{key: int(cfg[key]) for key in ("queue_capacity", "line_max", "baud", "pwm_max", "power_min")},
        "l_max_excl": math.ceil(lmax),
        "l2_max_excl": math.ceil(2 * lmax),
        "v_min": math.ceil(vmin),
        "v_max": math.floor(vmax),
        "v2_max": math.floor(2 * vmax),
        "v_max_sq": math.floor(vmax * vmax),
        "c_max_excl": math.ceil(cmax),
        "c2_max_excl": math.ceil(2 * cmax),
        "f_max_excl": math.ceil(fmax),
        "l_clamp": math.ceil(lmax) - 1,
        "c_clamp": math.ceil(cmax) - 1,
        "has_encoders": 1 if all(cpr) else 0,
        "encoder_cpr": _list(cpr),
        "control_period_ms": int(cfg["control_period_ms"]),
        "speed_kp": _f(cfg["speed_kp"]),
        "speed_ki": _f(cfg["speed_ki"]),
        "speed_band_inv": _f(1.0 / band if band > 0 else 0.0),
        "mode_at_reset": int(cfg["mode"]),
    }


def _guard_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The sonar stop's constants (firmware/safety.py) for the UNO's one sonar (zeros without one)."""
    axis = (cfg["sonar_axes"] or [[0.0, safety.HALF_CONE_DEG, 0.0, 0.0]])[0]
    heading = math.radians(float(axis[0]))
    steps = [safety.INCIDENCE_MAX * k / safety.INCIDENCE_STEPS for k in range(1, safety.INCIDENCE_STEPS + 1)]
    return {
        "guard_ax": _f(math.cos(heading)),
        "guard_ay": _f(math.sin(heading)),
        "guard_half": _f(math.radians(float(axis[1]))),
        "guard_lead": _f(axis[2]),
        "guard_width": _f(axis[3]),
        "guard_decel": _f(cfg.get("stop_decel_cms2", 100.0)),
        "guard_v_min": _f(cfg["speed_min_cms"]),
        "guard_uncovered": _f(cfg.get("uncovered_speed_cms", 25.0)),
        "guard_loop_ms": _f(1000.0 / float(cfg.get("loop_hz", 500)) + safety.LATENCY_MS),
        "guard_sound_cms": _f(safety.SOUND_CMS),
        "guard_steps": safety.INCIDENCE_STEPS,
        "guard_step": _f(safety.INCIDENCE_MAX / safety.INCIDENCE_STEPS),
        "guard_cos": _list(_f(math.cos(a)) for a in steps),
        "guard_sin": _list(_f(math.sin(a)) for a in steps),
    }


def _kinematics_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The rim-speed matrix in fixed point and the axes K_l's courses fold from."""
    shift = _fixed_shift(cfg["rim"])
    axes = [float(a) for a in cfg["kl_axes"]]
    return {
        "rim_shift": shift,
        "rim_rows": "\n".join(
            "    {" + _list(round(v * (1 << shift)) for v in row) + "}," for row in cfg["rim"]
        ),
        "kl_axes": len(axes),
        "kl_axes_cdeg": _list(round(a * 100) for a in axes),
    }


def _calibration_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The default calibration in CAL units: the tables' used knots one after the other (cal.cpp loads
    them in this order), their counts, K_l's courses and the per-motor values."""
    tables = [cfg["kt"], cfg["kr"], cfg["roller_coast"], *cfg["kl_tables"], *cfg["motor_gain"]]
    counts, knots = [], []
    for table in tables:
        count, rows = _table_rows(table, 1, codes.CAL_SCALE)
        counts.append(count)
        knots += rows[:count]
    per_motor = {key: _list(round(float(v) * 10) for v in cfg[key]) for key in _PER_MOTOR}
    return {
        "cal_knots": codes.CAL_KNOTS_MAX,
        "cal_curves": codes.CAL_KL_CURVES,
        "default_k": round(float(cfg["k"]) * 10),
        "kl_curves": len(cfg["kl_courses"]),
        "kl_courses": _list(round(c) for c in cfg["kl_courses"]),
        "knot_count": len(knots),
        "knots": ", ".join(knots),
        "table_count": len(counts),
        "knot_counts": _list(counts),
        **per_motor,
        "wheel_radius": _list(_f(r) for r in cfg["radius"]),
        "roller_dir": _list("{" + _list(_f(v) for v in row) + "}" for row in cfg["roller_dir"]),
        "roller_pitch": _list(_f(p) for p in cfg["roller_pitch"]),
    }


_PER_MOTOR = ("motor_offset", "roller_cos", "roller_sin", "motor_speed")
"""The calibration's per-motor values in tenths (DEFAULT_OFFSET, _ROLLER_COS, _ROLLER_SIN, _SPEED)."""


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
        _port_bit(f"M{i}_PWM", *_pin(pwm, b)),
        f"#define M{i}_OCR {ocr}\n#define M{i}_TCCR {tccr}\n#define M{i}_COM {com}",
    ]
    lines += [_port_bit(f"M{i}_{side.upper()}", *_pin(pins[side][i], b)) for side in ("in1", "in2")]
    port, bit = _pin(pins["encoders"][i], b)
    if port not in b.pcint:
        raise ConfigError(f"encoder pin {pins['encoders'][i]} has no pin-change interrupt", key="pins")
    group, base = b.pcint[port]
    lines.append(f"#define M{i}_ENC_PIN PIN{port}\n#define M{i}_ENC_BIT {bit}\n#define M{i}_ENC_PCIE {group}")
    lines.append(f"#define M{i}_ENC_PCMSK PCMSK{group}\n#define M{i}_ENC_PCINT {base + bit}")
    return "\n".join(lines)


def _pin_fields(b: Board, robot_name: str, n: int, sonars: int) -> dict[str, object]:
    """The board's pin map of the robot's wiring, checked against the board's pins and timers."""
    pins = b.wiring.get(robot_name)
    if pins is None:
        raise ConfigError(f"no {b.title} wiring for {robot_name!r} (it has {', '.join(b.wiring)})")
    if sonars and pins["sonar_trig"] is None:
        raise ConfigError(f"{robot_name} has a sonar but its {b.title} wiring none", key="sonars")
    lines = [_motor_pins(b, pins, i) for i in range(n)]
    if sonars:
        lines.append(_port_bit("SONAR_TRIG", *_pin(pins["sonar_trig"], b)))
        if pins["sonar_echo"] != b.echo:
            raise ConfigError(
                f"the sonar echo must be on {b.echo} (the clock timer's input capture on the {b.title})",
                key="pins",
            )
    return {"board_title": b.title, "pin_map": "\n".join(lines), "battery_adc": pins["battery_adc"]}


def header_source(robot_name: str, board_name: str = "uno") -> str:
    """The text of ``firmware-avr/generated/<robot>.h`` (the Mega's: ``generated/mega/<robot>.h``):
    :data:`HEADER_TEMPLATE` filled in, then on the Mega :data:`FEATURES_TEMPLATE`."""
    b = board(board_name)
    robot = load_robot(robot_name)
    cfg = build_config(robot)
    n, sonars = _checked_counts(cfg)
    fields = {
        "robot": repr(robot.name),
        "description": repr(robot_name),
        **_protocol_fields(n),
        **_robot_fields(robot.name, cfg, n, sonars),
        **_guard_fields(cfg),
        **_kinematics_fields(cfg),
        **_calibration_fields(cfg),
        **_pin_fields(b, robot_name, n, sonars),
        **_battery_fields(robot),
    }
    text = _header_template().substitute(fields)
    if b.name != "uno":
        text += _features_template().substitute(_feature_fields(cfg))
    return text


BATTERY_SHIFT = 6
"""The UNO's battery filter: f += adc - f / 64 every sample, so f is 64 times the filtered ADC count
(0..65472 in a uint16) and its time constant is 64 sample periods."""


def _battery_fields(robot: RobotDescription) -> dict[str, object]:
    """The battery divider and thresholds (firmware/battery.py) in the UNO's filter units."""
    b = robot.battery
    # full scale (1023 counts at 5 V) is twice the nominal pack voltage: the divider ratio is 2 V / 5 V
    # of pack per V of pin (omni4: 14.8 V at 5 V, 2.96:1, e.g. 20 k over 10.2 k)
    full_mv = round(2 * b.voltage * 1000)

    def units(volts: float) -> int:
        return round(volts * 1000 * 1023 / full_mv * (1 << BATTERY_SHIFT))

    period_ms = max(1, round(b.filter_s * 1000 / (1 << BATTERY_SHIFT)))
    samples = round(b.delay * 1000 / period_ms)
    if samples > 255:
        raise ConfigError(
            f"battery.delay {b.delay} s is more than the UNO's 255 samples of {period_ms} ms",
            key="battery.delay",
        )
    levels = (("WARN", b.warn_v), ("LIMIT", b.limit_v), ("STOP", b.stop_v), ("HYST", b.hysteresis_v))
    pwm_max = max(w.motor.pwm_max for w in robot.wheels)
    return {
        "battery_full_mv": full_mv,
        "battery_divider": f"{full_mv / 5000:.3f}",
        "battery_period_ms": period_ms,
        "battery_delay": samples,
        "battery_levels": "\n".join(
            f"#define BATTERY_{name} {units(v)}U  // {v:.3f} V" for name, v in levels
        ),
        "battery_cap": pwm_max * round(100 * b.limit_power) // 100,
    }


FEATURE_TEXTS = (codes.W_SHORT, codes.W_REACH)
"""The codes of :data:`NOT_SENT` that the Mega sends: their texts are in its :data:`FEATURES_TEMPLATE`."""

FEATURES_TEMPLATE = Path(__file__).with_name("avrgen_features.h.in")
"""What the Mega runs beyond the UNO (docs/uno.md, "The Arduino Mega 2560"), the end of its header:
the compile-time switches of firmware-avr/src/ (each ``FEATURE_*`` is 0 on the UNO, board.h) and
their constants, ``${field}`` filled in by :func:`_feature_fields` (package data, as
:data:`HEADER_TEMPLATE`)."""


@cache
def _features_template() -> Template:
    return Template(FEATURES_TEMPLATE.read_text(encoding="utf-8"))


def _floats(rows: Iterable[Iterable[float]]) -> str:
    """Rows of C float literals: ``{a, b}, {c, d}``."""
    return _list("{" + _list(_f(v) for v in row) + "}" for row in rows)


def _feature_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The Mega's features from the same config as the MicroPython firmware's: VEL's acceleration
    (motion_drive.py), the MOVE progress check (progress.py), the brake to rest, the calibrated reach."""
    n = int(cfg["motors"])
    tolerance = float(cfg.get("progress_tolerance", 0.0))
    rest = motion_brake.rest_counts(cfg["encoder_cpr"])
    count, rows = _table_rows(cfg["reach"], 1, 1)
    return {
        "version_max": codes.VERSIONS[-1],
        "vel_params_max": codes.VEL_PARAMS_MAX,
        "body_ff": _floats(cfg["body_ff"]),
        "wheel_ff": _floats([float(cfg["wheel_ff"][i]) * float(j) for j in cfg["J"][i]] for i in range(n)),
        "steady_periods": speedctl.STEADY_PERIODS,
        "speed_steady": _f(
            speedctl.steady_rate(float(cfg["speed_ki"]), float(cfg.get("speed_ki_steady", 0.0)))
        ),
        "progress_on": 1 if tolerance > 0 and all(int(c) for c in cfg["encoder_cpr"]) else 0,
        "progress_tolerance": _f(tolerance),
        "travel": _floats(cfg["travel"]),
        "brake_accel_max": _f(float(cfg.get("accel_max_cms2", 0.0)) * 0.01),
        "brake_alpha_max": _f(math.radians(float(cfg.get("angular_accel_max_dps2", 0.0)))),
        "brake_max_us": motion_brake.BRAKE_MAX_US,
        "rest_window_us": motion_brake.REST_WINDOW_US,
        "rest_counts": _list(rest),
        **_landing_fields(cfg),
        "reach_n": count,
        "reach": ", ".join(rows[:count]),
        "feature_texts": _text_defines(FEATURE_TEXTS),
        "feature_text_count": len(FEATURE_TEXTS),
        "feature_code_texts": _code_texts(FEATURE_TEXTS),
    }


_LANDING_FLOATS = ("LAG_S", "CRAWL", "CRAWL_W", "TOLERANCE", "TOLERANCE_W", "ROLL_EPS")
"""The closed-loop landing's float constants (firmware/landing.py), ``LAND_<name>`` in C."""


def _landing_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The closed-loop landing's constants (firmware/landing.py) and the floor's creep."""
    n = int(cfg["motors"])
    turn = [float(v) for v in cfg.get("turn") or [0.0] * n]
    accel = [float(v) for v in cfg.get("land_accel") or [0.0, 0.0]]
    zero = [[0.0, 0.0, 0.0]] * n
    on = all(int(c) > 0 for c in cfg["encoder_cpr"]) and any(turn) and min(accel) > 0.0
    return {
        "landing_on": 1 if on else 0,
        "turn": _list(_f(v) for v in turn),
        "land_accel": _f(accel[0]),
        "land_accel_w": _f(accel[1]),
        **{f"land_{name.lower()}": _f(getattr(landing, name)) for name in _LANDING_FLOATS},
        "land_far_us": landing.FAR_US,
        "land_chain_guard": motion_landing.CHAIN_GUARD,
        "default_slip": _list(_f(v) for v in cfg.get("slip") or [0.0, 0.0, 1.0]),
        "creep_roll": _floats(cfg.get("creep_roll") or zero),
        "creep_rim": _floats(cfg.get("creep_rim") or zero),
        "creep_mix": _floats(cfg.get("creep_mix") or [[0.0] * n] * n),
    }


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
        p1, b1 = _pin(pins["in1"][i], b)
        p2, b2 = _pin(pins["in2"][i], b)
        a = b.addr
        regs = (a[ocr], a[tccr], _COM_BITS[com], a[f"PORT{p1}"], b1, a[f"PORT{p2}"], b2)
        out.append("motor {:x} {:x} {} {:x} {} {:x} {}".format(*regs))
    for enc in pins["encoders"]:
        out.append("encoder {} {}".format(*_pin(enc, b)))
    if pins["sonar_trig"] is not None:
        out.append("trigger {} {}".format(*_pin(pins["sonar_trig"], b)))
        out.append("echo {} {}".format(*_pin(pins["sonar_echo"], b)))
    out.append(f"battery {pins['battery_adc']}")
    if b.name != "uno":
        out.append(
            "# the external interrupts' pins, INT0 first: unused here, unhooked (simavr polls their level)"
        )
        out += [f"extint {port} {bit}" for port, bit in b.extint]
    return "\n".join(out) + "\n"


def board_dir(board_name: str = "uno") -> Path:
    """The folder of a board's generated files: ``generated/`` for the UNO, ``generated/mega/``."""
    return OUT_DIR if board(board_name).name == "uno" else OUT_DIR / board_name


def header_path(robot_name: str, board_name: str = "uno") -> Path:
    """Where the generated header for ``robot_name`` on ``board_name`` goes."""
    return board_dir(board_name) / f"{robot_name}.h"


def board_path(robot_name: str, board_name: str = "uno") -> Path:
    """Where the generated board wiring for ``robot_name`` on ``board_name`` goes."""
    return board_dir(board_name) / f"{robot_name}.board"


def generated_files() -> dict[Path, str]:
    """Every generated file and its text: one header and one wiring per robot and board."""
    files = {}
    for board_name in BOARDS:
        for name in ROBOTS:
            files[header_path(name, board_name)] = header_source(name, board_name)
            files[board_path(name, board_name)] = board_source(name, board_name)
    return files


def main(argv: list[str] | None = None) -> int:
    """Write every generated file (or print one robot's header); the exit status."""
    ap = argparse.ArgumentParser(prog="python -m omnibot.firmware.avrgen", description=__doc__.split("\n")[0])
    ap.add_argument("robot", nargs="?", help="print this robot's header instead of writing every file")
    ap.add_argument("--board", choices=BOARDS, default="uno", help="with a robot: the board (default uno)")
    args = ap.parse_args(argv)
    if args.robot:
        print(header_source(args.robot, args.board), end="")
        return 0
    for path, text in generated_files().items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
