"""Correctly-rounded-enough ``tanh``, ``sin`` and ``cos`` in plain arithmetic, which the compiler
vectorises (numba calls the C library's one value at a time: it finds no SVML here), for the batch
kernel of :mod:`omnibot.sim.kernels.lanes`.

Each is within about one unit in the last place of the exact value (``tests/sim/kernels/test_libm.py``
measures it): an argument reduced exactly (by ln 2, or by pi/2 in three exact parts, good for
``|x| <= REDUCE_LIMIT``), then a Taylor polynomial that reaches a double's precision on the reduced
range. Larger angles are the caller's to give to the C library.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

from numba import njit

REDUCE_LIMIT = 1.0e6
"""Largest |x| :func:`sincos` and :func:`cos` reduce themselves (k pi/2 splits exactly up to 2^21)."""

_ROUND = 6755399441055744.0  # 1.5 * 2^52: (x + _ROUND) - _ROUND rounds x to an integer, |x| < 2^51


def _split(value: Decimal, bits: int) -> tuple[float, float, float]:
    """``value`` as hi + mid + lo, hi and mid with at most ``bits`` significant bits (so their
    products with an integer below 2^(53 - bits) are exact)."""
    parts = []
    rest = value
    for _ in range(2):
        exponent = math.frexp(float(rest))[1]
        part = math.ldexp(math.floor(math.ldexp(float(rest), bits - exponent)), exponent - bits)
        parts.append(part)
        rest -= Decimal(part)
    return parts[0], parts[1], float(rest)


with localcontext() as _ctx:
    _ctx.prec = 60
    _LN2 = Decimal(2).ln()
    _PI_2 = Decimal("3.14159265358979323846264338327950288419716939937510582097494459") / 2
    LN2_HI, LN2_MID, LN2_LO = _split(_LN2, 32)
    PIO2_HI, PIO2_MID, PIO2_LO = _split(_PI_2, 32)
    INV_LN2 = float(1 / _LN2)
    TWO_OVER_PI = float(1 / _PI_2)

# Taylor coefficients 1/n! (the reduced arguments are small enough for them to reach a double's precision)
_F = [1.0 / math.factorial(n) for n in range(19)]
EX2, EX3, EX4, EX5, EX6, EX7, EX8, EX9, EX10, EX11, EX12, EX13, EX14 = _F[2:15]
_SIN: tuple[float, ...] = tuple(_F[n] * (-1) ** (n // 2) for n in range(3, 18, 2))  # of x^3 .. x^17
_COS: tuple[float, ...] = tuple(_F[n] * (-1) ** (n // 2) for n in range(4, 19, 2))  # of x^4 .. x^18
SN3, SN5, SN7, SN9, SN11, SN13, SN15, SN17 = _SIN
CS4, CS6, CS8, CS10, CS12, CS14, CS16, CS18 = _COS


@njit(cache=True, inline="always", error_model="numpy")
def _expm1_reduced(r: float) -> float:
    """exp(r) - 1 for |r| <= ln 2 / 2."""
    e = EX14
    e = EX13 + r * e
    e = EX12 + r * e
    e = EX11 + r * e
    e = EX10 + r * e
    e = EX9 + r * e
    e = EX8 + r * e
    e = EX7 + r * e
    e = EX6 + r * e
    e = EX5 + r * e
    e = EX4 + r * e
    e = EX3 + r * e
    e = EX2 + r * e
    return r + r * r * e


@njit(cache=True, inline="always", error_model="numpy")
def tanh(x: float) -> float:
    """The hyperbolic tangent in plain arithmetic (vectorisable), within 3 ulps of the C library's:
    -M / (2 + M) with M = expm1(-2 |x|) = 2^k expm1(r) + 2^k - 1 below 0.55, 1 - 2E / (1 + E) with
    E = exp(-2 |x|) above, ``|x|`` held at 22 (tanh is 1 in double from 19.1)."""
    a = min(abs(x), 22.0)
    y = -2.0 * a
    kf = (y * INV_LN2 + _ROUND) - _ROUND  # -64 <= k <= 0
    r = ((y - kf * LN2_HI) - kf * LN2_MID) - kf * LN2_LO
    p = _expm1_reduced(r)
    n = int(-kf)
    scale = 0.5 if n & 1 else 1.0  # 2^k, exactly
    scale *= 0.25 if n & 2 else 1.0
    scale *= 0.0625 if n & 4 else 1.0
    scale *= 0.00390625 if n & 8 else 1.0
    scale *= 1.52587890625e-05 if n & 16 else 1.0
    scale *= 2.3283064365386963e-10 if n & 32 else 1.0
    scale *= 5.421010862427522e-20 if n & 64 else 1.0
    small = a < 0.55
    big_m = scale * p + (scale - 1.0)  # expm1(y)
    e = scale * p + scale  # exp(y)
    ratio = (-big_m if small else 2.0 * e) / (2.0 + big_m if small else 1.0 + e)  # one division
    t = ratio if small else 1.0 - ratio
    return t if x > 0.0 else -t if x < 0.0 else x


@njit(cache=True, inline="always", error_model="numpy")
def _reduce(x: float) -> tuple[float, float, int]:
    """x - k pi/2 as r + t, r in [-pi/4, pi/4] (about) and t its tail, and k mod 4, for |x| <=
    REDUCE_LIMIT (x - k hi is exact, and so are the products k hi and k mid)."""
    kf = (x * TWO_OVER_PI + _ROUND) - _ROUND
    a = x - kf * PIO2_HI
    b = kf * PIO2_MID
    r = a - b
    t = ((a - r) - b) - kf * PIO2_LO  # what the subtraction rounded off, less the last part
    return r + t, (r - (r + t)) + t, int(kf) & 3


@njit(cache=True, inline="always", error_model="numpy")
def _sin_reduced(r: float, t: float) -> float:
    z = r * r
    s = SN17
    s = SN15 + z * s
    s = SN13 + z * s
    s = SN11 + z * s
    s = SN9 + z * s
    s = SN7 + z * s
    s = SN5 + z * s
    s = SN3 + z * s
    return r + (r * z * s + t)


@njit(cache=True, inline="always", error_model="numpy")
def _cos_reduced(r: float, t: float) -> float:
    z = r * r
    c = CS18
    c = CS16 + z * c
    c = CS14 + z * c
    c = CS12 + z * c
    c = CS10 + z * c
    c = CS8 + z * c
    c = CS6 + z * c
    c = CS4 + z * c
    half = 0.5 * z
    w = 1.0 - half
    return w + (((1.0 - w) - half) + (z * z * c - r * t))  # (1 - w) - half: what rounding w lost


@njit(cache=True, inline="always", error_model="numpy")
def sincos(x: float) -> tuple[float, float]:
    """(sin x, cos x) in plain arithmetic (vectorisable), within about an ulp, |x| <= REDUCE_LIMIT."""
    r, t, quadrant = _reduce(x)
    s, c = _sin_reduced(r, t), _cos_reduced(r, t)
    sin = c if quadrant & 1 else s
    cos = s if quadrant & 1 else c
    sin = -sin if quadrant & 2 else sin
    cos = -cos if (quadrant + 1) & 2 else cos
    return sin, cos


@njit(cache=True, inline="always", error_model="numpy")
def cos(x: float) -> float:
    """cos x in plain arithmetic (vectorisable), within about an ulp, |x| <= REDUCE_LIMIT."""
    r, t, quadrant = _reduce(x)
    c = _sin_reduced(r, t) if quadrant & 1 else _cos_reduced(r, t)
    return -c if (quadrant + 1) & 2 else c
