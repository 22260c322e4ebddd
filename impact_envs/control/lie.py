"""SO(3) helpers: quaternions (w, x, y, z), exp/log maps, rot6d and slerp.

Per-tick functions (``quat_to_matrix``, ``so3_log``) work on Python scalars internally because
for 3x3 and 4-vectors that is several times cheaper than chains of small NumPy calls.
"""

from __future__ import annotations

import math

import numpy as np

from impact_envs.errors import InvalidArgumentError

_EPS_SMALL_ANGLE = 1e-8


def _quat_tuple(quat: np.ndarray) -> tuple[float, float, float, float]:
    """Return the normalized quaternion as floats; raise on a zero/non-finite input."""
    w, x, y, z = quat.tolist() if isinstance(quat, np.ndarray) else (float(v) for v in quat)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if not (n > 1e-12 and math.isfinite(n)):
        raise InvalidArgumentError(f"invalid quaternion {quat!r}; valid: finite, non-zero wxyz")
    return w / n, x / n, y / n, z / n


def quat_to_matrix(quat: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Rotation matrix of a (w, x, y, z) quaternion (normalized first).

    Args:
        quat: Quaternion (4,), any non-zero norm.
        out: Optional (3, 3) array to write into.

    Returns:
        The (3, 3) rotation matrix.
    """
    w, x, y, z = _quat_tuple(quat)
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    if out is None:
        out = np.empty((3, 3))
    out.flat[:] = (
        1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy),
        2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx),
        2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy),
    )  # fmt: skip
    return out


def _matrix_to_quat_tuple(rot: np.ndarray) -> tuple[float, float, float, float]:
    """Shepperd's method on scalars; returns (w, x, y, z) with w >= 0."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = rot.tolist()
    trace = m00 + m11 + m22
    if trace >= max(m00, m11, m22):
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


def matrix_to_quat(rot: np.ndarray) -> np.ndarray:
    """(w, x, y, z) quaternion of a rotation matrix, canonical sign w >= 0."""
    return np.array(_matrix_to_quat_tuple(np.asarray(rot, dtype=float)))


def quat_multiply(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Hamilton product q1 * q2 (rotation q2 first, then q1)."""
    w1, x1, y1, z1 = (float(v) for v in q1)
    w2, x2, y2, z2 = (float(v) for v in q2)
    return np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )


def quat_conjugate(quat: np.ndarray) -> np.ndarray:
    """Conjugate (= inverse for unit quaternions) of (w, x, y, z)."""
    return np.array([quat[0], -quat[1], -quat[2], -quat[3]], dtype=float)


def _quat_log_tuple(w: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """Rotation vector of a unit quaternion with w >= 0 (angle in [0, pi])."""
    s = math.sqrt(x * x + y * y + z * z)
    if s < _EPS_SMALL_ANGLE:
        # theta / s = 2 atan2(s, w) / s ~ (2 / w) (1 - s^2 / (3 w^2)); here w ~ 1.
        k = 2.0 / w * (1.0 - s * s / (3.0 * w * w))
    else:
        k = 2.0 * math.atan2(s, w) / s
    return k * x, k * y, k * z


def quat_to_rotvec(quat: np.ndarray) -> np.ndarray:
    """Rotation vector (axis * angle, angle in [0, pi]) of a quaternion."""
    w, x, y, z = _quat_tuple(quat)
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    return np.array(_quat_log_tuple(w, x, y, z))


def rotvec_to_quat(rotvec: np.ndarray) -> np.ndarray:
    """(w, x, y, z) quaternion of a rotation vector (series expansion near 0)."""
    rx, ry, rz = (float(v) for v in rotvec)
    theta = math.sqrt(rx * rx + ry * ry + rz * rz)
    # sin(theta / 2) / theta, with its series 1/2 - theta^2 / 48 near 0.
    k = 0.5 - theta * theta / 48.0 if theta < 1e-6 else math.sin(0.5 * theta) / theta
    return np.array([math.cos(0.5 * theta), k * rx, k * ry, k * rz])


def so3_exp(rotvec: np.ndarray) -> np.ndarray:
    """Exp map: rotation vector (3,) [rad] -> rotation matrix (3, 3)."""
    return quat_to_matrix(rotvec_to_quat(rotvec))


def so3_log(rot: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Log map: rotation matrix -> rotation vector with angle in [0, pi].

    Goes through the quaternion (Shepperd), so it is accurate near 0 and near pi, where the
    axis is recovered from the largest diagonal element instead of the vanishing skew part.

    Args:
        rot: Rotation matrix (3, 3).
        out: Optional (3,) array to write into.

    Returns:
        Rotation vector (3,) [rad].
    """
    w, x, y, z = _matrix_to_quat_tuple(rot)
    if out is None:
        out = np.empty(3)
    out[:] = _quat_log_tuple(w, x, y, z)
    return out


def orientation_error(
    quat_target: np.ndarray, rot: np.ndarray, out: np.ndarray | None = None
) -> np.ndarray:
    """Log(R_d R^T) computed as the log of the quaternion q_d * conj(q(R)) (shortest arc).

    Args:
        quat_target: Desired orientation q_d (w, x, y, z), normalized here.
        rot: Current orientation R (3, 3).
        out: Optional (3,) array to write into.

    Returns:
        Rotation vector (3,) [rad], world frame, angle in [0, pi].
    """
    dw, dx, dy, dz = _quat_tuple(quat_target)
    w, x, y, z = _matrix_to_quat_tuple(rot)
    # q_d * conj(q)
    ew = dw * w + dx * x + dy * y + dz * z
    ex = -dw * x + dx * w - dy * z + dz * y
    ey = -dw * y + dx * z + dy * w - dz * x
    ez = -dw * z - dx * y + dy * x + dz * w
    if ew < 0.0:
        ew, ex, ey, ez = -ew, -ex, -ey, -ez
    if out is None:
        out = np.empty(3)
    out[:] = _quat_log_tuple(ew, ex, ey, ez)
    return out


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v]_x such that [v]_x u = v x u."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rot6d_from_matrix(rot: np.ndarray) -> np.ndarray:
    """rot6d: first two columns of R, column-wise [r11, r21, r31, r12, r22, r32]."""
    rot = np.asarray(rot, dtype=float)
    return np.concatenate([rot[:, 0], rot[:, 1]])


def matrix_from_rot6d(rot6d: np.ndarray) -> np.ndarray:
    """Rotation matrix from rot6d via Gram-Schmidt (columns b1, b2, b1 x b2).

    Raises:
        InvalidArgumentError: If the two 3-vectors are (nearly) zero or parallel.
    """
    r = np.asarray(rot6d, dtype=float).reshape(6)
    a1, a2 = r[:3], r[3:]
    n1 = float(np.linalg.norm(a1))
    if not (n1 > 1e-9 and math.isfinite(n1)):
        raise InvalidArgumentError(f"invalid rot6d {rot6d!r}; valid: finite, non-zero columns")
    b1 = a1 / n1
    u2 = a2 - float(b1 @ a2) * b1
    n2 = float(np.linalg.norm(u2))
    if not (n2 > 1e-9 and math.isfinite(n2)):
        raise InvalidArgumentError(f"invalid rot6d {rot6d!r}; valid: non-parallel columns")
    b2 = u2 / n2
    return np.column_stack([b1, b2, np.cross(b1, b2)])


def slerp(quat0: np.ndarray, quat1: np.ndarray, t: float) -> np.ndarray:
    """Spherical linear interpolation along the shortest arc, t in [0, 1] -> unit quaternion."""
    q0 = np.array(_quat_tuple(quat0))
    q1 = np.array(_quat_tuple(quat1))
    dot = float(q0 @ q1)
    if dot < 0.0:
        q1, dot = -q1, -dot
    if dot > 1.0 - 1e-10:
        q = q0 + t * (q1 - q0)
    else:
        theta = math.acos(min(dot, 1.0))
        q = (math.sin((1.0 - t) * theta) * q0 + math.sin(t * theta) * q1) / math.sin(theta)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0.0 else -q
