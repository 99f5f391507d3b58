"""Typed commands from SI values: conversion to protocol units, rounding and range checks (pure).

Every builder converts with :mod:`omnibot.protocol.units`, rounds to the protocol's resolution and
checks the result against :class:`~omnibot.client.limits.Limits`, raising ValueError (naming the
parameter, the value given, what it became and the allowed range) before anything is sent.

Resolution (what a value is rounded to):

=====================  ===========================  ====================================
quantity               SI argument                  protocol step
=====================  ===========================  ====================================
distance               m (math.inf: endless)        1 cm
speed, vx, vy          m/s                          1 cm/s
course, angle          rad (math.inf: endless)      1 degree
rate, w                rad/s                        1 degree/s
curvature              1/m                          0.1 1/m (C = 1/(1000 cm))
time, period, timeout  s                            1 ms
sonar distances        m                            1 cm
=====================  ===========================  ====================================

The builders return the command exactly as it is sent, so a caller can see what rounding did.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

from omnibot.client.limits import Limits
from omnibot.estimation import SlipParameters
from omnibot.protocol import codes, units
from omnibot.protocol.messages import Cal, Delta, Mode, Move, Power, Rotate, Sonar, Telem, Vel
from omnibot.robot import CalibrationSpec, MotorMapSpec, PiecewiseLinear, ReachSpec, RollerDragSpec

INF = codes.INF
TIME_MAX_MS = 30000  # POWER T, SONAR and TELEM periods
VEL_TIME_MAX_MS = 1000
SONAR_CM_MAX = 500


def _convert(what: str, value: float, convert: Callable[[float], int], unit: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"{what}: expected a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{what}: expected a finite number, got {value}")
    out = convert(value)
    if not codes.INT_MIN <= out <= codes.INT_MAX:
        raise ValueError(f"{what} {value:g} is {out} {unit}, outside the protocol's 16-bit range")
    return out


def _endless(what: str, value: float, convert: Callable[[float], int], unit: str) -> int:
    """Like _convert, but +-inf becomes +-INF (endless motion)."""
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isinf(value):
        return INF if value > 0 else -INF
    out = _convert(what, value, convert, unit)
    if abs(out) >= INF:
        raise ValueError(
            f"{what} {value:g} is {out} {unit}; finite values must stay below {INF} (use math.inf)"
        )
    return out


def _fail(what: str, value: float, out: int, unit: str, allowed: str) -> ValueError:
    return ValueError(f"{what} {value:g} is {out} {unit}, outside {allowed}")


def _check_move(
    limits: Limits, name: str, L: int, V: int, D: int, C: int, k: int, given: Sequence[float]
) -> None:
    """The firmware's MOVE checks (k = 1) and DELTA increment checks (k = 2)."""
    if abs(L) >= limits.distance_max_cm * k and not (k == 1 and abs(L) == INF):
        raise _fail(f"{name} distance", given[0], L, "cm", f"abs(L) < {limits.distance_max_cm * k:g} cm")
    if k == 1:
        if V == 0 or not limits.speed_min_cms <= abs(V) <= limits.speed_max_cms:
            allowed = f"{limits.speed_min_cms:g} <= abs(V) <= {limits.speed_max_cms:g} cm/s"
            raise _fail(f"{name} speed", given[1], V, "cm/s", allowed)
    elif abs(V) > limits.speed_max_cms * k:
        raise _fail(f"{name} speed", given[1], V, "cm/s", f"abs(V) <= {limits.speed_max_cms * k:g} cm/s")
    if abs(D) >= 360 * k:
        raise _fail(f"{name} course", given[2], D, "degrees", f"abs(D) < {360 * k}")
    if abs(C) >= limits.curvature_max * k:
        raise _fail(f"{name} curvature", given[3], C, "1/(1000 cm)", f"abs(C) < {limits.curvature_max * k:g}")


def move(limits: Limits, distance: float, speed: float, course: float = 0.0, curvature: float = 0.0) -> Move:
    """MOVE: ``distance`` m (math.inf: until the next command; the sign of distance x speed picks
    forth or back), ``speed`` m/s, ``course`` rad from the head, ``curvature`` 1/m."""
    L = _endless("MOVE distance", distance, units.to_cm, "cm")
    V = _convert("MOVE speed", speed, units.to_cm, "cm/s")
    D = _convert("MOVE course", course, units.to_deg, "degrees")
    C = _convert("MOVE curvature", curvature, units.to_curvature, "1/(1000 cm)")
    _check_move(limits, "MOVE", L, V, D, C, 1, (distance, speed, course, curvature))
    return Move(L, V, D, C)


def delta(
    limits: Limits,
    distance: float = 0.0,
    speed: float = 0.0,
    course: float = 0.0,
    curvature: float = 0.0,
    repeat: float = 0,
) -> Delta:
    """DELTA: increments to the remembered MOVE (same units as :func:`move`), run max(repeat, 1)
    times; ``repeat`` an integer 0..30000 or math.inf (until the next command)."""
    L = _convert("DELTA distance", distance, units.to_cm, "cm")
    V = _convert("DELTA speed", speed, units.to_cm, "cm/s")
    D = _convert("DELTA course", course, units.to_deg, "degrees")
    C = _convert("DELTA curvature", curvature, units.to_curvature, "1/(1000 cm)")
    _check_move(limits, "DELTA", L, V, D, C, 2, (distance, speed, course, curvature))
    if isinstance(repeat, float) and math.isinf(repeat) and repeat > 0:
        R = INF
    elif isinstance(repeat, int) and not isinstance(repeat, bool) and 0 <= repeat <= INF:
        R = repeat
    else:
        raise ValueError(f"DELTA repeat: expected an integer 0..{INF} or math.inf, got {repeat!r}")
    return Delta(L, V, D, C, R)


def rotate(limits: Limits, angle: float, rate: float) -> Rotate:
    """ROTATE: ``angle`` rad (math.inf: until the next command) at ``rate`` rad/s; the sign of
    angle x rate picks the direction (positive: counter-clockwise)."""
    A = _endless("ROTATE angle", angle, units.to_deg, "degrees")
    F = _convert("ROTATE rate", rate, units.to_deg, "degrees/s")
    if F == 0 or abs(F) >= limits.rate_max_dps:
        raise _fail("ROTATE rate", rate, F, "degrees/s", f"0 < abs(F) < {limits.rate_max_dps:g}")
    return Rotate(A, F)


def power(limits: Limits, time: float, powers: Sequence[int]) -> Power:
    """POWER: raw motor powers (integers -pwm_max..pwm_max, one per motor) for ``time`` s."""
    T = _convert("POWER time", time, units.to_ms, "ms")
    if not 1 <= T <= TIME_MAX_MS:
        raise _fail("POWER time", time, T, "ms", f"1..{TIME_MAX_MS} ms")
    values = tuple(powers)
    want = limits.motors
    if not 1 <= len(values) <= codes.MOTORS_MAX or (want is not None and len(values) != want):
        count = f"{want}" if want is not None else f"1..{codes.MOTORS_MAX}"
        raise ValueError(f"POWER: expected {count} powers (one per motor), got {len(values)}")
    for i, p in enumerate(values, 1):
        if isinstance(p, bool) or not isinstance(p, int):
            raise TypeError(f"POWER power {i}: expected an integer PWM count, got {p!r}")
        if abs(p) > limits.pwm_max:
            raise ValueError(f"POWER power {i} = {p}, outside -{limits.pwm_max}..{limits.pwm_max}")
    return Power(T, values)


def vel(
    limits: Limits,
    vx: float,
    vy: float,
    w: float,
    timeout: float,
    accel: float = 0.0,
    body_accel: tuple[float, float, float] | None = None,
) -> Vel:
    """VEL: hold body velocity ``vx``, ``vy`` m/s and ``w`` rad/s for at most ``timeout`` s
    (0.001..1) unless refreshed; the motors stop when it runs out (watchdog). ``accel``: the planned
    rate of change of the speed hypot(vx, vy), m/s^2, along (vx, vy) (protocol version 3);
    ``body_accel``: the body's planned acceleration (m/s^2 along its x and y axes, the centre's in
    the world; rad/s^2) (version 4; not with ``accel``). The controller's wheel-speed loop feeds
    their torque forward (docs/protocol.md)."""
    if accel and body_accel is not None:
        raise ValueError("VEL: give accel (version 3) or body_accel (version 4), not both")
    A = _convert("VEL accel", accel, units.to_cm, "cm/s^2") if accel else 0
    body = None
    if body_accel is not None:
        ax, ay, aw = body_accel
        body = (
            _convert("VEL body_accel x", ax, units.to_cm, "cm/s^2"),
            _convert("VEL body_accel y", ay, units.to_cm, "cm/s^2"),
            _convert("VEL body_accel w", aw, units.to_deg, "degrees/s^2"),
        )
    VX = _convert("VEL vx", vx, units.to_cm, "cm/s")
    VY = _convert("VEL vy", vy, units.to_cm, "cm/s")
    W = _convert("VEL w", w, units.to_deg, "degrees/s")
    T = _convert("VEL timeout", timeout, units.to_ms, "ms")
    if limits.speed_max_cms**2 < (VX * VX + VY * VY):
        speed = math.hypot(vx, vy)
        if speed * 100.0 > limits.speed_max_cms:
            raise ValueError(f"VEL speed {speed:g} m/s exceeds the robot's {limits.speed_max_cms:g} cm/s")
        # within the limit as asked, past it only as its parts rounded to whole cm/s (0.707, 0.707 ->
        # 71, 71 cm/s: 100.4): each part rounded towards zero instead, still within 1 cm/s of it
        VX, VY = math.trunc(vx * 100.0), math.trunc(vy * 100.0)
    if abs(W) >= limits.rate_max_dps:
        raise _fail("VEL w", w, W, "degrees/s", f"abs(W) < {limits.rate_max_dps:g}")
    if not 1 <= T <= VEL_TIME_MAX_MS:
        raise _fail("VEL timeout", timeout, T, "ms", f"1..{VEL_TIME_MAX_MS} ms")
    return Vel(VX, VY, W, T, A, body)


def mode(limits: Limits, mask: int) -> Mode:
    """MODE without the binary bit (switch protocols with RobotClient.use_binary/use_text)."""
    if isinstance(mask, bool) or not isinstance(mask, int):
        raise TypeError(f"MODE mask: expected an integer, got {mask!r}")
    if mask & codes.MODE_BINARY:
        raise ValueError("MODE bit 2 (binary) is switched with use_binary() / use_text()")
    if mask & ~codes.MODE_MASK or mask < 0:
        raise ValueError(f"MODE mask {mask}: only bits 0..5 exist (docs/protocol.md, MODE bits)")
    if mask & codes.MODE_CLOSED_LOOP and limits.has_encoders is False:
        raise ValueError(f"MODE closed loop needs motor encoders, which robot {limits.robot} lacks")
    return Mode(mask)


def sonar(
    limits: Limits, number: int, period: float, low: float = 0.0, high: float = 0.0, stop: float = 0.0
) -> Sonar:
    """SONAR: sonar ``number`` (1..k, as in the protocol) measures every ``period`` s (0: off);
    RANGE events for readings in [low, high] m (outside it when low > high); a reading below
    ``stop`` m while moving stops the robot and latches (0: off)."""
    if isinstance(number, bool) or not isinstance(number, int):
        raise TypeError(f"SONAR number: expected an integer, got {number!r}")
    periods = limits.sonar_period_min_ms
    if number < 1 or (periods is not None and number > len(periods)):
        count = f"1..{len(periods)}" if periods is not None else ">= 1"
        raise ValueError(f"SONAR number {number}: the robot's sonars are numbered {count}")
    P = _convert("SONAR period", period, units.to_ms, "ms")
    minimum = periods[number - 1] if periods is not None else 60
    if P != 0 and not minimum <= P <= TIME_MAX_MS:
        raise _fail("SONAR period", period, P, "ms", f"0 (off) or {minimum}..{TIME_MAX_MS} ms")
    cm = []
    for what, value in (("low", low), ("high", high), ("stop", stop)):
        out = _convert(f"SONAR {what}", value, units.to_cm, "cm")
        if not 0 <= out <= SONAR_CM_MAX:
            raise _fail(f"SONAR {what}", value, out, "cm", f"0..{SONAR_CM_MAX} cm")
        cm.append(out)
    return Sonar(number, P, cm[0], cm[1], cm[2])


def telem(limits: Limits, period: float, mask: int = codes.TEL_MASK) -> Telem:
    """TELEM: a TEL line every ``period`` s (0: off; else 0.01..30) with the groups of ``mask``."""
    P = _convert("TELEM period", period, units.to_ms, "ms")
    if P != 0 and not codes.TEL_PERIOD_MIN <= P <= TIME_MAX_MS:
        raise _fail("TELEM period", period, P, "ms", f"0 (off) or {codes.TEL_PERIOD_MIN}..{TIME_MAX_MS} ms")
    if isinstance(mask, bool) or not isinstance(mask, int) or mask & ~codes.TEL_MASK or mask < 0:
        raise ValueError(f"TELEM mask {mask!r}: expected an integer 0..{codes.TEL_MASK}")
    return Telem(P, mask)


def cal(limits: Limits, table: int, index: int, x: int, y: int) -> Cal:
    """CAL with protocol integers (docs/protocol.md, CAL); the controller checks the knot order."""
    for what, value in (("table", table), ("index", index), ("x", x), ("y", y)):
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"CAL {what}: expected an integer, got {value!r}")
        if not codes.INT_MIN <= value <= codes.INT_MAX:
            raise ValueError(f"CAL {what} {value} is outside the protocol's 16-bit range")
    return Cal(table, index, x, y)


def _knots(table: int, curve: PiecewiseLinear) -> list[Cal]:
    return [
        Cal(table, i, round(x), units.to_milli(y))
        for i, (x, y) in enumerate(zip(curve.x, curve.y, strict=True))
    ]


def _reach(reach: ReachSpec | None) -> list[Cal]:
    """The reach's CAL table 8 knots (course degrees, cm/s); none: one knot of 0 (no reach known)."""
    if reach is None:
        return [Cal(codes.CAL_REACH, 0, 0, 0)]
    xs = [round(c) for c in reach.courses_deg]
    if any(b <= a for a, b in itertools.pairwise(xs)) or not 0 <= xs[0] <= xs[-1] <= codes.CAL_COURSE_MAX:
        raise ValueError(f"reach: courses {list(reach.courses_deg)} are not 1 degree apart within 0..90")
    return [
        Cal(codes.CAL_REACH, i, x, max(1, math.floor(100.0 * v + 1e-6)))
        for i, (x, v) in enumerate(zip(xs, reach.speed, strict=True))
    ]


def slip(params: SlipParameters) -> list[Cal]:
    """CAL table 9: the floor's wheel creep (roll, combined, scale, ramp) that a closed-loop MOVE's
    landing takes out of its encoders (docs/firmware.md, landing)."""
    values = (
        ("roll", round(params.roll * 1e5)),
        ("combined", round(params.combined * codes.CAL_SLIP_SCALE)),
        ("scale", round(params.scale * codes.CAL_SLIP_SCALE)),
        ("ramp", round(params.ramp * 1e6)),
    )
    for what, y in values:
        if not 0 <= y <= codes.INT_MAX:
            raise ValueError(f"slip {what} {getattr(params, what)} does not fit CAL table 9")
    return [Cal(codes.CAL_SLIP, i, 0, y) for i, (_, y) in enumerate(values)]


def calibration(spec: CalibrationSpec, motors: int | None = None) -> list[Cal]:
    """The CAL commands that upload a calibration section: K, then K_t, K_r, K_l (knot 0 upwards,
    dropping curves the controller may hold beyond the section's), then the motor map and the roller
    drag, then the reach. A section without them uploads the identity map, no drag and no reach when
    the robot's ``motors`` are known, so the controller uses exactly the section."""
    out = [Cal(codes.CAL_K, 0, 0, units.to_cal_k(spec.k))]
    if spec.k_t is not None:
        out += _knots(codes.CAL_KT, spec.k_t)
    if spec.k_r is not None:
        out += _knots(codes.CAL_KR, spec.k_r)
    if spec.k_l is not None:
        if len(spec.k_l.curves) > codes.CAL_KL_CURVES:
            raise ValueError(f"K_l: at most {codes.CAL_KL_CURVES} curves can be uploaded")
        for k, (course, curve) in enumerate(zip(spec.k_l.courses_deg, spec.k_l.curves, strict=True)):
            out.append(Cal(codes.CAL_KL + k, -1, round(course), 0))
            out += _knots(codes.CAL_KL + k, curve)
        n = len(spec.k_l.curves)
        if n < codes.CAL_KL_CURVES:
            out.append(Cal(codes.CAL_KL + n, codes.CAL_KL_DROP, 0, 0))
    motor_map = spec.motors
    if motor_map is None and motors is not None:
        flat = PiecewiseLinear(x=(0.0,), y=(1.0,))
        motor_map = MotorMapSpec(offset=(0.0,) * motors, gain=(flat,) * motors)
    if motor_map is not None:
        n = len(motor_map.gain)
        if n > codes.CAL_MOTORS or (motors is not None and n != motors):
            raise ValueError(f"motor map: {n} motors for a robot with {motors} (at most {codes.CAL_MOTORS})")
        for i, (offset, gain) in enumerate(zip(motor_map.offset, motor_map.gain, strict=True)):
            out.append(Cal(codes.CAL_OFFSET, i, 0, round(10 * offset)))
            out += _knots(codes.CAL_GAIN + i, gain)
            out.append(Cal(codes.CAL_SPEED, i, 0, round(10 * motor_map.speed_term(i))))
    rollers = spec.rollers
    if rollers is None and motors is not None:
        rollers = RollerDragSpec(cos=(0.0,) * motors, sin=(0.0,) * motors)
    if rollers is not None:
        n = len(rollers.cos)
        if motors is not None and n != motors:
            raise ValueError(f"roller drag: {n} wheels for a robot with {motors}")
        for i, (a, b) in enumerate(zip(rollers.cos, rollers.sin, strict=True)):
            out.append(Cal(codes.CAL_ROLLER_COS, i, 0, round(10 * a)))
            out.append(Cal(codes.CAL_ROLLER_SIN, i, 0, round(10 * b)))
        coast = rollers.coast or PiecewiseLinear(x=(0.0,), y=(0.0,))
        xs = [round(100.0 * x) for x in coast.x]
        if any(b <= a for a, b in itertools.pairwise(xs)):
            raise ValueError(f"roller coast: speeds {list(coast.x)} m/s are not 1 cm/s apart")
        for i, (x, y) in enumerate(zip(xs, coast.y, strict=True)):
            out.append(Cal(codes.CAL_ROLLER_COAST, i, x, units.to_milli(y)))
    if spec.reach is not None or motors is not None:
        out += _reach(spec.reach)
    for c in out:
        if not all(codes.INT_MIN <= p <= codes.INT_MAX for p in c.params()):
            raise ValueError(f"CAL {c.params()}: a value is outside the protocol's 16-bit range")
    return out
