"""The laser scanner's measurement: what a revolution reports for its true ranges
(:func:`scan_measure`), given its normal and uniform draws (numpy's ``Generator.standard_normal``
and ``Generator.random``, drawn by :class:`~omnibot.sim.scanner.LaserScanner`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from omnibot.sim.kernels.layout import FloatArray


@njit(cache=True)
def scan_measure(
    true: FloatArray,
    normals: FloatArray,
    uniforms: FloatArray,
    noise_std: float,
    noise_fraction: float,
    resolution: float,
    dropout: float,
    range_min: float,
    range_max: float,
    out: FloatArray,
) -> None:
    """What the scanner reports for the n true ranges (inf: no return) into out, from a standard
    normal and a uniform draw in [0, 1) per ray: ray i is dropped when uniforms[i] < dropout, else
    its range plus (noise_std + noise_fraction * range) * normals[i], quantised to resolution (when
    > 0); inf for a dropout, no return or a value outside [range_min, range_max]."""
    for i in range(true.shape[0]):
        r = true[i]
        if not r < np.inf or uniforms[i] < dropout:
            out[i] = np.inf
            continue
        v = r + (noise_std + noise_fraction * r) * normals[i]
        if resolution > 0.0:
            v = round(v / resolution) * resolution
        out[i] = v if range_min <= v <= range_max else np.inf
