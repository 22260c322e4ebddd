"""A fifth task that lives outside the package, added by this file and its scene only
(tests/reach_scene.xml): bring the TCP to a random target whose height is the swept
parameter. Importing this module registers ``IMPACT-Test/Reach-v0`` and its expert;
docs/adding_a_task.md walks through it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from impact_envs.control.lie import rot6d_from_matrix
from impact_envs.policies.experts import register_expert
from impact_envs.robot.ik import HOME_Q
from impact_envs.robot.sim import FrankaSim
from impact_envs.tasks.base import ObsEntry, Task, TaskParam
from impact_envs.tasks.registry import register_task

TOLERANCE_M = 0.02
"""The TCP counts as at the target within this distance [m]."""


class ReachTask(Task):
    """Bring the TCP to a random target in front of the robot."""

    name = "reach"
    env_id = "IMPACT-Test/Reach-v0"
    scene_xml = str(Path(__file__).with_name("reach_scene.xml"))
    object_bodies = ()
    params = (TaskParam("target_height", 0.3, 0.15, 0.5, "m"),)
    observations = (ObsEntry("goal_pos", 3, -2.0, 2.0, "m", "target position, world frame"),)
    max_episode_steps = 90
    workspace_low = np.array([0.15, -0.45, 0.0])
    workspace_high = np.array([0.70, 0.45, 0.60])

    def bind(self, sim: FrankaSim) -> None:
        self.mocap = int(sim.model.body("target").mocapid[0])

    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        self.height = values["target_height"]

    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        xy = rng.uniform([0.35, -0.15], [0.55, 0.15])
        sim.data.mocap_pos[self.mocap] = [xy[0], xy[1], self.height]
        return HOME_Q + rng.uniform(-0.03, 0.03, size=7)

    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        return {"goal_pos": sim.data.mocap_pos[self.mocap].copy()}

    def is_success(self, sim: FrankaSim) -> bool:
        tcp, _ = sim.tcp_pose()
        return bool(np.linalg.norm(tcp - sim.data.mocap_pos[self.mocap]) < TOLERANCE_M)


class ReachExpert:
    """Moves its TCP target from the start pose toward the goal at 0.3 m/s (pointing down,
    gripper open); the impedance pulls the TCP after it."""

    def reset(self, n_envs: int, object_mass_kg: np.ndarray | None = None) -> None:
        self.n, self.target = n_envs, None

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        if self.target is None:
            self.target = obs["ee_pos"].astype(float)
        delta = obs["goal_pos"] - self.target
        dist = np.maximum(np.linalg.norm(delta, axis=1, keepdims=True), 1e-9)
        self.target = self.target + delta * np.minimum(1.0, 0.01 / dist)
        rot6d = rot6d_from_matrix(np.diag([1.0, -1.0, -1.0]))
        return np.concatenate([self.target, np.tile(rot6d, (self.n, 1)),
                               -np.ones((self.n, 1))], axis=1).astype(np.float32)


register_task(ReachTask)
register_expert("reach", lambda compensation: ReachExpert())
