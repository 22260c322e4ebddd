"""SE(3) log and exp on (position, unit quaternion) pairs, for numba kernels (the target
filter, ``target_filter.py``).

A pose (p, R) has the twist coordinates xi = (v, w) with w = Log(R) (rotation vector,
|w| = theta in [0, pi]) and v = V(w)^-1 p, where

    V(w)    = I + a [w]x + b [w]x^2,     a = (1 - cos t) / t^2,  b = (t - sin t) / t^3
    V(w)^-1 = I - [w]x / 2 + c [w]x^2,   c = (1 - t sin t / (2 (1 - cos t))) / t^2

([w]x^2 x = w (w . x) - t^2 x). Below ``SMALL_ANGLE`` rad the series a = 1/2 - t^2/24,
b = 1/6 - t^2/120, c = 1/12 + t^2/720 are used (error O(t^4), below 1e-17 there).
"""

from __future__ import annotations

import math

from numba import njit

from impact_control.kernel_math import quat_log

SMALL_ANGLE = 1e-4
"""Below this rotation angle [rad] the V coefficients use their series."""


@njit(cache=True, inline="always")
def _cross_terms(w0, w1, w2, x0, x1, x2):
    """([w]x x, [w]x^2 x) as two 3-tuples."""
    c0, c1, c2 = w1 * x2 - w2 * x1, w2 * x0 - w0 * x2, w0 * x1 - w1 * x0
    d = w0 * x0 + w1 * x1 + w2 * x2
    t2 = w0 * w0 + w1 * w1 + w2 * w2
    return (c0, c1, c2), (w0 * d - t2 * x0, w1 * d - t2 * x1, w2 * d - t2 * x2)


@njit(cache=True)
def se3_log(pos, w, x, y, z, out) -> None:
    """out = (v, w) of the pose (pos, unit quaternion w, x, y, z); the quaternion's sign is
    made w >= 0 first (rotation angle in [0, pi])."""
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    r0, r1, r2 = quat_log(w, x, y, z)
    t2 = r0 * r0 + r1 * r1 + r2 * r2
    t = math.sqrt(t2)
    if t < SMALL_ANGLE:
        c = 1.0 / 12.0 + t2 / 720.0
    else:
        c = (1.0 - t * math.sin(t) / (2.0 * (1.0 - math.cos(t)))) / t2
    cr, cr2 = _cross_terms(r0, r1, r2, pos[0], pos[1], pos[2])
    for i in range(3):
        out[i] = pos[i] - 0.5 * cr[i] + c * cr2[i]
    out[3], out[4], out[5] = r0, r1, r2


@njit(cache=True)
def se3_exp(xi, pos, quat) -> None:
    """(pos, quat (w, x, y, z)) = Exp(xi), xi = (v, w) twist coordinates."""
    r0, r1, r2 = xi[3], xi[4], xi[5]
    t2 = r0 * r0 + r1 * r1 + r2 * r2
    t = math.sqrt(t2)
    if t < SMALL_ANGLE:
        a, b, k = 0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0, 0.5 - t2 / 48.0
    else:
        a, b, k = (1.0 - math.cos(t)) / t2, (t - math.sin(t)) / (t2 * t), math.sin(0.5 * t) / t
    cr, cr2 = _cross_terms(r0, r1, r2, xi[0], xi[1], xi[2])
    for i in range(3):
        pos[i] = xi[i] + a * cr[i] + b * cr2[i]
    quat[0] = math.cos(0.5 * t)
    quat[1], quat[2], quat[3] = k * r0, k * r1, k * r2


@njit(cache=True, inline="always")
def quat_mul(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product (a0..a3) * (b0..b3) of (w, x, y, z) quaternions, as a 4-tuple."""
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


@njit(cache=True, inline="always")
def quat_rotate(w, x, y, z, v0, v1, v2):
    """R(q) v for a unit quaternion (w, x, y, z), as a 3-tuple."""
    t0, t1, t2 = 2.0 * (y * v2 - z * v1), 2.0 * (z * v0 - x * v2), 2.0 * (x * v1 - y * v0)
    return (v0 + w * t0 + y * t2 - z * t1, v1 + w * t1 + z * t0 - x * t2,
            v2 + w * t2 + x * t1 - y * t0)
