"""The IMPACT envs' state observation space: the robot's entries, then the task's."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from impact_control.dynamics import PinocchioArm
from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.base import ObsEntry, Task

ROBOT_OBSERVATIONS = (
    ObsEntry("ee_pos", 3, -2.0, 2.0, "m", "TCP position, forward kinematics of the encoders"),
    ObsEntry("ee_rot6d", 6, -1.0, 1.0, "", "TCP orientation, rot6d"),
    ObsEntry("gripper_width", 1, 0.0, 0.1, "m", "finger opening"),
    ObsEntry("joint_pos", 7, -np.inf, np.inf, "rad", "encoder reading (bounds: joint limits "
             "+- 0.1 rad)"),
    ObsEntry("joint_vel", 7, -10.0, 10.0, "rad/s", "encoder velocity reading"),
)
"""The robot's observation entries, first in every env (no force sensing in observations)."""


def state_space(dynamics: PinocchioArm, task: Task) -> spaces.Dict:
    """The robot's entries (``ROBOT_OBSERVATIONS``, joint bounds from the model) then the
    task's declared ones, in that order."""
    bounds = {"joint_pos": (dynamics.q_lower - 0.1, dynamics.q_upper + 0.1)}
    entries = (*ROBOT_OBSERVATIONS, *task.observations)
    names = [e.name for e in entries]
    if len(set(names)) != len(names):
        raise InvalidArgumentError(f"{task.name}: observation names repeat: {names}")
    return spaces.Dict({
        e.name: spaces.Box(*(np.broadcast_to(b, (e.size,)).astype(np.float32)
                             for b in bounds.get(e.name, (e.low, e.high))),
                           dtype=np.float32)
        for e in entries
    })
