"""Battery chemistries: per-cell voltages, default thresholds and the open-circuit voltage curve.

Pure data and functions (no I/O): the robot description takes its default thresholds from
:data:`CHEMISTRIES`, and the simulator its open-circuit voltage as the pack's state of charge falls
(:func:`open_voltage`). Figures per cell, volts.

The thresholds are those hobby chargers, ESCs and flight controllers use under load: a 2S/3S Li-Po
warns at 3.5 V a cell, limits power at 3.4 and cuts at 3.3 (BLHeli's and Betaflight's low-voltage
cut-offs sit at 3.0-3.3 V a cell, ArduPilot's ``BATT_LOW_VOLT`` defaults to 3.5 V a cell on its
templates); a pack rests 0.1-0.3 V a cell above what it reads under load, which is why the stop is
latched and released only above the stop threshold plus a hysteresis.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass


@dataclass(frozen=True)
class Chemistry:
    """One cell chemistry: nominal and full voltage, default thresholds, rest-voltage curve."""

    nominal: float
    full: float
    warn: float
    limit: float
    stop: float
    hysteresis: float
    curve: tuple[tuple[float, float], ...]  # (state of charge 0..1, open-circuit V), ascending


CHEMISTRIES: dict[str, Chemistry] = {
    # Li-Po rest voltage against state of charge (the hobby charts' table; 3.7 V near 20 %)
    "lipo": Chemistry(
        3.7,
        4.2,
        3.5,
        3.4,
        3.3,
        0.05,
        (
            (0.0, 3.27),
            (0.05, 3.5),
            (0.10, 3.6),
            (0.20, 3.7),
            (0.30, 3.75),
            (0.40, 3.8),
            (0.50, 3.85),
            (0.60, 3.92),
            (0.70, 3.99),
            (0.80, 4.06),
            (0.90, 4.13),
            (1.0, 4.2),
        ),
    ),
    "liion": Chemistry(
        3.6,
        4.2,
        3.4,
        3.2,
        3.0,
        0.05,
        ((0.0, 3.0), (0.05, 3.3), (0.10, 3.45), (0.20, 3.55), (0.50, 3.7), (0.80, 3.95), (1.0, 4.2)),
    ),
    "life": Chemistry(
        3.2,
        3.65,
        3.0,
        2.9,
        2.8,
        0.05,
        ((0.0, 2.5), (0.05, 3.0), (0.10, 3.2), (0.20, 3.25), (0.50, 3.3), (0.90, 3.35), (1.0, 3.4)),
    ),
    "nimh": Chemistry(
        1.2,
        1.4,
        1.1,
        1.05,
        1.0,
        0.02,
        ((0.0, 0.9), (0.05, 1.05), (0.10, 1.1), (0.20, 1.18), (0.50, 1.23), (0.90, 1.3), (1.0, 1.4)),
    ),
}


def open_voltage(chemistry: str, cells: int, charge: float) -> float:
    """The pack's open-circuit voltage at state of charge ``charge`` (clamped to 0..1), V."""
    curve = CHEMISTRIES[chemistry].curve
    q = min(max(charge, 0.0), 1.0)
    k = min(max(bisect_right([c[0] for c in curve], q) - 1, 0), len(curve) - 2)
    (q0, v0), (q1, v1) = curve[k], curve[k + 1]
    return cells * (v0 + (v1 - v0) * (q - q0) / (q1 - q0))


LEVELS = ("ok", "low", "limited", "flat")
"""What a front end shows: above warn; below warn (WARN 19); below limit, power limited (WARN 20);
the battery stop latched (WARN 43, STATUS state 4) or below the stop threshold."""


def battery_level(
    volts: float | None, warn_v: float, limit_v: float, stop_v: float, stopped: bool = False
) -> str:
    """The battery's level for a front end from a reading (V) and the thresholds; ``stopped``: the
    controller reports its battery stop latched. ``unknown`` without a reading (0 V: not measured)."""
    if stopped:
        return "flat"
    if volts is None or volts <= 0.0:
        return "unknown"
    if volts < stop_v:
        return "flat"
    if volts < limit_v:
        return "limited"
    if volts < warn_v:
        return "low"
    return "ok"
