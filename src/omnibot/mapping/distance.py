"""The exact Euclidean distance transform of a grid's walls (the planner's clearance).

Felzenszwalb and Huttenlocher's two passes of lower envelopes of parabolas, one along each axis,
compiled with numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def distance_squared(walls: BoolArray) -> FloatArray:
    """Squared distance (cells) from each cell's centre to the nearest ``walls`` cell's centre
    (exact Euclidean, Felzenszwalb and Huttenlocher's two passes of lower envelopes)."""
    big = float((walls.shape[0] + walls.shape[1]) ** 2 + 1)
    f = np.where(walls, 0.0, big).astype(np.float64)
    return np.asarray(_edt2(f), dtype=np.float64)


@njit(cache=True)
def _edt1(f, out, v, z):  # type: ignore[no-untyped-def]  # numba kernel
    n = f.shape[0]
    k = 0
    v[0] = 0
    z[0] = -np.inf
    z[1] = np.inf
    for q in range(1, n):
        s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k])
        while s <= z[k]:
            k -= 1
            s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k])
        k += 1
        v[k] = q
        z[k] = s
        z[k + 1] = np.inf
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        out[q] = (q - v[k]) ** 2 + f[v[k]]


@njit(cache=True)
def _edt2(f):  # type: ignore[no-untyped-def]  # numba kernel
    rows, cols = f.shape
    m = max(rows, cols)
    v = np.zeros(m, np.int64)
    z = np.zeros(m + 1)
    tmp = np.empty(m)
    out = np.empty_like(f)
    for c in range(cols):
        _edt1(f[:, c].copy(), tmp[:rows], v, z)
        out[:, c] = tmp[:rows]
    for r in range(rows):
        _edt1(out[r, :].copy(), tmp[:cols], v, z)
        out[r, :] = tmp[:cols]
    return out
