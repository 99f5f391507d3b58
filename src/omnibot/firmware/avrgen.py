"""The AVR firmware's headers, generated from the protocol and the robot description (CPython).

One source of truth: ``firmware-avr/generated/<robot>.h`` holds the protocol codes and texts
(:mod:`omnibot.protocol.codes`), the robot's limits, the rim-speed matrix in fixed point, the
default calibration tables (all from :func:`omnibot.firmware.config.build_config`, as the
MicroPython firmware gets them) and the UNO pin map of the robot's wiring;
``<robot>.board`` gives the same wiring to the emulator harness. The Arduino Mega 2560's are in
``generated/mega/``, with its pin map. The header's text is the template ``avrgen_header.h.in``
beside this module (:data:`HEADER_TEMPLATE`), filled in by the short functions below; beside them:

==================  ===============================================================================
``avrboard.py``     the boards' pins and timers, the robots' wiring (``UNO_WIRING``,
                    ``MEGA_WIRING``), the header's pin map and the harness's ``.board`` file
``avrfeatures.py``  what the Mega runs beyond the UNO, the end of its header (``avrgen_features.h.in``)
``avrliterals.py``  the C literals all of them write
==================  ===============================================================================

``tests/firmware/test_avrgen.py`` fails when a checked-in header is stale.

::

    python -m omnibot.firmware.avrgen                       # rewrite every generated file
    python -m omnibot.firmware.avrgen omni4                 # print one robot's UNO header
    python -m omnibot.firmware.avrgen omni4 --board mega    # ... its Mega header
"""

from __future__ import annotations

import argparse
import math
from functools import cache
from pathlib import Path
from string import Template
from typing import Any

from omnibot.errors import ConfigError
from omnibot.firmware import safety
from omnibot.firmware.avrboard import BOARDS, board, board_source, pin_fields
from omnibot.firmware.avrfeatures import features_source
from omnibot.firmware.avrliterals import (
    c_float,
    c_list,
    c_string,
    code_texts,
    defines,
    fixed_shift,
    table_rows,
    text_defines,
)
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
adds their texts, :data:`~omnibot.firmware.avrfeatures.FEATURE_TEXTS`); WARN 10 is a board's gyro (neither wiring has one)."""
HEADER_TEMPLATE = Path(__file__).with_name("avrgen_header.h.in")
"""The generated header's text with ``${field}`` for what the robot and the protocol fill in
(:class:`string.Template`; shipped beside this module as package data)."""


@cache
def _header_template() -> Template:
    return Template(HEADER_TEMPLATE.read_text(encoding="utf-8"))


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
        "protocol": defines("P_", (*first, *prefixed)),
        "commands": "\n".join(f"#define K_{name} {kid}" for name, kid in codes.COMMANDS.items()),
        "command_count": len(codes.COMMANDS),
        "binary": defines("T_", _BINARY_TYPES)
        + "\n"
        + defines("P_", (*_FRAMING, "TEXT_SEQ_WINDOW", "TEXT_SEQ_MAX")),
        "keywords": "\n".join(_keyword(name, kid, n) for name, kid in codes.COMMANDS.items()),
        "texts": text_defines(texts),
        "text_count": len(texts),
        "code_texts": code_texts(texts),
    }


def _keyword(name: str, kid: int, n: int) -> str:
    """One row of KEYWORDS: the keyword, its id, fewest and most parameters, its INF parameter."""
    lo, hi = codes.PARAM_COUNTS[kid]
    if kid == codes.POWER:
        lo = hi = n + 1
    elif kid == codes.VEL:
        hi = 4  # protocol version 2 only: no room for VEL's acceleration (docs/uno.md)
    inf = codes.INF_PARAMS.get(kid, -1) + 1
    return f"    {{{c_string(name)}, {kid}, {lo}, {hi}, {inf}}},"


def _robot_fields(name: str, cfg: dict[str, Any], n: int, sonars: int) -> dict[str, object]:
    """The robot's sizes, link, limits (as the integer checks of motion.py) and wheel-speed loop."""
    lmax, vmin, vmax = float(cfg["distance_max_cm"]), float(cfg["speed_min_cms"]), float(cfg["speed_max_cms"])
    cmax, fmax = float(cfg["curvature_max"]), float(cfg["rate_max_dps"])
    cpr = [int(c) for c in cfg["encoder_cpr"]]
    band = float(cfg["speed_band"])
    return {
        "robot_name": c_string(name),
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
        "encoder_cpr": c_list(cpr),
        "control_period_ms": int(cfg["control_period_ms"]),
        "speed_kp": c_float(cfg["speed_kp"]),
        "speed_ki": c_float(cfg["speed_ki"]),
        "speed_band_inv": c_float(1.0 / band if band > 0 else 0.0),
        "mode_at_reset": int(cfg["mode"]),
    }


def _guard_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The sonar stop's constants (firmware/safety.py) for the UNO's one sonar (zeros without one)."""
    axis = (cfg["sonar_axes"] or [[0.0, safety.HALF_CONE_DEG, 0.0, 0.0]])[0]
    heading = math.radians(float(axis[0]))
    steps = [safety.INCIDENCE_MAX * k / safety.INCIDENCE_STEPS for k in range(1, safety.INCIDENCE_STEPS + 1)]
    return {
        "guard_ax": c_float(math.cos(heading)),
        "guard_ay": c_float(math.sin(heading)),
        "guard_half": c_float(math.radians(float(axis[1]))),
        "guard_lead": c_float(axis[2]),
        "guard_width": c_float(axis[3]),
        "guard_decel": c_float(cfg.get("stop_decel_cms2", 100.0)),
        "guard_v_min": c_float(cfg["speed_min_cms"]),
        "guard_uncovered": c_float(cfg.get("uncovered_speed_cms", 25.0)),
        "guard_loop_ms": c_float(1000.0 / float(cfg.get("loop_hz", 500)) + safety.LATENCY_MS),
        "guard_sound_cms": c_float(safety.SOUND_CMS),
        "guard_steps": safety.INCIDENCE_STEPS,
        "guard_step": c_float(safety.INCIDENCE_MAX / safety.INCIDENCE_STEPS),
        "guard_cos": c_list(c_float(math.cos(a)) for a in steps),
        "guard_sin": c_list(c_float(math.sin(a)) for a in steps),
    }


def _kinematics_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The rim-speed matrix in fixed point and the axes K_l's courses fold from."""
    shift = fixed_shift(cfg["rim"])
    axes = [float(a) for a in cfg["kl_axes"]]
    return {
        "rim_shift": shift,
        "rim_rows": "\n".join(
            "    {" + c_list(round(v * (1 << shift)) for v in row) + "}," for row in cfg["rim"]
        ),
        "kl_axes": len(axes),
        "kl_axes_cdeg": c_list(round(a * 100) for a in axes),
    }


def _calibration_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The default calibration in CAL units: the tables' used knots one after the other (cal.cpp loads
    them in this order), their counts, K_l's courses and the per-motor values."""
    tables = [cfg["kt"], cfg["kr"], cfg["roller_coast"], *cfg["kl_tables"], *cfg["motor_gain"]]
    counts, knots = [], []
    for table in tables:
        count, rows = table_rows(table, 1, codes.CAL_SCALE)
        counts.append(count)
        knots += rows[:count]
    per_motor = {key: c_list(round(float(v) * 10) for v in cfg[key]) for key in _PER_MOTOR}
    return {
        "cal_knots": codes.CAL_KNOTS_MAX,
        "cal_curves": codes.CAL_KL_CURVES,
        "default_k": round(float(cfg["k"]) * 10),
        "kl_curves": len(cfg["kl_courses"]),
        "kl_courses": c_list(round(c) for c in cfg["kl_courses"]),
        "knot_count": len(knots),
        "knots": ", ".join(knots),
        "table_count": len(counts),
        "knot_counts": c_list(counts),
        **per_motor,
        "wheel_radius": c_list(c_float(r) for r in cfg["radius"]),
        "roller_dir": c_list("{" + c_list(c_float(v) for v in row) + "}" for row in cfg["roller_dir"]),
        "roller_pitch": c_list(c_float(p) for p in cfg["roller_pitch"]),
    }


_PER_MOTOR = ("motor_offset", "roller_cos", "roller_sin", "motor_speed")
"""The calibration's per-motor values in tenths (DEFAULT_OFFSET, _ROLLER_COS, _ROLLER_SIN, _SPEED)."""


def header_source(robot_name: str, board_name: str = "uno") -> str:
    """The text of ``firmware-avr/generated/<robot>.h`` (the Mega's: ``generated/mega/<robot>.h``):
    :data:`HEADER_TEMPLATE` filled in, then on the Mega :func:`~omnibot.firmware.avrfeatures.features_source`."""
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
        **pin_fields(b, robot_name, n, sonars),
        **_battery_fields(robot),
    }
    text = _header_template().substitute(fields)
    if b.name != "uno":
        text += features_source(cfg)
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
