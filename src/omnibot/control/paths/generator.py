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

from omnibot.control.paths.path import FloatArray, Path
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
    for name, value in (
        ("length", length),
        ("radius_min", radius_min),
        ("spacing", spacing),
        ("swing_rate", swing_rate),
    ):
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f"random path {name} must be a positive number, got {value}")
    if not (math.isfinite(swing) and swing >= 0):
        raise ConfigError(f"random path swing must be a non-negative number of radians, got {swing}")
    wave = 4.0 * radius_min if wavelength is None else wavelength
    if not (math.isfinite(wave) and wave > 0):
        raise ConfigError(f"random path wavelength must be a positive number, got {wavelength}")
    if length / spacing > 200_000:
        raise ConfigError(
            f"random path of {length:g} m at {spacing:g} m spacing is too long; at most 200,000 points"
        )
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
