"""Seeded smooth random paths: what a user might teach, for tests and the tracking benchmark.

A path is built from two smooth random functions of the arc length s, each a sum of a few sine
waves with random wavelengths (between ``wavelength`` and 3x it), amplitudes and phases:

* the **curvature** kappa(s), scaled so that |kappa| <= 1 / ``radius_min`` everywhere; the direction
  of travel is its integral and the position the integral of the direction, so position, direction
  and curvature are all continuous (C-infinity between the ends);
* the **heading** theta(s) the body holds: ``"fixed"`` (the start heading), ``"tangent"`` (the
  direction of travel, the body turning with the course) or ``"swing"`` (a second random function
  of at most ``swing`` rad either side of the start heading, independent of the course, whose
  rate is at most ``swing_rate`` rad per metre).

Every path starts at the origin travelling along +x. The same seed and arguments give the same path
(``numpy.random.default_rng(seed)``). The bounds are geometric: the time-optimal profile
(:mod:`~omnibot.control.paths.profile`) turns them into speeds within the robot's limits (lateral
grip, turn rate, heading acceleration), so a path is feasible for any robot whose curvature limit
is at least 1 / ``radius_min``.
"""

from __future__ import annotations

import math

import numpy as np

from omnibot.control.paths.path import FloatArray, Path, tangent_headings
from omnibot.errors import ConfigError

GENERATED_HEADINGS = ("fixed", "tangent", "swing")
WAVES = 4
"""Sine waves per random function."""


def _smooth_function(
    rng: np.random.Generator, s: FloatArray, wavelength: float
) -> tuple[FloatArray, FloatArray]:
    """A random smooth function of ``s`` scaled to |f| <= 1 (a bound, not its maximum), and f'."""
    lam = wavelength * rng.uniform(1.0, 3.0, WAVES)
    amp = rng.uniform(0.3, 1.0, WAVES) * rng.choice((-1.0, 1.0), WAVES)
    phase = rng.uniform(0.0, 2.0 * math.pi, WAVES)
    k = 2.0 * math.pi / lam
    arg = np.outer(s, k) + phase
    bound = float(np.sum(np.abs(amp)))
    f = np.sin(arg) @ amp / bound
    df = np.cos(arg) @ (amp * k) / bound
    return f, df


def smooth_random_path(
    seed: int,
    *,
    length: float = 4.0,
    radius_min: float = 0.5,
    wavelength: float | None = None,
    heading: str = "swing",
    swing: float = 0.5 * math.pi,
    swing_rate: float = 2.0,
    spacing: float = 0.01,
) -> Path:
    """A smooth pseudo-random path of ``length`` m for ``seed`` (see the module docstring).

    ``wavelength`` (m, default 4 ``radius_min``) is the shortest wavelength of the curvature's
    and the swing's variation; ``swing`` (rad) bounds the swing either side of the start heading
    and ``swing_rate`` (rad/m) its rate along the path.
    """
    if heading not in GENERATED_HEADINGS:
        raise ConfigError(
            f"unknown heading mode '{heading}'; expected one of: {', '.join(GENERATED_HEADINGS)}"
        )
    _check_sizes("random", length, radius_min, spacing, swing, swing_rate)
    wave = 4.0 * radius_min if wavelength is None else wavelength
    if not (math.isfinite(wave) and wave > 0):
        raise ConfigError(f"random path wavelength must be a positive number, got {wavelength}")
    rng = np.random.default_rng(seed)
    n = max(2, math.ceil(length / spacing) + 1)
    s = np.linspace(0.0, length, n)
    shape, _ = _smooth_function(rng, s, wave)
    kappa = shape / radius_min
    # direction and position: trapezoidal integrals (exact to O(spacing^2) for these smooth functions)
    ds = np.diff(s)
    direction = np.concatenate(([0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * ds)))
    mid = direction[:-1] + 0.5 * np.diff(direction)
    x = np.concatenate(([0.0], np.cumsum(np.cos(mid) * ds)))
    y = np.concatenate(([0.0], np.cumsum(np.sin(mid) * ds)))
    swing_fn, swing_d = _smooth_function(rng, s, wave)
    if heading == "fixed":
        theta = np.zeros(n)
    elif heading == "tangent":
        theta = direction
    else:
        # g = (f - f(0)) / 2 starts at 0 and stays within +-1; its amplitude is cut so that the
        # rate |d theta/ds| = amplitude |g'| stays within swing_rate where g' peaks
        g, dg = 0.5 * (swing_fn - swing_fn[0]), 0.5 * swing_d
        peak = float(np.max(np.abs(dg)))
        amplitude = min(swing, swing_rate / peak) if peak > 0 else swing
        theta = amplitude * g
    return Path(x, y, theta)


CLOSED_SAMPLES = 20_000
"""Samples of the curve's parameter before the path is resampled by arc length."""
EIGHT_KINDS = {"gerono": (0.35, 1.2, 0.6), "bernoulli": (0.6, 2.0, 1.1)}
"""Per lemniscate: the range of its aspect (the y scale of the unit curve) and its roundest one (the
largest least radius of curvature for its length: 0.049 and 0.064 of it)."""
TRIES = 40
"""Times a closed shape is smoothed (or a figure eight made rounder) to meet ``radius_min``."""


def _check_sizes(
    kind: str, length: float, radius_min: float, spacing: float, swing: float, swing_rate: float
) -> None:
    """A generated path's sizes, or a ConfigError naming the ``kind`` of path and the bad one."""
    for name, value in (
        ("length", length),
        ("radius_min", radius_min),
        ("spacing", spacing),
        ("swing_rate", swing_rate),
    ):
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f"{kind} path {name} must be a positive number, got {value}")
    if not (math.isfinite(swing) and swing >= 0):
        raise ConfigError(f"{kind} path swing must be a non-negative number of radians, got {swing}")
    if length / spacing > 200_000:
        raise ConfigError(
            f"{kind} path of {length:g} m at {spacing:g} m spacing is too long; at most 200,000 points"
        )


def _check_closed(length: float, radius_min: float, spacing: float, swing: float, swing_rate: float) -> None:
    _check_sizes("closed", length, radius_min, spacing, swing, swing_rate)
    if length < 2.0 * math.pi * radius_min:
        raise ConfigError(
            f"a closed path of {length:g} m cannot keep a radius of curvature of {radius_min:g} m "
            f"(a circle of that radius is {2 * math.pi * radius_min:.3g} m round)"
        )


def _loop_radius(xy: FloatArray) -> tuple[float, FloatArray]:
    """The least radius of curvature of a closed curve sampled at equal parameter steps (the last
    sample repeats the first), and its cumulative arc length."""
    p = xy[:-1]
    d1 = 0.5 * (np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0))
    d2 = np.roll(p, -1, axis=0) - 2.0 * p + np.roll(p, 1, axis=0)
    speed = np.hypot(d1[:, 0], d1[:, 1])
    kappa = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(speed, 1e-300) ** 3
    s = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))))
    return 1.0 / float(np.max(kappa)), s


def _closed_path(
    rng: np.random.Generator,
    xy: FloatArray,
    length: float,
    heading: str,
    swing: float,
    swing_rate: float,
    spacing: float,
) -> Path:
    """The closed curve ``xy`` (scaled to ``length``, its start moved to the origin and turned to
    travel along +x) as a path of ``spacing`` m with a ``heading`` column; the last point is the first."""
    _, s = _loop_radius(xy)
    xy = (xy - xy[0]) * (length / s[-1])
    d = xy[1] - xy[-2]
    a = -math.atan2(d[1], d[0])
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    xy = xy @ rot.T
    xy[-1] = xy[0]
    s = s * (length / s[-1])
    n = max(3, math.ceil(length / spacing) + 1)
    grid = np.linspace(0.0, length, n)
    x, y = np.interp(grid, s, xy[:, 0]), np.interp(grid, s, xy[:, 1])
    if heading == "fixed":
        theta = np.zeros(n)
    elif heading == "tangent":
        theta = tangent_headings(x, y)
        # closed: the direction at both ends is the start's, the turns made on the way between
        theta[0], theta[-1] = 0.0, round((theta[-2] + (theta[-2] - theta[-3])) / (2 * math.pi)) * 2 * math.pi
    else:
        periods = int(rng.integers(1, 4))
        amplitude = min(swing, swing_rate * length / (2.0 * math.pi * periods))
        theta = amplitude * np.sin(2.0 * math.pi * periods * grid / length)
    return Path(x, y, theta)


def _pick_heading(rng: np.random.Generator, heading: str) -> str:
    if heading == "random":
        return str(rng.choice(GENERATED_HEADINGS))
    if heading not in GENERATED_HEADINGS:
        raise ConfigError(
            f"unknown heading mode '{heading}'; expected random or one of: {', '.join(GENERATED_HEADINGS)}"
        )
    return heading


def figure_eight_path(
    seed: int,
    *,
    length: float = 10.0,
    radius_min: float = 0.4,
    heading: str = "random",
    swing: float = 0.5 * math.pi,
    swing_rate: float = 2.0,
    spacing: float = 0.01,
) -> Path:
    """A seeded figure eight of ``length`` m: one lap of a lemniscate of Gerono or of Bernoulli
    (``seed`` picks which), of random aspect (:data:`EIGHT_KINDS`), left or right lobe first, from
    its crossing at the origin along +x and back there.

    Its least radius of curvature is at least ``radius_min`` (the aspect is made rounder, step by
    step, until it is; a figure eight needs ``length`` >= 16 ``radius_min``, else ConfigError). ``heading``: ``"random"`` (the seed picks one of the following), ``"fixed"``,
    ``"tangent"`` or ``"swing"`` (1-3 sine periods a lap, within ``swing`` rad and ``swing_rate``
    rad/m). Closed and C-infinity: position, direction and curvature continue across the join.
    """
    _check_closed(length, radius_min, spacing, swing, swing_rate)
    rng = np.random.default_rng(seed)
    kind = str(rng.choice(list(EIGHT_KINDS)))
    low, high, roundest = EIGHT_KINDS[kind]
    aspect = float(np.exp(rng.uniform(math.log(low), math.log(high))))
    side = float(rng.choice((-1.0, 1.0)))
    mode = _pick_heading(rng, heading)
    t = np.linspace(0.0, 2.0 * math.pi, CLOSED_SAMPLES + 1)
    for _ in range(TRIES):
        if kind == "gerono":
            x, y = np.sin(t), np.sin(t) * np.cos(t)
        else:  # Bernoulli's, from its crossing (t = pi/2 in the usual parametrisation)
            d = 1.0 + np.cos(t) ** 2
            x, y = np.sin(t) / d, np.sin(t) * np.cos(t) / d
        xy = np.column_stack((x, side * aspect * y))
        radius, s = _loop_radius(xy)
        if radius * length / s[-1] >= radius_min:
            return _closed_path(rng, xy, length, mode, swing, swing_rate, spacing)
        aspect = math.exp(0.8 * math.log(aspect) + 0.2 * math.log(roundest))
    raise ConfigError(f"a figure eight of {length:g} m cannot keep a radius of curvature of {radius_min:g} m")


def closed_curve_path(
    seed: int,
    *,
    length: float = 6.0,
    radius_min: float = 0.4,
    harmonics: int = 5,
    heading: str = "random",
    swing: float = 0.5 * math.pi,
    swing_rate: float = 2.0,
    spacing: float = 0.01,
) -> Path:
    """A seeded closed free-form curve of ``length`` m: r(phi) = 1 + sum c_k cos(k phi + p_k) for k
    = 1..``harmonics`` with random c_k (sum |c_k| <= 0.6) and p_k, counter-clockwise or clockwise.

    Star-shaped around its centre (r > 0), so it never crosses itself; C-infinity, so position,
    direction, curvature and its rate all continue across the join. Its waves are flattened, step by
    step, until its least radius of curvature is at least ``radius_min`` (a circle at worst). The
    path starts at the origin along +x and ends there; ``heading`` as for :func:`figure_eight_path`.
    """
    _check_closed(length, radius_min, spacing, swing, swing_rate)
    if harmonics < 1:
        raise ConfigError(f"closed curve harmonics must be at least 1, got {harmonics}")
    rng = np.random.default_rng(seed)
    k = np.arange(1, harmonics + 1)
    amp = rng.uniform(0.0, 1.0, harmonics) / k
    amp *= 0.6 / float(np.sum(amp))
    phase = rng.uniform(0.0, 2.0 * math.pi, harmonics)
    side = float(rng.choice((-1.0, 1.0)))
    mode = _pick_heading(rng, heading)
    phi = np.linspace(0.0, 2.0 * math.pi, CLOSED_SAMPLES + 1)
    waves = np.cos(np.outer(phi, k) + phase)
    for _ in range(TRIES):
        r = 1.0 + waves @ amp
        xy = np.column_stack((r * np.cos(phi), side * r * np.sin(phi)))
        radius, s = _loop_radius(xy)
        if radius * length / s[-1] >= radius_min:
            return _closed_path(rng, xy, length, mode, swing, swing_rate, spacing)
        amp *= 0.8
    xy = np.column_stack((np.cos(phi), side * np.sin(phi)))  # a circle: 2 pi radius_min <= length
    return _closed_path(rng, xy, length, mode, swing, swing_rate, spacing)
