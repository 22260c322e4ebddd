"""The target-pose EMA (target_filter.py, se3.py) against values computed by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_control.lie import matrix_to_quat, quat_to_matrix, so3_exp, so3_log
from impact_control.se3 import se3_exp, se3_log
from impact_control.target_filter import TargetFilter, TargetFilterConfig


def _rot_x(angle: float) -> np.ndarray:
    return so3_exp(np.array([angle, 0.0, 0.0]))


def _quat_x(angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2), math.sin(angle / 2), 0.0, 0.0])


def _filter(space: str = "se3_log") -> TargetFilter:
    return TargetFilter(TargetFilterConfig(enabled=True, weight_new=0.9, space=space))


def test_se3_log_and_exp_are_inverse_and_match_the_closed_forms() -> None:
    rng = np.random.default_rng(4)
    for _ in range(20):
        rot = so3_exp(rng.normal(size=3))
        pos = rng.normal(size=3)
        xi, pos2, quat2 = np.empty(6), np.empty(3), np.empty(4)
        q = matrix_to_quat(rot)
        se3_log(pos, q[0], q[1], q[2], q[3], xi)
        np.testing.assert_allclose(xi[3:], so3_log(rot), atol=1e-12)
        se3_exp(xi, pos2, quat2)
        np.testing.assert_allclose(pos2, pos, atol=1e-12)
        np.testing.assert_allclose(quat_to_matrix(quat2), rot, atol=1e-12)
    xi = np.array([1.0, 2.0, 3.0, 0.0, 0.0, 0.0])  # no rotation: v = p
    se3_exp(xi, pos2, quat2)
    np.testing.assert_array_equal(pos2, [1.0, 2.0, 3.0])


def test_first_tick_starts_from_the_tcp_and_weighs_the_new_target_0_9() -> None:
    f = _filter()
    rot = _rot_x(2.0)
    p_tcp, p_target = np.array([0.4, 0.0, 0.3]), np.array([0.5, -0.1, 0.2])
    f.step(p_target, matrix_to_quat(rot), p_tcp, rot)  # same rotation: a lerp of positions
    np.testing.assert_allclose(f.pos_target_world, 0.1 * p_tcp + 0.9 * p_target, atol=1e-12)
    for k in range(2, 6):  # a fixed target: the gap shrinks by 0.1 per tick
        f.step(p_target, matrix_to_quat(rot), p_tcp, rot)
        np.testing.assert_allclose(f.pos_target_world - p_target, 0.1 ** k * (p_tcp - p_target),
                                   atol=1e-12)
    f.reset()  # forgets: the next tick starts from the TCP again
    f.step(p_target, matrix_to_quat(rot), p_tcp, rot)
    np.testing.assert_allclose(f.pos_target_world, 0.1 * p_tcp + 0.9 * p_target, atol=1e-12)


def test_rotation_about_one_axis_averages_the_angles() -> None:
    f = _filter()
    f.step(np.zeros(3), _quat_x(1.0), np.zeros(3), _rot_x(0.2))
    np.testing.assert_allclose(quat_to_matrix(f.quat_target_world), _rot_x(0.1 * 0.2 + 0.9),
                               atol=1e-12)


def test_as_coded_the_log_average_breaks_across_pi_and_geodesic_does_not() -> None:
    """TCP at pi - 0.01 about x, target at pi + 0.01 (0.02 rad away): the logs are
    +(pi - 0.01) x and -(pi - 0.01) x, their average 0.1 (+) + 0.9 (-) = -0.8 (pi - 0.01) x,
    a rotation 0.8 (pi - 0.01) about -x: 2.5 rad from both. The geodesic average moves 0.9 of
    the 0.02 rad: to pi + 0.008 about x."""
    a = math.pi - 0.01
    coded, geodesic = _filter(), _filter("geodesic")
    for f in (coded, geodesic):
        f.step(np.zeros(3), _quat_x(math.pi + 0.01), np.zeros(3), _rot_x(a))
    np.testing.assert_allclose(quat_to_matrix(coded.quat_target_world), _rot_x(-0.8 * a),
                               atol=1e-9)
    np.testing.assert_allclose(quat_to_matrix(geodesic.quat_target_world),
                               _rot_x(math.pi + 0.008), atol=1e-9)


def test_geodesic_equals_the_log_average_away_from_pi() -> None:
    rng = np.random.default_rng(7)
    p_tcp, p_target = rng.normal(size=3), rng.normal(size=3)
    r_tcp = so3_exp(np.array([0.3, -0.2, 0.1]))
    r_target = so3_exp(np.array([0.3, -0.2, 0.1]))  # same rotation: both lerp the position
    coded, geodesic = _filter(), _filter("geodesic")
    for f in (coded, geodesic):
        f.step(p_target, matrix_to_quat(r_target), p_tcp, r_tcp)
    np.testing.assert_allclose(coded.pos_target_world, geodesic.pos_target_world, atol=1e-12)


def test_bad_config_is_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="valid choices: se3_log, geodesic"):
        TargetFilterConfig(space="slerp")
    with pytest.raises(InvalidArgumentError, match=r"weight_new 0.0; valid: \(0, 1\]"):
        TargetFilterConfig(weight_new=0.0)
