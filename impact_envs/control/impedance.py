"""Task-space impedance law with null-space posture control and model compensation.

tau_no_gravity = J^T (w_imp + w_ff) + N tau_0 + C(q, dq) dq,   g(q) kept separate
w_imp  = K e - D J dq,   e = [p_d - p; Log(R_d R^T)]  (world frame)
tau_0  = k_n (q_null - q) - d_n dq
N      = I - J^T (J^+)^T,   J^+ = J^T (J J^T + lambda_n^2 I)^-1   (Franka's static projector)

w_ff is any extra wrench (internal-model feedforward, commanded wrench). The projection is
evaluated as N tau_0 = tau_0 - J^T w_null with w_null = (J^+)^T tau_0, so all wrenches share one
J^T product: tau = J^T (w_imp + w_ff - w_null) + tau_0 + C dq. Gravity is returned separately
(``tau_gravity``) because the torque-rate limiter acts on the command without gravity, like
libfranka.
"""

from __future__ import annotations

import numpy as np

from impact_envs.control import kernels
from impact_envs.control.arm_model import ArmDynamics, dynamics_arrays
from impact_envs.control.config import ImpedanceConfig
from impact_envs.control.lie import invalid_quaternion


class CartesianImpedance:
    """Preallocated impedance law; all outputs are attributes overwritten every ``compute``.

    The law itself is ``kernels.impedance_law`` (also run by ``kernels.controller_tick``); the
    array attributes are views of ``buffer`` (layout: ``kernels.impedance_views``).

    Attributes:
        pose_error: e = [p_d - p (3) [m]; Log(R_d R^T) (3) [rad]], world frame.
        twist_world: TCP velocity J dq (6,) [m/s, rad/s].
        wrench_imp_world: K e - D J dq (6,) [N, Nm].
        tau_posture: Unprojected posture torque tau_0 (7,) [Nm].
        wrench_null_world: (J^+)^T tau_0 (6,) [N, Nm], removed by the projector.
        tau_coriolis: C dq (7,) [Nm] (zeros if disabled).
        tau_gravity: g(q) (7,) [Nm] (zeros if disabled).
        tau_no_gravity: Full command without gravity (7,) [Nm].
        q_null: Posture target of the null-space task (7,) [rad].
    """

    def __init__(self, config: ImpedanceConfig, n_joints: int = 7) -> None:
        """Create the law from ``config`` for an arm with ``n_joints`` joints."""
        self.config = config
        self.k_null = config.nullspace_stiffness_nm_per_rad
        self.d_null = config.nullspace_damping
        self.buffer = np.zeros(kernels.impedance_size(n_joints))
        (par, self._k_q_null, self.pose_error, self.twist_world, self.wrench_imp_world,
         self.tau_posture, self.wrench_null_world, self._w, self.tau_coriolis, self.tau_gravity,
         self.tau_no_gravity) = kernels.impedance_views(self.buffer)  # fmt: skip
        par[:] = (
            config.stiffness_translational_n_per_m
            + config.stiffness_rotational_nm_per_rad
            + config.damping_translational_ns_per_m
            + config.damping_rotational_nms_per_rad
            + (self.k_null, self.d_null)
            + (float(config.compensate_gravity), float(config.compensate_coriolis))
        )
        self.stiffness, self.damping = par[:6], par[6:12]
        self.q_null = np.zeros(n_joints)
        self._zeros6 = np.zeros(6)

    def set_posture(self, q_null: np.ndarray) -> None:
        """Set the null-space posture target q_null [rad] (the controller does it at reset)."""
        self.q_null[:] = q_null
        np.multiply(self.q_null, self.k_null, out=self._k_q_null)

    def compute_pose_error(
        self,
        pos_ee_world: np.ndarray,
        rot_ee_world: np.ndarray,
        pos_target_world: np.ndarray,
        quat_target_world: np.ndarray,
    ) -> np.ndarray:
        """Fill and return ``pose_error`` = [p_d - p; Log(R_d R^T)] (6,) [m, rad]."""
        quat = np.ascontiguousarray(quat_target_world, dtype=np.float64)
        rot = np.ascontiguousarray(rot_ee_world, dtype=np.float64)
        if not kernels.orientation_error(quat, rot, self.pose_error[3:]):
            raise invalid_quaternion(quat_target_world)
        np.subtract(pos_target_world, pos_ee_world, out=self.pose_error[:3])
        return self.pose_error

    def compute(
        self,
        dynamics: ArmDynamics,
        q: np.ndarray,
        dq: np.ndarray,
        pos_target_world: np.ndarray,
        quat_target_world: np.ndarray,
        wrench_map: np.ndarray,
        wrench_ff_world: np.ndarray | None = None,
    ) -> np.ndarray:
        """Evaluate the law at the state cached in ``dynamics`` (already ``update``-d).

        Args:
            dynamics: Model updated at (q, dq).
            q: Joint positions (7,) [rad].
            dq: Joint velocities (7,) [rad/s].
            pos_target_world: Desired TCP position (3,) [m].
            quat_target_world: Desired TCP orientation (w, x, y, z).
            wrench_map: (J J^T + lambda_n^2 I)^-1 J (6, 7), see ``regularized_wrench_map``.
            wrench_ff_world: Optional extra wrench added as J^T w_ff (6,) [N, Nm].

        Returns:
            ``tau_no_gravity`` (7,) [Nm]; add ``tau_gravity`` for the full command.

        Raises:
            InvalidArgumentError: If the target quaternion is zero or not finite.
        """
        f64 = np.float64
        w_ff = self._zeros6 if wrench_ff_world is None else np.asarray(wrench_ff_world, f64)
        ok = kernels.impedance_law(
            dynamics_arrays(dynamics), np.asarray(q, f64), np.asarray(dq, f64),
            np.asarray(pos_target_world, f64), np.asarray(quat_target_world, f64),
            np.asarray(wrench_map, f64), w_ff, self.buffer,
        )  # fmt: skip
        if not ok:
            raise invalid_quaternion(quat_target_world)
        return self.tau_no_gravity

    def tau_null(self, jacobian: np.ndarray) -> np.ndarray:
        """Projected posture torque N tau_0 = tau_0 - J^T w_null (7,) [Nm] of the last tick."""
        return self.tau_posture - self.wrench_null_world @ jacobian
