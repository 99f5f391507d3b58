"""Where the kernels' state lies: the column indices of their parameter and state arrays, and the
offsets of the arrays packed into one buffer.

Column indices are compile-time constants (numba freezes a module's globals when it compiles):

* ``wp`` (n, m, W_COLUMNS): per wheel: the traction row ``W_TX..W_TA`` and roller row
  ``W_NX..W_NA`` of the contact matrix H (body vx, vy, w and wheel-speed coefficients), motor,
  driver and roller constants, the static load;
* ``rp`` (n, R_COLUMNS): per robot: mass / dt, yaw inertia / dt, battery resistance and relaxation;
* ``surf`` (S, S_COLUMNS): per floor surface: mu, 1 / slip velocity, rolling multiplier;
* a gyro's state (``G_`` columns) and the tracking wheels' (``T_``);
* the simulator's float and int state (``F_`` and ``I_`` headers, :func:`sim_offsets`), the
  world's packed geometry (:func:`world_offsets`), a physics state packed in one buffer
  (:func:`physics_offsets`, :func:`physics_views`), a fleet's layout (``L_`` columns) and
  :func:`~omnibot.sim.kernels.step.robot_step`'s status bits (``STEP_``) and the places of its
  arguments that change from step to step (``A_``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# wheel parameter columns
W_TX, W_TY, W_TW, W_TA = 0, 1, 2, 3
W_NX, W_NY, W_NW, W_NA = 4, 5, 6, 7
W_J_DT = 8
W_INV_PWM_MAX = 9
W_ON_THRESHOLD = 10
W_DROP = 11
W_INV_RES = 12
W_KE_RES = 13
W_I_MAX = 14
W_KT = 15
W_EMF_DAMPING = 16
W_VISC = 17
W_STATIC = 18
W_LOAD = 19
W_GRIP_LOAD = 20
W_RR_TOP = 21
W_RR_VAR = 22
W_ROLLER_COUNT = 23
W_RADIUS = 24
W_SCRUB_LOAD = 25
W_COLUMNS = 26

# robot parameter columns
R_M_DT, R_I_DT, R_BATT_RES, R_BATT_RELAX = 0, 1, 2, 3
R_COLUMNS = 4

# surface table columns
S_MU, S_INV_VEPS, S_ROLL = 0, 1, 2
S_COLUMNS = 3

# gyro state columns (one float64 array per gyro)
G_BIAS, G_SCALE, G_SIGMA, G_WALK, G_DUE, G_PERIOD, G_RANGE, G_RESOLUTION = 0, 1, 2, 3, 4, 5, 6, 7
G_ACC_TIME, G_ACC_ANGLE, G_RATE, G_ANGLE, G_SAMPLES, G_NEXT = 8, 9, 10, 11, 12, 13
G_COLUMNS = 14
"""G_NEXT: index of the next unused normal draw in the gyro's block."""

# tracking wheels state: T_SLIP, T_NEXT, then per wheel (ux, uy, px, py, distance)
T_SLIP, T_NEXT, T_HEADER, T_WHEEL = 0, 1, 2, 5

# the simulator's float state (sf): header, then outline (V, 2), contact rows (C, 6), contact
# speeds (C,), wheel positions (m, 2), pose log (I_LOG_CAP, 3)
F_MASS, F_INERTIA, F_OMEGA, F_DAMPING, F_WALL_FRICTION = 0, 1, 2, 3, 4
F_CLEAR_X, F_CLEAR_Y, F_CLEAR = 5, 6, 7
F_SURF_X, F_SURF_Y, F_SURF_TH, F_SURF_CLEAR, F_REACH = 8, 9, 10, 11, 12
F_AT_X, F_AT_Y, F_AT_TH = 13, 14, 15
F_HEADER = 16
# its int state (si): header, then last touch (us) per world owner, new-collision flags (C,),
# world surface id -> physics surface id, surface ids of the last probe (m,)
I_V, I_C, I_M, I_OWNERS, I_SURFACES, I_COUNT, I_WALLS, I_PATCHY, I_RELEASE = 0, 1, 2, 3, 4, 5, 6, 7, 8
# the pose log for the laser scanners (sf's last section, I_LOG_CAP rows of x, y, theta): the step
# records its end pose as row I_LOG_N when it ends at or after I_LOG_NEXT (us), then I_LOG_NEXT
# moves on by I_LOG_STRIDE, and says STEP_SCAN when that end is at or after I_LOG_FLUSH (us); only
# while I_LOG_ON; I_LOG_DT: the step's length, us
I_LOG_ON, I_LOG_N, I_LOG_CAP, I_LOG_NEXT, I_LOG_STRIDE, I_LOG_DT, I_LOG_FLUSH = 9, 10, 11, 12, 13, 14, 15
I_HEADER = 16
NEVER = -(2**62)
"""A last-touch time meaning 'never touched'."""
# the world's packed geometry: wf floats solid_v (V, 2), solid_c (K, 2), solid_r (K,), thin_v (2E, 2),
# patch_v (P, 2); wi ints: the sizes V, K, E, P, Q, then solid_off (K + 1), solid_owner (K),
# thin_owner (E), patch_off (Q + 1), patch_sid (Q)
WORLD_HEADER = 5

# robot_step status bits (STEP_SCAN: the pose log recorded a row at or after its flush time)
STEP_BAD_SURFACE, STEP_COLLISION, STEP_REFILL, STEP_FORCE, STEP_SCAN = 1, 2, 4, 8, 16

# robot_step's arguments that change from step to step (the simulator binds the others once):
# the number of extra-force rows and the time the step begins
A_N_EXTRA, A_NOW_US = 9, 14

# a fleet's layout (fleet_step): one row per robot, where its arrays lie in the fleet's buffers
(
    L_PBUF, L_PBUF_END, L_M, L_N_SURF, L_SF, L_SF_END, L_GYRO, L_GYRO_END, L_TRACKING, L_TRACKING_END,
    L_IDS, L_SI, L_SI_END, L_GYRO_NORMALS, L_GYRO_NORMALS_END, L_TRACKING_NORMALS, L_TRACKING_NORMALS_END,
    L_EXTRA, L_N_EXTRA,
) = range(19)  # fmt: skip
L_COLUMNS = 19


@njit(cache=True)
def physics_offsets(
    n: int, m: int, n_surf: int
) -> tuple[int, int, int, int, int, int, int, int, int, int, int, int, int]:
    """Where each array of a physics state packed in one float64 buffer starts (and its size, last):
    pose (n, 3), q (n, 3 + m), wheel_angle, current, traction (n, m), battery (n, 2), v_open (n,),
    pwm (n, m), ext (n, 3), wp (n, m, W_COLUMNS), rp (n, R_COLUMNS), surf (n_surf, S_COLUMNS)."""
    o0 = 0
    o1 = o0 + 3 * n
    o2 = o1 + (3 + m) * n
    o3 = o2 + n * m
    o4 = o3 + n * m
    o5 = o4 + n * m
    o6 = o5 + 2 * n
    o7 = o6 + n
    o8 = o7 + n * m
    o9 = o8 + 3 * n
    o10 = o9 + n * m * W_COLUMNS
    o11 = o10 + n * R_COLUMNS
    return o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11, o11 + n_surf * S_COLUMNS


@njit(cache=True)
def physics_views(
    buf: FloatArray, n: int, m: int, n_surf: int
) -> tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
]:  # fmt: skip
    """The arrays of a packed physics state (:func:`physics_offsets`) as views of ``buf``."""
    o = physics_offsets(n, m, n_surf)
    return (
        buf[o[0] : o[1]].reshape((n, 3)),
        buf[o[1] : o[2]].reshape((n, 3 + m)),
        buf[o[2] : o[3]].reshape((n, m)),
        buf[o[3] : o[4]].reshape((n, m)),
        buf[o[4] : o[5]].reshape((n, m)),
        buf[o[5] : o[6]].reshape((n, 2)),
        buf[o[6] : o[7]],
        buf[o[7] : o[8]].reshape((n, m)),
        buf[o[8] : o[9]].reshape((n, 3)),
        buf[o[9] : o[10]].reshape((n, m, W_COLUMNS)),
        buf[o[10] : o[11]].reshape((n, R_COLUMNS)),
        buf[o[11] : o[12]].reshape((n_surf, S_COLUMNS)),
    )


@njit(cache=True)
def world_offsets(wi: IntArray) -> tuple[int, int, int, int, int, int, int, int, int, int, int]:
    """Where each array of a packed world starts: (solid_v, solid_c, solid_r, thin_v, patch_v, end
    of wf; solid_off, solid_owner, thin_owner, patch_off, patch_sid in wi)."""
    nv, nk, ne, npv, nq = wi[0], wi[1], wi[2], wi[3], wi[4]
    f0 = 0
    f1 = f0 + 2 * nv
    f2 = f1 + 2 * nk
    f3 = f2 + nk
    f4 = f3 + 4 * ne
    f5 = f4 + 2 * npv
    i0 = WORLD_HEADER
    i1 = i0 + nk + 1
    i2 = i1 + nk
    i3 = i2 + ne
    i4 = i3 + nq + 1
    return f0, f1, f2, f3, f4, f5, i0, i1, i2, i3, i4


@njit(cache=True)
def sim_offsets(si: IntArray) -> tuple[int, int, int, int, int, int, int, int, int, int, int]:
    """Where each array of the simulator's state starts: (outline, contact rows, contact speeds,
    wheel positions, pose log, end of sf; last touch, new flags, surface map, probed ids, end of si)."""
    nv, nc, m = si[I_V], si[I_C], si[I_M]
    f0 = F_HEADER
    f1 = f0 + 2 * nv
    f2 = f1 + 6 * nc
    f3 = f2 + nc
    f4 = f3 + 2 * m
    f5 = f4 + 3 * si[I_LOG_CAP]
    i0 = I_HEADER
    i1 = i0 + si[I_OWNERS]
    i2 = i1 + nc
    i3 = i2 + si[I_SURFACES]
    i4 = i3 + m
    return f0, f1, f2, f3, f4, f5, i0, i1, i2, i3, i4
