"""The laser scanner's measurement noise: what a revolution reports for its true ranges
(:func:`scan_measure`)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels.layout import FloatArray


@njit(cache=True)
def scan_measure(
    true: FloatArray,
    draws: FloatArray,
    noise_std: float,
    noise_fraction: float,
    resolution: float,
    dropout: float,
    range_min: float,
    range_max: float,
    out: FloatArray,
) -> None:
    """What the scanner reports for the true ranges (inf: no return) into out, from 3 uniform draws
    per ray (draws[i], draws[n + i], draws[2n + i]: a Box-Muller normal from the first two, the
    dropout from the third): the range plus N(0, noise_std + noise_fraction * range), quantised to
    resolution (when > 0); inf for a dropout or a value outside [range_min, range_max]."""
    n = true.shape[0]
    for i in range(n):
        r = true[i]
        if not r < np.inf or draws[2 * n + i] < dropout:
            out[i] = np.inf
            continue
        z = math.sqrt(-2.0 * math.log1p(-draws[i])) * math.cos(2.0 * math.pi * draws[n + i])
        v = r + (noise_std + noise_fraction * r) * z
        if resolution > 0.0:
            v = round(v / resolution) * resolution
        out[i] = v if range_min <= v <= range_max else np.inf
