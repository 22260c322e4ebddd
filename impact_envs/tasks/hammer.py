"""Hammer pick-and-place task: grasp a hammer near its centre of mass, place it in a basket."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from impact_control.ik import HOME_Q
from impact_envs.robot.sim import FrankaSim
from impact_envs.tasks.base import (
    OBJECT_POSE,
    BodyMass,
    FreeBody,
    ObsEntry,
    Task,
    TaskParam,
    pick_place_reward,
)
from impact_envs.versions import current_id

HANDLE_HALF_HEIGHT_M = 0.0125
"""Half thickness of the square handle [m]; the hammer lies flat at this COM height."""
BASKET_INNER_HALF_M = (0.19, 0.09)
"""Inner half extents of the basket floor (x, y) [m]."""
BASKET_WALL_TOP_M = 0.06
PAD_CLEARANCE_M = 0.004
"""Grasp slightly above the handle centre so the finger pads (half height 14 mm around the
TCP) clear the table instead of pressing into it."""


class HammerTask(Task):
    """Pick the hammer at its centre of mass and place it inside the basket."""

    name = "hammer"
    env_id = current_id("Hammer")
    env_entry_point = "impact_envs.envs.hammer:HammerEnv"
    scene_xml = "hammer_scene.xml"
    object_bodies = ("hammer",)
    params = (TaskParam("object_mass", 0.2, 0.05, 12.0, "kg", is_mass=True),)
    observations = (*OBJECT_POSE, ObsEntry("goal_pos", 3, -2.0, 2.0, "m", "basket centre"))
    privileged_observations = ("object_pos", "object_rot6d", "goal_pos")
    max_episode_steps = 750
    workspace_low = np.array([0.15, -0.45, 0.0])
    workspace_high = np.array([0.70, 0.45, 0.60])

    hammer_xy_low = np.array([0.36, 0.14])
    hammer_xy_high = np.array([0.44, 0.22])
    hammer_yaw_max_rad = np.pi / 6
    basket_xy_low = np.array([0.33, -0.27])
    basket_xy_high = np.array([0.38, -0.21])

    def bind(self, sim: FrankaSim) -> None:
        m = sim.model
        self.mass = BodyMass(m, "hammer")
        self.body = FreeBody(m, "hammer", "hammer_free")
        self.hammer = self.body.id
        self.basket = m.body("basket").id
        self.com_offset = m.body_ipos[self.hammer].copy()

    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        self.mass.set(sim.model, values["object_mass"])

    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        m, d = sim.model, sim.data
        com_xy = rng.uniform(self.hammer_xy_low, self.hammer_xy_high)
        yaw = rng.uniform(-self.hammer_yaw_max_rad, self.hammer_yaw_max_rad)
        c, s = np.cos(yaw), np.sin(yaw)
        origin_xy = com_xy - np.array([c, s]) * self.com_offset[0]
        self.body.place(d, origin_xy, HANDLE_HALF_HEIGHT_M, yaw)
        m.body_pos[self.basket, :2] = rng.uniform(self.basket_xy_low, self.basket_xy_high)
        return HOME_Q + rng.uniform(-0.03, 0.03, size=7)

    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        return {**self.body.observe(sim.data), "goal_pos": sim.model.body_pos[self.basket].copy()}

    def is_success(self, sim: FrankaSim) -> bool:
        d = sim.data
        rel = d.xipos[self.hammer] - sim.model.body_pos[self.basket]
        inside = (abs(rel[0]) < BASKET_INNER_HALF_M[0] and abs(rel[1]) < BASKET_INNER_HALF_M[1]
                  and rel[2] < BASKET_WALL_TOP_M)
        return bool(inside and sim.object_finger_contacts("hammer") == 0)

    def info(self, sim: FrankaSim) -> dict[str, float | bool]:
        return {"is_grasped": sim.object_finger_contacts("hammer") >= 2}

    def supported_weight_n(self, values: Mapping[str, float]) -> float:
        """The hammer's weight, m g [N]: it rests on the table and in the basket."""
        return 9.81 * values["object_mass"]

    def dense_reward(self, sim: FrankaSim) -> float:
        """``pick_place_reward``: reach the hammer's COM, grasp, lift, carry it over the basket
        (goal: the basket centre, 5 cm above its floor)."""
        d = sim.data
        goal = sim.model.body_pos[self.basket] + np.array([0.0, 0.0, 0.05])
        return pick_place_reward(sim.tcp_pose()[0], d.xipos[self.hammer], goal,
                                 sim.object_finger_contacts("hammer") >= 2,
                                 d.xipos[self.hammer, 2] - HANDLE_HALF_HEIGHT_M,
                                 self.is_success(sim))
