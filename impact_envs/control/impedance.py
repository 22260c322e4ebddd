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

from impact_envs.control.config import ImpedanceConfig
from impact_envs.control.lie import orientation_error
from impact_envs.control.protocols import ArmDynamics


class CartesianImpedance:
    """Preallocated impedance law; all outputs are attributes overwritten every ``compute``.

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
        self.stiffness = np.array(
            config.stiffness_translational_n_per_m + config.stiffness_rotational_nm_per_rad
        )
        self.damping = np.array(
            config.damping_translational_ns_per_m + config.damping_rotational_nms_per_rad
        )
        self.k_null = config.nullspace_stiffness_nm_per_rad
        self.d_null = config.nullspace_damping
        self.q_null = np.zeros(n_joints)
        self._k_q_null = np.zeros(n_joints)
        self.pose_error = np.zeros(6)
        self._e_pos, self._e_rot = self.pose_error[:3], self.pose_error[3:]
        self.twist_world = np.zeros(6)
        self.wrench_imp_world = np.zeros(6)
        self.wrench_null_world = np.zeros(6)
        self.tau_posture = np.zeros(n_joints)
        self.tau_coriolis = np.zeros(n_joints)
        self.tau_gravity = np.zeros(n_joints)
        self.tau_no_gravity = np.zeros(n_joints)
        self._w = np.zeros(6)
        self._tmp6 = np.zeros(6)
        self._tmp7 = np.zeros(n_joints)

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
        np.subtract(pos_target_world, pos_ee_world, out=self._e_pos)
        orientation_error(quat_target_world, rot_ee_world, out=self._e_rot)
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
        """
        jac = dynamics.jacobian
        self.compute_pose_error(
            dynamics.pos_ee_world, dynamics.rot_ee_world, pos_target_world, quat_target_world
        )
        np.dot(jac, dq, out=self.twist_world)
        w_imp, tmp6 = self.wrench_imp_world, self._tmp6
        np.multiply(self.stiffness, self.pose_error, out=w_imp)
        np.multiply(self.damping, self.twist_world, out=tmp6)
        w_imp -= tmp6
        # Posture torque tau_0 = k_n q_null - k_n q - d_n dq and its task-space part.
        tau0 = self.tau_posture
        np.multiply(q, -self.k_null, out=tau0)
        tau0 += self._k_q_null
        np.multiply(dq, self.d_null, out=self._tmp7)
        tau0 -= self._tmp7
        np.dot(wrench_map, tau0, out=self.wrench_null_world)
        w = self._w
        np.subtract(w_imp, self.wrench_null_world, out=w)
        if wrench_ff_world is not None:
            w += wrench_ff_world
        out = self.tau_no_gravity
        np.dot(w, jac, out=out)
        out += tau0
        if self.config.compensate_coriolis:
            np.dot(dynamics.coriolis_matrix, dq, out=self.tau_coriolis)
            out += self.tau_coriolis
        if self.config.compensate_gravity:
            self.tau_gravity[:] = dynamics.gravity
        return out

    def tau_null(self, jacobian: np.ndarray) -> np.ndarray:
        """Projected posture torque N tau_0 = tau_0 - J^T w_null (7,) [Nm] of the last tick."""
        return self.tau_posture - self.wrench_null_world @ jacobian
