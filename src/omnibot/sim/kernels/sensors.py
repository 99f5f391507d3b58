"""The sensors' kernels: a gyro's samples (bias walk, noise, range, resolution) and the tracking
wheels' distances (see :mod:`omnibot.sim.sensors`).
"""

from __future__ import annotations

from numba import njit

from omnibot.sim.kernels.layout import (
    G_ACC_ANGLE,
    G_ACC_TIME,
    G_ANGLE,
    G_BIAS,
    G_DUE,
    G_NEXT,
    G_PERIOD,
    G_RANGE,
    G_RATE,
    G_RESOLUTION,
    G_SAMPLES,
    G_SCALE,
    G_SIGMA,
    G_WALK,
    T_HEADER,
    T_NEXT,
    T_SLIP,
    T_WHEEL,
    FloatArray,
)


@njit(cache=True)
def gyro_measure(g: FloatArray, normals: FloatArray, true_rate: float) -> float:
    """One sample of a (period-averaged) true rate into g (see :class:`omnibot.sim.sensors.Gyro`);
    normal draws from ``normals`` at g[G_NEXT] on."""
    k = int(g[G_NEXT])
    if g[G_WALK] > 0:
        g[G_BIAS] += g[G_WALK] * normals[k]
        k += 1
    noise = 0.0
    if g[G_SIGMA] > 0:
        noise = g[G_SIGMA] * normals[k]
        k += 1
    g[G_NEXT] = k
    limit, resolution = g[G_RANGE], g[G_RESOLUTION]
    value = (1.0 + g[G_SCALE]) * true_rate + g[G_BIAS] + noise
    value = min(max(value, -limit), limit)
    if resolution > 0:
        value = round(value / resolution) * resolution
        value = min(max(value, -limit), limit)
    g[G_RATE] = value
    g[G_ANGLE] += value * g[G_PERIOD]
    g[G_SAMPLES] += 1.0
    return float(value)


@njit(cache=True)
def gyro_update(g: FloatArray, normals: FloatArray, dt: float, true_rate: float) -> bool:
    """Advance the gyro g by dt at true_rate; True if it took at least one sample."""
    g[G_ACC_TIME] += dt
    g[G_ACC_ANGLE] += true_rate * dt
    if g[G_ACC_TIME] < g[G_DUE]:
        return False
    while g[G_ACC_TIME] >= g[G_DUE]:
        mean = g[G_ACC_ANGLE] / g[G_ACC_TIME]
        g[G_ACC_TIME] -= g[G_PERIOD]
        g[G_ACC_ANGLE] = mean * g[G_ACC_TIME]
        gyro_measure(g, normals, mean)
    return True


@njit(cache=True)
def tracking_update(t: FloatArray, normals: FloatArray, vx: float, vy: float, w: float, dt: float) -> None:
    """Roll the tracking wheels t for dt at the body twist (see :class:`omnibot.sim.sensors.TrackingWheels`)."""
    slip_std = t[T_SLIP]
    k = int(t[T_NEXT])
    for a in range(T_HEADER, t.shape[0], T_WHEEL):
        ux, uy, px, py = t[a], t[a + 1], t[a + 2], t[a + 3]
        step = ((vx - w * py) * ux + (vy + w * px) * uy) * dt
        if slip_std > 0:
            step = step * (1.0 + slip_std * normals[k])
            k += 1
        t[a + 4] = t[a + 4] + step
    t[T_NEXT] = k
