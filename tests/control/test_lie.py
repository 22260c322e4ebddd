"""SO(3) helpers: round trips, robustness near 0 and pi, finite differences, rot6d, slerp."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_control.lie import (
    matrix_from_rot6d,
    matrix_to_quat,
    orientation_error,
    quat_multiply,
    quat_to_matrix,
    quat_to_rotvec,
    rot6d_from_matrix,
    rotvec_to_quat,
    skew,
    slerp,
    so3_exp,
    so3_log,
)

RNG = np.random.default_rng(0)


def _random_rotvecs(n: int, max_angle: float = math.pi - 1e-6) -> list[np.ndarray]:
    out = []
    for _ in range(n):
        axis = RNG.normal(size=3)
        axis /= np.linalg.norm(axis)
        out.append(axis * RNG.uniform(0.0, max_angle))
    return out


def test_quat_to_matrix_known_value() -> None:
    c = math.cos(math.pi / 4)
    rot = quat_to_matrix(np.array([c, 0.0, 0.0, c]))  # +90 deg about z
    np.testing.assert_allclose(rot, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)


def test_quaternion_matrix_round_trip() -> None:
    for _ in range(200):
        quat = RNG.normal(size=4)
        rot = quat_to_matrix(quat)
        np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-13)
        assert np.linalg.det(rot) == pytest.approx(1.0, abs=1e-13)
        back = matrix_to_quat(rot)
        assert back[0] >= 0.0
        expected = quat / np.linalg.norm(quat) * np.sign(quat[0])
        np.testing.assert_allclose(back, expected, atol=1e-12)


def test_quat_multiply_matches_matrix_product() -> None:
    q1, q2 = RNG.normal(size=4), RNG.normal(size=4)
    q1 /= np.linalg.norm(q1)
    q2 /= np.linalg.norm(q2)
    np.testing.assert_allclose(
        quat_to_matrix(quat_multiply(q1, q2)), quat_to_matrix(q1) @ quat_to_matrix(q2), atol=1e-13
    )


def test_exp_known_value_and_log_exp_identity() -> None:
    np.testing.assert_allclose(
        so3_exp(np.array([0.0, 0.0, math.pi / 2])), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15
    )
    for rotvec in _random_rotvecs(200):
        np.testing.assert_allclose(so3_log(so3_exp(rotvec)), rotvec, atol=1e-10)
        np.testing.assert_allclose(quat_to_rotvec(rotvec_to_quat(rotvec)), rotvec, atol=1e-10)


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3])
def test_log_near_zero(angle: float) -> None:
    rotvec = angle * np.array([0.6, -0.8, 0.0])
    np.testing.assert_allclose(so3_log(so3_exp(rotvec)), rotvec, atol=1e-15, rtol=1e-9)


@pytest.mark.parametrize("delta", [0.0, 1e-12, 1e-9, 1e-6, 1e-4])
def test_log_near_pi(delta: float) -> None:
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    rot = so3_exp(axis * (math.pi - delta))
    rotvec = so3_log(rot)
    assert np.linalg.norm(rotvec) == pytest.approx(math.pi - delta, abs=1e-9)
    # At exactly pi the sign of the axis is ambiguous; the rotation must be reproduced.
    np.testing.assert_allclose(so3_exp(rotvec), rot, atol=1e-9)
    if delta > 0.0:
        np.testing.assert_allclose(rotvec, axis * (math.pi - delta), atol=1e-8)


def test_exp_finite_difference_gives_world_angular_velocity() -> None:
    r0 = so3_exp(np.array([0.3, -0.2, 0.9]))
    omega = np.array([0.4, -1.1, 0.7])
    h = 1e-6
    rot_plus, rot_minus = so3_exp(h * omega) @ r0, so3_exp(-h * omega) @ r0
    rdot = (rot_plus - rot_minus) / (2 * h)
    np.testing.assert_allclose(rdot @ r0.T, skew(omega), atol=1e-8)


def test_log_finite_difference_near_identity() -> None:
    r0 = so3_exp(np.array([0.5, 0.1, -0.4]))
    omega = np.array([-0.3, 0.8, 0.2])
    h = 1e-6
    # d/dt Log(R(t) R0^T) at t = 0 for R(t) = Exp(t omega) R0 equals omega.
    deriv = (so3_log(so3_exp(h * omega) @ r0 @ r0.T) - so3_log(r0 @ r0.T)) / h
    np.testing.assert_allclose(deriv, omega, atol=1e-8)


def test_orientation_error_equals_log_of_rd_rt() -> None:
    for _ in range(100):
        quat_d = RNG.normal(size=4)
        rot = quat_to_matrix(RNG.normal(size=4))
        expected = so3_log(quat_to_matrix(quat_d) @ rot.T)
        np.testing.assert_allclose(orientation_error(quat_d, rot), expected, atol=1e-10)
    rot = so3_exp(np.array([0.2, 0.3, -0.1]))
    a = np.array([0.01, -0.02, 0.03])
    np.testing.assert_allclose(orientation_error(matrix_to_quat(so3_exp(a) @ rot), rot), a)


def test_rot6d_round_trip_and_layout() -> None:
    rot = so3_exp(np.array([0.4, -1.2, 2.0]))
    r6 = rot6d_from_matrix(rot)
    np.testing.assert_array_equal(
        r6, [rot[0, 0], rot[1, 0], rot[2, 0], rot[0, 1], rot[1, 1], rot[2, 1]]
    )
    np.testing.assert_allclose(matrix_from_rot6d(r6), rot, atol=1e-14)


def test_rot6d_gram_schmidt_of_perturbed_input() -> None:
    rot = so3_exp(np.array([1.0, 0.5, -0.3]))
    r6 = rot6d_from_matrix(rot) * 3.0 + np.concatenate([np.zeros(3), 0.5 * rot[:, 0]])
    out = matrix_from_rot6d(r6)
    np.testing.assert_allclose(out, rot, atol=1e-13)  # scaling / shear along b1 removed
    np.testing.assert_allclose(out.T @ out, np.eye(3), atol=1e-14)


@pytest.mark.parametrize(
    "bad", [np.array([np.nan, 0, 0, 0, 1, 0]), np.array([1.0, 0, 0, 0, np.inf, 0])]
)
def test_rot6d_non_finite_raises(bad: np.ndarray) -> None:
    with pytest.raises(InvalidArgumentError, match="valid: finite numbers"):
        matrix_from_rot6d(bad)


def _assert_rotation(rot: np.ndarray) -> None:
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0, abs=1e-12)


def test_degenerate_rot6d_maps_to_the_documented_rotation() -> None:
    """Zero first column -> world x; a second column parallel, antiparallel or zero -> the
    world axis least aligned with b1 (ties: x first), orthogonalized."""
    np.testing.assert_array_equal(matrix_from_rot6d(np.zeros(6)), np.eye(3))
    np.testing.assert_array_equal(matrix_from_rot6d(np.array([1.0, 0, 0, 2.0, 0, 0])), np.eye(3))
    np.testing.assert_array_equal(matrix_from_rot6d(np.array([0.0, 0, 0, 0, 0, 1])),
                                  np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]))
    rot = matrix_from_rot6d(np.array([-1.0, 1, 1, 1, -1, -1]))  # issue 16: PPO's clipped corner
    _assert_rotation(rot)
    b1 = np.array([-1.0, 1, 1]) / np.sqrt(3)
    b2 = np.array([1.0, 0, 0]) - b1[0] * b1
    np.testing.assert_allclose(rot[:, :2], np.stack([b1, b2 / np.linalg.norm(b2)], 1),
                               atol=1e-15)


def test_every_corner_of_the_action_box_is_a_rotation() -> None:
    corners = np.array(np.meshgrid(*[[-1.0, 0.0, 1.0]] * 6)).reshape(6, -1).T
    for c in corners:
        _assert_rotation(matrix_from_rot6d(c))


def test_zero_quaternion_raises() -> None:
    with pytest.raises(InvalidArgumentError):
        quat_to_matrix(np.zeros(4))


def test_slerp_endpoints_constant_speed_and_shortest_arc() -> None:
    q0 = matrix_to_quat(so3_exp(np.array([0.1, 0.2, 0.3])))
    q1 = matrix_to_quat(so3_exp(np.array([0.9, -0.5, 1.3])))
    np.testing.assert_allclose(slerp(q0, q1, 0.0), q0, atol=1e-14)
    np.testing.assert_allclose(slerp(q0, q1, 1.0), q1, atol=1e-14)
    total = np.linalg.norm(so3_log(quat_to_matrix(q1) @ quat_to_matrix(q0).T))
    ts = np.linspace(0.0, 1.0, 11)
    rots = [quat_to_matrix(slerp(q0, q1, t)) for t in ts]
    steps = [np.linalg.norm(so3_log(b @ a.T)) for a, b in zip(rots[:-1], rots[1:], strict=True)]
    np.testing.assert_allclose(steps, total / 10, rtol=1e-9)
    # -q1 is the same rotation: the interpolation must not take the long way round.
    np.testing.assert_allclose(quat_to_matrix(slerp(q0, -q1, 0.5)), rots[5], atol=1e-12)
