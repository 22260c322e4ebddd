"""SO(3) helpers: quaternions (w, x, y, z), exp/log maps, rot6d and slerp.

Small functions work on Python scalars internally because for 3x3 and 4-vectors that is several
times cheaper than chains of small NumPy calls. Matrix -> quaternion (Shepperd), the quaternion
log and ``orientation_error`` are the numba functions of ``control/kernels.py`` that the
controller runs every tick (imported on first use, so importing this module stays light).
"""

from __future__ import annotations

import math

import numpy as np

from impact_control.errors import InvalidArgumentError


def invalid_quaternion(quat: object) -> InvalidArgumentError:
    """The error raised for a zero or non-finite quaternion."""
    return InvalidArgumentError(f"invalid quaternion {quat!r}; valid: finite, non-zero wxyz")


def _quat_tuple(quat: np.ndarray) -> tuple[float, float, float, float]:
    """Return the normalized quaternion as floats; raise on a zero/non-finite input."""
    w, x, y, z = quat.tolist() if isinstance(quat, np.ndarray) else (float(v) for v in quat)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if not (n > 1e-12 and math.isfinite(n)):
        raise invalid_quaternion(quat)
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
    """Shepperd's method (``kernels.matrix_to_quat``); returns (w, x, y, z) with w >= 0."""
    from impact_control.kernel_math import matrix_to_quat

    return matrix_to_quat(np.ascontiguousarray(rot, dtype=np.float64))


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


def _quat_log_tuple(w: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """Rotation vector of a unit quaternion with w >= 0 (angle in [0, pi],
    ``kernel_math.quat_log``)."""
    from impact_control.kernel_math import quat_log

    return quat_log(float(w), float(x), float(y), float(z))


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

    The controller's per-tick pose error is the same function (``kernel_math.orientation_error``).

    Args:
        quat_target: Desired orientation q_d (w, x, y, z), normalized here.
        rot: Current orientation R (3, 3).
        out: Optional (3,) array to write into.

    Returns:
        Rotation vector (3,) [rad], world frame, angle in [0, pi].

    Raises:
        InvalidArgumentError: If ``quat_target`` is zero or not finite.
    """
    from impact_control.kernel_math import orientation_error as kernel_orientation_error

    res = np.empty(3)
    quat = np.ascontiguousarray(quat_target, dtype=np.float64)
    if not kernel_orientation_error(quat, np.ascontiguousarray(rot, dtype=np.float64), res):
        raise invalid_quaternion(quat_target)
    if out is None:
        return res
    out[:] = res
    return out


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v]_x such that [v]_x u = v x u."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rot6d_from_matrix(rot: np.ndarray) -> np.ndarray:
    """rot6d: first two columns of R, column-wise [r11, r21, r31, r12, r22, r32]."""
    rot = np.asarray(rot, dtype=float)
    return np.concatenate([rot[:, 0], rot[:, 1]])


ROT6D_MIN_NORM = 1e-9
"""Below this length a rot6d column (or the second column's part orthogonal to the first) is
degenerate and replaced as ``matrix_from_rot6d`` documents."""


def _least_aligned_axis(x: float, y: float, z: float) -> tuple[float, float, float]:
    """The world axis with the smallest |component| of (x, y, z) (first on ties)."""
    mags = [abs(x), abs(y), abs(z)]
    i = mags.index(min(mags))
    return (1.0 if i == 0 else 0.0, 1.0 if i == 1 else 0.0, 1.0 if i == 2 else 0.0)


def matrix_from_rot6d(rot6d: np.ndarray) -> np.ndarray:
    """Rotation matrix from rot6d via Gram-Schmidt (columns b1, b2, b1 x b2).

    Every finite input gives a rotation (an RL policy's clipped corners included): a first
    column shorter than ``ROT6D_MIN_NORM`` becomes world x; a second column whose part
    orthogonal to b1 is shorter than that (zero, parallel or antiparallel to b1) is replaced by
    the world axis least aligned with b1 (first of x, y, z on ties), then orthogonalized.

    Raises:
        InvalidArgumentError: If an entry is not finite.
    """
    x1, y1, z1, x2, y2, z2 = np.asarray(rot6d, dtype=float).reshape(6).tolist()
    if not all(math.isfinite(v) for v in (x1, y1, z1, x2, y2, z2)):
        raise InvalidArgumentError(f"invalid rot6d {rot6d!r}; valid: finite numbers")
    n1 = math.sqrt(x1 * x1 + y1 * y1 + z1 * z1)
    if not n1 > ROT6D_MIN_NORM:
        x1, y1, z1, n1 = 1.0, 0.0, 0.0, 1.0
    x1, y1, z1 = x1 / n1, y1 / n1, z1 / n1
    d = x1 * x2 + y1 * y2 + z1 * z2
    x2, y2, z2 = x2 - d * x1, y2 - d * y1, z2 - d * z1
    n2 = math.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
    if not n2 > ROT6D_MIN_NORM:
        x2, y2, z2 = _least_aligned_axis(x1, y1, z1)
        d = x1 * x2 + y1 * y2 + z1 * z2
        x2, y2, z2 = x2 - d * x1, y2 - d * y1, z2 - d * z1
        n2 = math.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
    x2, y2, z2 = x2 / n2, y2 / n2, z2 / n2
    return np.array([
        [x1, x2, y1 * z2 - z1 * y2],
        [y1, y2, z1 * x2 - x1 * z2],
        [z1, z2, x1 * y2 - y1 * x2],
    ])


def slerp(quat0: np.ndarray, quat1: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    """Spherical linear interpolation along the shortest arc, t in [0, 1] -> unit quaternion.

    A scalar ``t`` gives (4,); an array of n values gives (n, 4), one row per value (the env
    interpolates all control ticks of a policy step in one call).
    """
    q0 = np.array(_quat_tuple(quat0))
    q1 = np.array(_quat_tuple(quat1))
    dot = float(q0 @ q1)
    if dot < 0.0:
        q1, dot = -q1, -dot
    tt = np.asarray(t, dtype=float)[..., None]
    if dot > 1.0 - 1e-10:
        q = q0 + tt * (q1 - q0)
    else:
        theta = math.acos(min(dot, 1.0))
        q = (np.sin((1.0 - tt) * theta) * q0 + np.sin(tt * theta) * q1) / math.sin(theta)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] >= 0.0, q, -q)
