"""What the Arduino Mega 2560 runs beyond the UNO: the end of its generated header (CPython).

The compile-time switches of firmware-avr/src/ (each ``FEATURE_*`` is 0 on the UNO, board.h) and their
constants, from the same config as the MicroPython firmware's: VEL's planned acceleration
(motion_drive.py), the MOVE progress check (progress.py), the brake to rest (motion_brake.py), the
calibrated reach, the closed-loop landing (landing.py, motion_landing.py) and the speed loop's steady
integral (speedctl.py). The text is the template ``avrgen_features.h.in`` beside this module
(:data:`FEATURES_TEMPLATE`), filled in by :func:`features_source`.
"""

from __future__ import annotations

import math
from functools import cache
from pathlib import Path
from string import Template
from typing import Any

from omnibot.firmware import landing, motion_brake, motion_landing, speedctl
from omnibot.firmware.avrliterals import c_float, c_floats, c_list, code_texts, table_rows, text_defines
from omnibot.protocol import codes

FEATURE_TEXTS = (codes.W_SHORT, codes.W_REACH)
"""The codes of :data:`~omnibot.firmware.avrgen.NOT_SENT` that the Mega sends: their texts are in its :data:`FEATURES_TEMPLATE`."""

FEATURES_TEMPLATE = Path(__file__).with_name("avrgen_features.h.in")
"""What the Mega runs beyond the UNO (docs/uno.md, "The Arduino Mega 2560"), the end of its header:
the compile-time switches of firmware-avr/src/ (each ``FEATURE_*`` is 0 on the UNO, board.h) and
their constants, ``${field}`` filled in by :func:`_feature_fields` (package data, as the
header's ``avrgen_header.h.in``)."""


@cache
def _features_template() -> Template:
    return Template(FEATURES_TEMPLATE.read_text(encoding="utf-8"))


def _feature_fields(cfg: dict[str, Any]) -> dict[str, object]:
    """The Mega's features from the same config as the MicroPython firmware's: VEL's acceleration
    (motion_drive.py), the MOVE progress check (progress.py), the brake to rest, the calibrated reach."""
    n = int(cfg["motors"])
    tolerance = float(cfg.get("progress_tolerance", 0.0))
    rest = motion_brake.rest_counts(cfg["encoder_cpr"])
    count, rows = table_rows(cfg["reach"], 1, 1)
    return {
        "version_max": codes.VERSIONS[-1],
        "vel_params_max": codes.VEL_PARAMS_MAX,
        "body_ff": c_floats(cfg["body_ff"]),
        "wheel_ff": c_floats([float(cfg["wheel_ff"][i]) * float(j) for j in cfg["J"][i]] for i in range(n)),
        "steady_periods": speedctl.STEADY_PERIODS,
        "speed_steady": c_float(
            speedctl.steady_rate(float(cfg["speed_ki"]), float(cfg.get("speed_ki_steady", 0.0)))
        ),
        "progress_on": 1 if tolerance > 0 and all(int(c) for c in cfg["encoder_cpr"]) else 0,
        "progress_tolerance": c_float(tolerance),
        "travel": c_floats(cfg["travel"]),
        "brake_accel_max": c_float(float(cfg.get("accel_max_cms2", 0.0)) * 0.01),
        "brake_alpha_max": c_float(math.radians(float(cfg.get("angular_accel_max_dps2", 0.0)))),
        "brake_max_us": motion_brake.BRAKE_MAX_US,
        "rest_window_us": motion_brake.REST_WINDOW_US,
        "rest_counts": c_list(rest),
        **_landing_fields(cfg),
        "reach_n": count,
        "reach": ", ".join(rows[:count]),
        "feature_texts": text_defines(FEATURE_TEXTS),
        "feature_text_count": len(FEATURE_TEXTS),
        "feature_code_texts": code_texts(FEATURE_TEXTS),
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
        "turn": c_list(c_float(v) for v in turn),
        "land_accel": c_float(accel[0]),
        "land_accel_w": c_float(accel[1]),
        **{f"land_{name.lower()}": c_float(getattr(landing, name)) for name in _LANDING_FLOATS},
        "land_far_us": landing.FAR_US,
        "land_chain_guard": motion_landing.CHAIN_GUARD,
        "default_slip": c_list(c_float(v) for v in landing.slip_coefficients(cfg)),
        "creep_roll": c_floats(cfg.get("creep_roll") or zero),
        "creep_rim": c_floats(cfg.get("creep_rim") or zero),
        "creep_mix": c_floats(cfg.get("creep_mix") or [[0.0] * n] * n),
    }


def features_source(cfg: dict[str, Any]) -> str:
    """The Mega's features for a robot's config: :data:`FEATURES_TEMPLATE` filled in."""
    return _features_template().substitute(_feature_fields(cfg))
