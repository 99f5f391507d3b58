"""The laser scanner's measurement noise: normal draws by the ziggurat method from the scanner's
uniform draws, and what a revolution reports for its true ranges (:func:`scan_measure`).

A normal draw costs a few integer operations, a table lookup and a multiplication in 98.8 % of
the cases (Marsaglia and Tsang's ziggurat, 256 layers, as numpy's ``standard_normal``), where the
Box-Muller transform called ``log1p``, ``sqrt`` and ``cos`` for every ray (~25 ns a ray, 8-9 us
of a 360-ray revolution). The uniform draws are doubles of 53 random bits (numpy's
``Generator.random``): a ray's first draw gives the layer (8 bits), the sign (1) and the position
in the layer (44); the few draws the rejections need come in order from a pool of the revolution's
(SCAN_POOL draws: 8 used on average by 360 rays, at most 29 in 200,000 revolutions).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels.layout import FloatArray

_R = 3.6541528853610088
"""Where the ziggurat's base layer ends and its tail begins (256 layers)."""
_V = 0.00492867323399
"""The area of each of its layers (under exp(-x^2 / 2))."""
_BITS = 44
"""Random bits of a draw's position in its layer (53 less 8 for the layer, 1 for the sign)."""
SCAN_POOL = 64
"""Uniform draws a revolution keeps for its normal draws' rejections (after its 2 per ray)."""
_TWO53 = 9007199254740992.0
"""2^53: a uniform draw times this is its 53 random bits as an integer, exactly."""


def _ziggurat_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(k, w, f) of the 256-layer ziggurat for exp(-x^2 / 2) (Marsaglia and Tsang 2000): a draw
    of layer i at position p (an integer below 2^_BITS) is x = p * w[i], inside the curve for sure
    when p < k[i]; f[i] is the curve at the layer's outer edge (f[0] = 1: x = 0)."""
    m = float(2**_BITS)
    k = np.zeros(256, dtype=np.int64)
    w, f = np.zeros(256), np.zeros(256)
    dn = tn = _R
    q = _V / math.exp(-0.5 * dn * dn)
    k[0] = int(dn / q * m)
    w[0], w[255] = q / m, dn / m
    f[0], f[255] = 1.0, math.exp(-0.5 * dn * dn)
    for i in range(254, 0, -1):
        dn = math.sqrt(-2.0 * math.log(_V / dn + math.exp(-0.5 * dn * dn)))
        k[i + 1] = int(dn / tn * m)
        tn = dn
        f[i], w[i] = math.exp(-0.5 * dn * dn), dn / m
    return k, w, f


_ZIG_K, _ZIG_W, _ZIG_F = _ziggurat_tables()


@njit(cache=True, inline="always")
def _pool_draw(draws: FloatArray, at: int, lo: int, hi: int) -> tuple[float, int]:
    """(draws[at], the next pool index): the pool is draws[lo:hi], read from the start again at its end."""
    return draws[at], at + 1 if at + 1 < hi else lo


@njit(cache=True)
def normal_draw(u: float, draws: FloatArray, at: int, lo: int, hi: int) -> tuple[float, int]:
    """(a standard normal draw, the next pool index) by the ziggurat from the uniform draw ``u`` in
    [0, 1); a rejection (1.2 % of the cases, a few draws each) takes more uniforms from the pool
    draws[lo:hi] at ``at``, read from its start again should it run out (SCAN_POOL draws for 360
    rays: with a probability near 1e-16 a revolution)."""
    while True:
        bits = int(u * _TWO53)
        layer = bits & 255
        position = bits >> 9
        x = position * _ZIG_W[layer]
        if (bits >> 8) & 1:
            x = -x
        if position < _ZIG_K[layer]:
            return x, at
        if layer == 0:  # the tail beyond _R
            while True:
                u1, at = _pool_draw(draws, at, lo, hi)
                u2, at = _pool_draw(draws, at, lo, hi)
                xx = -math.log1p(-u1) / _R
                yy = -math.log1p(-u2)
                if yy + yy > xx * xx:
                    return (-(_R + xx) if x < 0.0 else _R + xx), at
        u1, at = _pool_draw(draws, at, lo, hi)
        if (_ZIG_F[layer - 1] - _ZIG_F[layer]) * u1 + _ZIG_F[layer] < math.exp(-0.5 * x * x):
            return x, at
        u, at = _pool_draw(draws, at, lo, hi)


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
    """What the scanner reports for the n true ranges (inf: no return) into out, from 2 uniform
    draws per ray and a pool (2n + SCAN_POOL in all): ray i's dropout from draws[n + i], its normal
    from draws[i] (:func:`normal_draw`; the rejections' from the pool draws[2n:], in the order of
    the rays): the range plus N(0, noise_std + noise_fraction * range), quantised to resolution
    (when > 0); inf for a dropout or a value outside [range_min, range_max]."""
    n = true.shape[0]
    at = 2 * n
    for i in range(n):
        r = true[i]
        if not r < np.inf or draws[n + i] < dropout:
            out[i] = np.inf
            continue
        z, at = normal_draw(draws[i], draws, at, 2 * n, draws.shape[0])
        v = r + (noise_std + noise_fraction * r) * z
        if resolution > 0.0:
            v = round(v / resolution) * resolution
        out[i] = v if range_min <= v <= range_max else np.inf
