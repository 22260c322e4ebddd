"""The impedance law's options (impedance_options.py): TCP-frame gains, pose-error clip,
clamped null space, the authors' negative null-space damping; and the joint-limit repulsion
(joint_limits.py). Values computed by hand."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.fake_dynamics import ConstantArmDynamics

from impact_control.errors import InvalidArgumentError
from impact_control.impedance import CartesianImpedance, ImpedanceConfig
from impact_control.jacobian import regularized_wrench_map
from impact_control.joint_limits import (
    FR3_Q_MAX_RAD,
    FR3_Q_MIN_RAD,
    JointLimitConfig,
    JointLimitRepulsion,
)
from impact_control.lie import matrix_to_quat, so3_exp


def _law(config: ImpedanceConfig, q: np.ndarray, dq: np.ndarray, e_pos: np.ndarray,
         q_null: np.ndarray | None = None) -> tuple[CartesianImpedance, ConstantArmDynamics]:
    """The law once at (q, dq) with the target e_pos from the TCP (same orientation)."""
    dyn = ConstantArmDynamics(seed=11)
    dyn.rot_ref = so3_exp(np.array([2.5, 0.4, -0.3]))  # a TCP frame far from the world's
    dyn.update(q, dq)
    imp = CartesianImpedance(config)
    imp.set_posture(q if q_null is None else q_null)
    wmap = regularized_wrench_map(dyn.jacobian, config.nullspace_pinv_damping)
    imp.compute(dyn, q, dq, dyn.pos_ee_world + e_pos, matrix_to_quat(dyn.rot_ee_world), wmap)
    return imp, dyn


def test_tcp_frame_gains_equal_world_gains_when_isotropic_and_unclipped() -> None:
    q, dq = np.full(7, 0.2), np.array([0.3, -0.1, 0.2, 0.05, -0.4, 0.1, 0.2])
    e = np.array([0.02, -0.01, 0.03])
    world = _law(ImpedanceConfig(), q, dq, e)[0].tau_no_gravity.copy()
    tcp = _law(ImpedanceConfig(gains_frame="tcp"), q, dq, e)[0].tau_no_gravity
    np.testing.assert_allclose(tcp, world, atol=1e-12)


def test_position_error_is_clipped_per_tcp_axis() -> None:
    """0.3 m along TCP x and 0.05 m along TCP y: clipped to (0.1, 0.05, 0) m, so K e = (40,
    20, 0) N on TCP axes, R (40, 20, 0) in the world (no velocity, no orientation error)."""
    cfg = ImpedanceConfig(gains_frame="tcp", pose_error_clip_m=0.1, pose_error_clip_rad=0.5)
    q = np.full(7, 0.2)
    rot = _law(cfg, q, np.zeros(7), np.zeros(3))[1].rot_ee_world
    imp, _ = _law(cfg, q, np.zeros(7), rot @ np.array([0.3, 0.05, 0.0]))
    np.testing.assert_allclose(imp.extra.error_gains[:3], [0.1, 0.05, 0.0], atol=1e-12)
    np.testing.assert_allclose(imp.wrench_imp_world[:3], rot @ np.array([40.0, 20.0, 0.0]),
                               atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(imp.pose_error[:3]), np.hypot(0.3, 0.05))


def test_nullspace_torque_is_clamped_to_5_nm_per_joint_after_the_projection() -> None:
    q, q_null = np.zeros(7), np.array([3.0, -3.0, 2.0, 0.0, 0.0, 0.0, 0.0])
    base = {"nullspace_stiffness_nm_per_rad": 20.0, "nullspace_pinv_damping": 1e-6}
    imp, dyn = _law(ImpedanceConfig(**base), q, np.zeros(7), np.zeros(3), q_null)
    clamped = _law(ImpedanceConfig(**base, nullspace_torque_max_nm=5.0), q, np.zeros(7),
                   np.zeros(3), q_null)[0]
    n_tau0 = imp.tau_posture - dyn.jacobian.T @ imp.wrench_null_world  # N tau_0
    assert np.abs(n_tau0).max() > 5.0 > np.abs(n_tau0).min()  # the clamp binds on some joints
    np.testing.assert_allclose(clamped.extra.tau_null, np.clip(n_tau0, -5.0, 5.0), atol=1e-9)
    np.testing.assert_allclose(clamped.tau_no_gravity, np.clip(n_tau0, -5.0, 5.0), atol=1e-9)


def test_negative_nullspace_damping_as_coded_injects_energy() -> None:
    """The authors' d_n = -1: tau_0 = k_n (q_null - q) + dq; None is 2 sqrt(k_n)."""
    dq = np.array([0.1, -0.2, 0.3, 0.0, 0.1, 0.0, -0.1])
    imp, _ = _law(ImpedanceConfig(nullspace_stiffness_nm_per_rad=2.0,
                                  nullspace_damping_nms_per_rad=-1.0), np.zeros(7), dq, np.zeros(3))
    np.testing.assert_allclose(imp.tau_posture, dq, atol=1e-15)
    assert ImpedanceConfig(nullspace_stiffness_nm_per_rad=2.0).nullspace_damping == (
        pytest.approx(2.0 * np.sqrt(2.0)))
    with pytest.raises(InvalidArgumentError, match="valid: finite or None"):
        ImpedanceConfig(nullspace_damping_nms_per_rad=float("nan"))
    with pytest.raises(InvalidArgumentError, match="valid choices: world, tcp"):
        ImpedanceConfig(gains_frame="base")


@pytest.mark.parametrize(("joint", "q", "tau"), [
    (0, FR3_Q_MIN_RAD[0] + 0.3, 0.0),  # at the edge of the 0.3 rad range: nothing
    (0, FR3_Q_MIN_RAD[0] + 0.15, 2.5),  # half way: 5 Nm x 0.5, pushing up
    (0, FR3_Q_MIN_RAD[0] - 0.1, 5.0),  # beyond the limit: 5 Nm
    (3, FR3_Q_MAX_RAD[3] - 0.06, -4.0),  # joint 4 near its upper limit -0.1518: 5 x 0.8, down
    (5, 0.5 * (FR3_Q_MIN_RAD[5] + FR3_Q_MAX_RAD[5]), 0.0),
])
def test_joint_limit_repulsion_rises_linearly_to_5_nm_within_0_3_rad(joint, q, tau) -> None:
    rep = JointLimitRepulsion(JointLimitConfig(torque_max_nm=5.0, range_rad=0.3))
    qs = 0.5 * (np.array(FR3_Q_MIN_RAD) + np.array(FR3_Q_MAX_RAD))
    qs[joint] = q
    out = rep.torque(qs)
    assert out[joint] == pytest.approx(tau, abs=1e-9)
    assert np.count_nonzero(np.delete(out, joint)) == 0


def test_joint_limit_config_is_checked_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="q_min_rad < q_max_rad"):
        JointLimitConfig(q_min_rad=FR3_Q_MAX_RAD, q_max_rad=FR3_Q_MIN_RAD)
    with pytest.raises(InvalidArgumentError, match="a tuple of 7 floats"):
        JointLimitConfig(q_min_rad=(0.0,))


def test_option_flags_read_the_slots_their_layout_defines() -> None:
    """The tick reads the impedance options' flags without building their views (a view
    costs its reference count on every tick): the slots must be the layout's."""
    from impact_control.impedance_options import (
        IMPEDANCE_EXTRA_LAYOUT,
        null_clamp_on,
        options_on,
        unpack_impedance_extra,
    )

    ext = np.zeros(IMPEDANCE_EXTRA_LAYOUT.size(n=7))
    x, length = unpack_impedance_extra(ext, 7)
    assert length == ext.shape[0]
    x.on[0] = 1.0
    assert options_on(ext) and not null_clamp_on(ext)
    x.null_clamp[0] = 1.0
    assert null_clamp_on(ext)
    off = CartesianImpedance(ImpedanceConfig())
    assert not options_on(off.state.extra) and not null_clamp_on(off.state.extra)
