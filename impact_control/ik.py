"""Damped least-squares inverse kinematics on the controller's Pinocchio model.

Used to place the arm at reset and by tests; the controllers never call it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from impact_control.dynamics import PinocchioArm
from impact_control.errors import InvalidArgumentError

HOME_Q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, np.pi / 4])
"""Home posture [rad]: TCP about 0.46 m in front of the base, 0.40 m high, pointing down."""


def solve_ik(
    arm: PinocchioArm,
    pos_world: np.ndarray,
    rot_world: np.ndarray,
    q_init: np.ndarray | None = None,
    *,
    iters: int = 200,
    tol: float = 1e-6,
    damping: float = 1e-4,
    posture_gain: float = 1e-3,
) -> np.ndarray:
    """Joint positions [rad] placing the TCP at ``pos_world`` with rotation ``rot_world``.

    Raises:
        InvalidArgumentError: if the pose is not reached within ``iters`` iterations.
    """
    model = arm.model
    data = model.createData()
    q = (HOME_Q if q_init is None else q_init).astype(float).copy()
    frame = model.getFrameId("tcp")
    target = pin.SE3(rot_world, pos_world)
    for _ in range(iters):
        pin.framesForwardKinematics(model, data, q)
        current = data.oMf[frame]
        err = np.concatenate(
            [target.translation - current.translation,
             pin.log3(target.rotation @ current.rotation.T)]
        )
        if np.linalg.norm(err) < tol:
            return q
        jac = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)
        jjt = jac @ jac.T + damping * np.eye(6)
        dq = jac.T @ np.linalg.solve(jjt, err)
        null = np.eye(7) - np.linalg.pinv(jac) @ jac
        dq += null @ (posture_gain * (HOME_Q - q))
        q = np.clip(q + dq, arm.q_lower + 1e-3, arm.q_upper - 1e-3)
    raise InvalidArgumentError(f"IK did not converge for target position {np.round(pos_world, 3)}")
