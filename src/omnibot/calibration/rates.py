"""A sweep's rates (pure functions, no I/O): each power level's steady rate and start/stop loss, and
the curve of rim speed against power they make.

From the runs of one power level (each at two or more durations) the steady rate and the start/stop
loss separate: ``amount(T) = rate * T + loss``; the loss is then smoothed over the levels as
``-(a rate + b rate^2)`` (:func:`loss_model`) and each level's rate refitted with it. A MOVE of length ``L`` at speed V lasts L / V, so
it lands on L when ``rate * L / V + loss = L``: the *effective* rate for moves of the reference
length is ``rate / (1 - loss / L)`` (the same for ROTATE and its reference angle). Times the
busiest wheel's rim factor this is a rim speed; :class:`RateCurve` holds rim speed against power,
made monotone (pool-adjacent-violators) and anchored at the dead band, and inverts it.
"""

from __future__ import annotations

import math
import statistics
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from omnibot.calibration.runs import RunResult
from omnibot.errors import ConfigError

LOSS_LIMIT = 0.5
"""The start/stop loss (or a coasting gain) is never taken as more than this fraction of the
reference amount."""


@dataclass(frozen=True)
class RatePoint:
    """One power level of a sweep: steady rate, start/stop loss and the effective rim speed."""

    power: int
    rate: float
    """Steady rate: m/s (straight) or rad/s (rotation)."""
    loss: float
    """Amount (m or rad) at zero duration: what starting and stopping add (negative: lose)."""
    effective: float
    """Rate that makes a motion of the reference amount land on it."""
    rim: float
    """Effective rim speed of the busiest wheel, m/s."""
    runs: int


def loss_model(levels: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """(a, b) of ``loss(rate) = -(a rate + b rate^2)`` fitted to per-level (rate, loss) pairs.

    Starting lags behind the power (a time constant: ``a``) and, where the motors' current limit
    caps the acceleration, by the square of the speed (``b``); coasting gives some back (a heavy
    robot that coasts far has a negative loss: a gain). One smooth model across all levels is far
    less noisy than each level's own two-point intercept (on a floor where the rollers' resistance
    varies from run to run that intercept scatters widely). With fewer than three levels one term.
    """
    pts = [(r, -loss) for r, loss in levels if r > 0]
    if not pts:
        return 0.0, 0.0
    s11 = sum(r * r for r, _ in pts)
    s12 = sum(r**3 for r, _ in pts)
    s22 = sum(r**4 for r, _ in pts)
    y1 = sum(r * g for r, g in pts)
    y2 = sum(r * r * g for r, g in pts)
    det = s11 * s22 - s12 * s12
    if len(pts) >= 3 and det > 1e-12:
        return (y1 * s22 - y2 * s12) / det, (s11 * y2 - s12 * y1) / det
    candidates = [(y1 / s11, 0.0), (0.0, y2 / s22)]  # one term only
    return min(candidates, key=lambda ab: sum((g - ab[0] * r - ab[1] * r * r) ** 2 for r, g in pts))


def rate_points(
    runs: Iterable[RunResult], reference: float, factor: dict[float, float] | float
) -> list[RatePoint]:
    """Per power level, the rates of runs measured by the truth (see the module docstring).

    Each level's two durations give a first (rate, loss); the losses are then smoothed by
    :func:`loss_model` across the levels and each level's rate refitted with its loss from the model.
    ``factor``: rim speed of the busiest wheel per unit rate, one number or per raw course (deg).
    """
    by_power: dict[int, list[RunResult]] = defaultdict(list)
    for r in runs:
        if r.power is not None and r.amount is not None:
            by_power[r.power].append(r)
    levels: list[tuple[int, list[float], list[float], float]] = []  # power, durations, mean amounts, m
    raw: list[tuple[float, float]] = []
    for power in sorted(by_power):
        group = by_power[power]
        by_t: dict[float, list[float]] = defaultdict(list)
        for r in group:
            assert r.amount is not None
            by_t[r.duration].append(r.amount)
        ts = sorted(by_t)
        means = [statistics.fmean(by_t[t]) for t in ts]
        if isinstance(factor, dict):
            m = statistics.fmean(factor[r.course_deg or 0.0] for r in group)
        else:
            m = factor
        levels.append((power, ts, means, m))
        if len(ts) >= 2:
            t_mean, a_mean = statistics.fmean(ts), statistics.fmean(means)
            sxx = sum((t - t_mean) ** 2 for t in ts)
            rate = sum((t - t_mean) * (a - a_mean) for t, a in zip(ts, means, strict=True)) / sxx
            raw.append((rate, a_mean - rate * t_mean))
    a, b = loss_model(raw)
    limit = LOSS_LIMIT * reference
    out = []
    for power, ts, means, m in levels:

        def misfit(rate: float, ts: list[float] = ts, means: list[float] = means) -> float:
            loss = min(max(-(a * rate + b * rate * rate), -limit), limit)
            return sum((x - rate * t - loss) ** 2 for t, x in zip(ts, means, strict=True))

        # amount = rate T - (a rate + b rate^2): least squares in rate
        rate = golden_min(misfit, 0.0, 3.0 * max(max(means) / min(ts), 1e-6))
        loss = min(max(-(a * rate + b * rate * rate), -limit), limit)
        effective = rate / (1.0 - loss / reference) if rate > 0 else 0.0
        out.append(RatePoint(power, rate, loss, effective, effective * m, len(by_power[power])))
    return out


def golden_min(f: Callable[[float], float], lo: float, hi: float, iterations: int = 60) -> float:
    """The minimum of a unimodal ``f`` on [lo, hi] by golden-section search."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(iterations):
        if f1 <= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - g * (hi - lo)
            f1 = f(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + g * (hi - lo)
            f2 = f(x2)
    return 0.5 * (lo + hi)


def isotonic(values: Sequence[float]) -> list[float]:
    """The non-decreasing sequence closest to ``values`` in least squares (pool adjacent violators)."""
    blocks: list[list[float]] = []  # [sum, count]
    for v in values:
        blocks.append([v, 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            s, n = blocks.pop()
            blocks[-1][0] += s
            blocks[-1][1] += n
    out: list[float] = []
    for s, n in blocks:
        out += [s / n] * int(n)
    return out


@dataclass(frozen=True)
class RateCurve:
    """Rim speed of the busiest wheel (m/s) against power: monotone, zero up to the dead band.

    Between the measured levels the curve is a monotone cubic (Fritsch-Carlson), so its bend near
    the dead band and where acceleration limits the speed is followed; beyond the last level it is
    extended linearly.
    """

    powers: tuple[float, ...]
    rims: tuple[float, ...]

    @classmethod
    def fit(cls, points: Sequence[RatePoint], deadband: int | None = None) -> RateCurve:
        """The curve through the measured ``points`` (made monotone), zero up to ``deadband``;
        ConfigError when no run moved the robot."""
        pts = sorted((p.power, p.rim) for p in points)
        if not pts or max(r for _, r in pts) <= 0.0:
            raise ConfigError(
                "no run moved the robot: nothing to fit (is the robot on the floor and powered?)"
            )
        powers = [float(p) for p, _ in pts]
        rims = isotonic([max(r, 0.0) for _, r in pts])
        _start(powers, rims, deadband)
        return cls(tuple(powers), tuple(rims))

    @property
    def deadband(self) -> float:
        """Highest power at which the curve is still zero."""
        last = self.powers[0]
        for p, r in zip(self.powers, self.rims, strict=True):
            if r > 0.0:
                break
            last = p
        return last

    @cached_property
    def _slopes(self) -> list[float]:
        """Fritsch-Carlson tangents at the points (monotone cubic Hermite)."""
        ps, rs = self.powers, self.rims
        n = len(ps)
        if n < 2:
            return [0.0] * n
        d = [(rs[i + 1] - rs[i]) / (ps[i + 1] - ps[i]) for i in range(n - 1)]
        m = (
            [d[0]]
            + [0.0 if d[i - 1] * d[i] <= 0 else 0.5 * (d[i - 1] + d[i]) for i in range(1, n - 1)]
            + [d[-1]]
        )
        if n > 2 and ps[0] == 0.0 and ps[1] == 1.0 and rs[0] == 0.0 < rs[1]:
            m[1] = d[1]  # the first count's jump (:func:`_start`): the line of the levels goes on from it
        for i in range(n - 1):
            if d[i] == 0.0:
                m[i] = m[i + 1] = 0.0
                continue
            a, b = m[i] / d[i], m[i + 1] / d[i]
            h = a * a + b * b
            if h > 9.0:
                t = 3.0 / math.sqrt(h)
                m[i], m[i + 1] = t * a * d[i], t * b * d[i]
        return m

    def rim_at(self, power: float) -> float:
        """Rim speed at ``power`` PWM counts, m/s (held below the first level, linear beyond the last)."""
        ps, rs, m = self.powers, self.rims, self._slopes
        if power <= ps[0]:
            return rs[0]
        if power >= ps[-1]:
            return rs[-1] + self._top_slope() * (power - ps[-1])
        i = next(k for k in range(1, len(ps)) if power <= ps[k])
        h = ps[i] - ps[i - 1]
        t = (power - ps[i - 1]) / h
        h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
        h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
        return h00 * rs[i - 1] + h10 * h * m[i - 1] + h01 * rs[i] + h11 * h * m[i]

    def power_for(self, rim: float) -> float:
        """The lowest power that gives ``rim`` m/s (linear beyond the last point)."""
        ps, rs = self.powers, self.rims
        if rim <= 0.0:
            return self.deadband
        if rim >= rs[-1]:
            return ps[-1] + (rim - rs[-1]) / self._top_slope()
        i = next(k for k in range(1, len(ps)) if rim <= rs[k] and rs[k] > rs[k - 1])
        lo, hi = ps[i - 1], ps[i]
        for _ in range(50):  # bisection on the monotone cubic
            mid = 0.5 * (lo + hi)
            if self.rim_at(mid) < rim:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    def _top_slope(self) -> float:
        """rim per power for extrapolation: the chord over the upper half of the curve (robust to a
        flat or noisy last level)."""
        ps, rs = self.powers, self.rims
        top = rs[-1]
        if top <= 0.0:
            return 1e-3
        j = next(i for i, r in enumerate(rs) if r >= 0.5 * top)
        if j == len(ps) - 1:
            j = max(0, j - 1)
        slope = (top - rs[j]) / (ps[-1] - ps[j]) if ps[-1] > ps[j] else 0.0
        return max(slope, 1e-4)

    def with_point(self, power: float, rim: float) -> RateCurve:
        """The curve with (``power``, ``rim``) measured as well: the point added (replacing a level
        at the same power) and the curve made monotone again."""
        deadband = self.deadband
        pts = sorted(
            [(p, r) for p, r in zip(self.powers, self.rims, strict=True) if p != power and p > 1.0]
            + [(power, rim)]
        )  # the start (at most the first count, :func:`_start`) drawn again through the new point
        powers = [p for p, _ in pts]
        rims = isotonic([r for _, r in pts])
        _start(powers, rims, deadband)
        return RateCurve(tuple(powers), tuple(rims))

    def slope_k(self) -> float:
        """PWM counts per m/s of rim speed over the upper half of the curve: the motor's K."""
        pairs = [(p, r) for p, r in zip(self.powers, self.rims, strict=True) if r >= 0.3 * self.rims[-1]]
        if len(pairs) < 2:
            pairs = list(zip(self.powers, self.rims, strict=True))[-2:]
        pm = statistics.fmean(p for p, _ in pairs)
        rm = statistics.fmean(r for _, r in pairs)
        srr = sum((r - rm) ** 2 for _, r in pairs)
        if srr <= 0.0:
            return self.powers[-1] / max(self.rims[-1], 1e-6)
        return sum((p - pm) * (r - rm) for p, r in pairs) / srr

    def as_dict(self) -> dict[str, Any]:
        """The measured levels as plain data."""
        return {"powers": list(self.powers), "rims": list(self.rims)}


def _start(powers: list[float], rims: list[float], deadband: float | None) -> None:
    """Where the curve through the levels ``powers``, ``rims`` (sorted, made monotone) starts: the
    points below its first level inserted in place.

    The dead band is where a short run from rest turns the robot visibly. Where the line through the
    first two levels reaches zero lower (through a motor map, whose offsets already make up the
    friction, the robot runs steadily at no power above them), the curve starts there: anchored at
    the dead band its first segment would be steeper than the levels above and the cubic would bulge
    over them, under-powering slow ROTATEs. Where that line reaches zero below the first count, the
    first count already carries the robot at the line's speed there (the firmware ramps a motor's
    offset in over its first count, so the power jumps from 0 to the offset and one count): the curve
    jumps from (0, 0) to that point, where it went to (0, 0) in a line before and so gave slow MOVEs
    too much power (mecanum4 forward on carpet at 0.1 m/s: +12 %, its first count 0.078 m/s)."""
    if not powers or rims[0] <= 0.0:
        return
    slope = next(
        ((rims[i] - rims[0]) / (powers[i] - powers[0]) for i in range(1, len(powers)) if rims[i] > rims[0]),
        None,
    )
    zero = powers[0] - rims[0] / slope if slope is not None else powers[0] - 1.0
    if slope is not None and zero < 1.0 < powers[0] and (deadband is None or deadband < powers[0]):
        first = rims[0] - slope * (powers[0] - 1.0)
        powers[:0] = [0.0, 1.0]
        rims[:0] = [0.0, first]
        return
    if deadband is not None and deadband < powers[0]:
        zero = min(float(deadband), zero)
    powers.insert(0, max(0.0, zero))
    rims.insert(0, 0.0)


# --------------------------------------------------------------------------- factor tables
