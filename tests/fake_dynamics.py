"""Analytic stand-in for ``ArmDynamics`` used by the controller-core unit tests.

Constant random model: M symmetric positive definite, C skew-symmetric (so M_dot = C + C^T = 0
holds exactly for the constant M), constant g and J, viscous friction b dq, and a forward
kinematics that is exact to first order: p = p0 + J_v (q - q_ref), R = Exp(J_w (q - q_ref)) R0.
"""

from __future__ import annotations

import numpy as np

from impact_envs.control.lie import so3_exp


class ConstantArmDynamics:
    """Fake 7-DoF model with fixed random arrays (see module docstring)."""

    def __init__(self, seed: int = 0, friction_nms_per_rad: float = 0.2) -> None:
        """Draw the fixed arrays from ``seed``; ``friction_nms_per_rad`` is the viscous b."""
        rng = np.random.default_rng(seed)
        n = 7
        self.n = n
        jac = rng.normal(size=(6, n))
        jac[:3] *= 0.3  # ~0.3 m lever arms
        jac[:3, 4:] *= 0.3  # wrist joints ~0.1 m from the TCP (FR3 wrist limit is 12 Nm)
        self.jacobian = jac
        a = rng.normal(size=(n, n))
        self.mass_matrix = a @ a.T / n + 0.3 * np.eye(n)
        s = rng.normal(size=(n, n))
        self.coriolis_matrix = 0.05 * (s - s.T)
        self.gravity = 5.0 * rng.normal(size=n)
        self.friction_nms_per_rad = friction_nms_per_rad
        self.q_ref = np.zeros(n)
        self.pos_ref = np.array([0.5, 0.0, 0.4])
        self.rot_ref = np.diag([1.0, -1.0, -1.0])
        self.pos_ee_world = self.pos_ref.copy()
        self.rot_ee_world = self.rot_ref.copy()
        self.n_updates = 0

    def update(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Recompute the TCP pose (M, C, g, J are constant)."""
        dqr = np.asarray(q, dtype=float) - self.q_ref
        self.pos_ee_world = self.pos_ref + self.jacobian[:3] @ dqr
        self.rot_ee_world = so3_exp(self.jacobian[3:] @ dqr) @ self.rot_ref
        self.n_updates += 1

    def joint_friction(self, dq: np.ndarray) -> np.ndarray:
        """Viscous friction torque b dq [Nm]."""
        return self.friction_nms_per_rad * np.asarray(dq, dtype=float)
