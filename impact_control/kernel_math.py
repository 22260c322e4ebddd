"""Numba kernels: small linear algebra and SO(3) helpers of the controller stages.

Matrix products are explicit loops (numba's ``@`` needs SciPy's BLAS, and for 6x7 operands
loops are faster anyway).
"""

from __future__ import annotations

import math

from numba import njit

EPS_SMALL_ANGLE = 1e-8
"""Below this |vector part| the quaternion log uses its series expansion."""


# ------------------------------------------------------------------------------ linear algebra
@njit(cache=True)
def mat_vec(a, x, out) -> None:
    """out = a @ x for a (m, n)."""
    for i in range(a.shape[0]):
        s = 0.0
        for j in range(a.shape[1]):
            s += a[i, j] * x[j]
        out[i] = s


@njit(cache=True)
def mat_t_vec(a, x, out) -> None:
    """out = a.T @ x for a (m, n)."""
    for j in range(a.shape[1]):
        out[j] = 0.0
    for i in range(a.shape[0]):
        xi = x[i]
        for j in range(a.shape[1]):
            out[j] += a[i, j] * xi


@njit(cache=True)
def regularized_wrench_map(jac, damping_sq, gram, out) -> None:
    """out = (J J^T + damping_sq I)^-1 J by Cholesky (J J^T + lambda^2 I is SPD for lambda > 0).

    ``gram`` (m, m) is scratch (holds the Cholesky factor afterwards). A non-finite Jacobian
    gives NaN, which the controller's finite check reports.
    """
    m, n = jac.shape
    for i in range(m):
        for k in range(i + 1):
            s = 0.0
            for j in range(n):
                s += jac[i, j] * jac[k, j]
            gram[i, k] = s
        gram[i, i] += damping_sq
    for j in range(m):  # in-place lower Cholesky factor
        s = gram[j, j]
        for k in range(j):
            s -= gram[j, k] * gram[j, k]
        d = math.sqrt(s) if s > 0.0 else math.nan
        gram[j, j] = d
        for i in range(j + 1, m):
            s = gram[i, j]
            for k in range(j):
                s -= gram[i, k] * gram[j, k]
            gram[i, j] = s / d
    for c in range(n):  # L L^T x = J[:, c]
        for i in range(m):
            s = jac[i, c]
            for k in range(i):
                s -= gram[i, k] * out[k, c]
            out[i, c] = s / gram[i, i]
        for i in range(m - 1, -1, -1):
            s = out[i, c]
            for k in range(i + 1, m):
                s -= gram[k, i] * out[k, c]
            out[i, c] = s / gram[i, i]


@njit(cache=True)
def clamp_norm3(v, lo, norm_max) -> None:
    """v[lo:lo + 3] *= norm_max / |v[lo:lo + 3]| when its norm exceeds ``norm_max`` (inf:
    never)."""
    n_sq = v[lo] * v[lo] + v[lo + 1] * v[lo + 1] + v[lo + 2] * v[lo + 2]
    if n_sq > norm_max * norm_max:
        s = norm_max / math.sqrt(n_sq)
        for i in range(lo, lo + 3):
            v[i] *= s


@njit(cache=True)
def rotate(rot, w, out) -> None:
    """out = (R w[:3], R w[3:]): a wrench or twist from the frame of ``rot`` (e.g. the TCP,
    ``rot`` = R_ee) to the world frame."""
    for h in (0, 3):
        for i in range(3):
            out[h + i] = rot[i, 0] * w[h] + rot[i, 1] * w[h + 1] + rot[i, 2] * w[h + 2]


@njit(cache=True)
def rotate_back(rot, w, out) -> None:
    """out = (R^T w[:3], R^T w[3:]): from the world frame to the frame of ``rot``."""
    for h in (0, 3):
        for i in range(3):
            out[h + i] = rot[0, i] * w[h] + rot[1, i] * w[h + 1] + rot[2, i] * w[h + 2]


# ----------------------------------------------------------------------------------- SO(3)
@njit(cache=True)
def quat_normalized(quat):
    """(valid, w, x, y, z) of quat / |quat|; invalid when the norm is ~0 or not finite."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if not (n > 1e-12 and math.isfinite(n)):
        return False, 1.0, 0.0, 0.0, 0.0
    return True, w / n, x / n, y / n, z / n


@njit(cache=True)
def matrix_to_quat(rot):
    """Shepperd's method: unit (w, x, y, z) of a rotation matrix with w >= 0."""
    m00, m01, m02 = rot[0, 0], rot[0, 1], rot[0, 2]
    m10, m11, m12 = rot[1, 0], rot[1, 1], rot[1, 2]
    m20, m21, m22 = rot[2, 0], rot[2, 1], rot[2, 2]
    trace = m00 + m11 + m22
    if trace >= max(m00, max(m11, m22)):
        s = 2.0 * math.sqrt(max(1.0 + trace, 0.0))
        w, x, y, z = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 >= m11 and m00 >= m22:
        s = 2.0 * math.sqrt(max(1.0 + m00 - m11 - m22, 0.0))
        w, x, y, z = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 >= m22:
        s = 2.0 * math.sqrt(max(1.0 + m11 - m00 - m22, 0.0))
        w, x, y, z = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = 2.0 * math.sqrt(max(1.0 + m22 - m00 - m11, 0.0))
        w, x, y, z = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if w < 0.0:
        n = -n
    return w / n, x / n, y / n, z / n


@njit(cache=True)
def quat_log(w, x, y, z):
    """Rotation vector of a unit quaternion with w >= 0 (angle in [0, pi])."""
    s = math.sqrt(x * x + y * y + z * z)
    if s < EPS_SMALL_ANGLE:
        # theta / s = 2 atan2(s, w) / s ~ (2 / w) (1 - s^2 / (3 w^2)); here w ~ 1.
        k = 2.0 / w * (1.0 - s * s / (3.0 * w * w))
    else:
        k = 2.0 * math.atan2(s, w) / s
    return k * x, k * y, k * z


@njit(cache=True)
def orientation_error(quat_target, rot, out) -> bool:
    """out = Log(R_d R^T) via q_d * conj(q(R)) (shortest arc); False if q_d is invalid."""
    valid, dw, dx, dy, dz = quat_normalized(quat_target)
    if not valid:
        return False
    w, x, y, z = matrix_to_quat(rot)
    ew = dw * w + dx * x + dy * y + dz * z
    ex = -dw * x + dx * w - dy * z + dz * y
    ey = -dw * y + dx * z + dy * w - dz * x
    ez = -dw * z - dx * y + dy * x + dz * w
    if ew < 0.0:
        ew, ex, ey, ez = -ew, -ex, -ey, -ez
    out[0], out[1], out[2] = quat_log(ew, ex, ey, ez)
    return True
