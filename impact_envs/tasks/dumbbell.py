"""Dumbbell pick-and-place task: grasp a hex dumbbell at its bar centre, place it on a pad."""

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

PLATE_APOTHEM_M = 0.0433
"""Half height of the hexagonal plates [m]: the bar centre (= COM) height when lying flat."""
PAD_HALF_M = (0.15, 0.09, 0.005)
"""Half extents of the target pad (x, y, thickness) [m]; its top is at 0.01 m."""
PAD_TOP_M = 2.0 * PAD_HALF_M[2]
REST_HEIGHT_TOL_M = 0.01
"""Allowed deviation of the COM height from lying flat on the pad [m]."""
REST_SPEED_M_S = 0.05
"""The dumbbell counts as resting below this COM speed [m/s]."""


class DumbbellTask(Task):
    """Pick the dumbbell at its bar centre and place it flat on the pad."""

    name = "dumbbell"
    env_id = current_id("Dumbbell")
    env_entry_point = "impact_envs.envs.dumbbell:DumbbellEnv"
    scene_xml = "dumbbell_scene.xml"
    object_bodies = ("dumbbell",)
    params = (TaskParam("object_mass", 2.5, 0.1, 12.0, "kg", is_mass=True),)
    observations = (*OBJECT_POSE, ObsEntry("goal_pos", 3, -2.0, 2.0, "m", "pad centre"))
    privileged_observations = ("object_pos", "object_rot6d", "goal_pos")
    max_episode_steps = 750
    workspace_low = np.array([0.15, -0.45, 0.0])
    workspace_high = np.array([0.70, 0.45, 0.60])

    # COM within ~0.44 m of the base so 10 kg stays inside the FR3 torque limits (docs/robot.md)
    dumbbell_xy_low = np.array([0.34, 0.12])
    dumbbell_xy_high = np.array([0.40, 0.18])
    dumbbell_yaw_max_rad = np.pi / 6
    pad_xy_low = np.array([0.32, -0.20])
    pad_xy_high = np.array([0.38, -0.14])

    def bind(self, sim: FrankaSim) -> None:
        m = sim.model
        self.mass = BodyMass(m, "dumbbell")
        self.body = FreeBody(m, "dumbbell", "dumbbell_free")
        self.dumbbell = self.body.id
        self.pad = m.body("pad").id
        self.plates = np.array([m.geom(f"dumbbell_plate_{s}").id for s in ("px", "nx")])

    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        self.mass.set(sim.model, values["object_mass"])

    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        m, d = sim.model, sim.data
        xy = rng.uniform(self.dumbbell_xy_low, self.dumbbell_xy_high)
        yaw = rng.uniform(-self.dumbbell_yaw_max_rad, self.dumbbell_yaw_max_rad)
        self.body.place(d, xy, PLATE_APOTHEM_M, yaw)
        m.body_pos[self.pad, :2] = rng.uniform(self.pad_xy_low, self.pad_xy_high)
        return HOME_Q + rng.uniform(-0.03, 0.03, size=7)

    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        return {**self.body.observe(sim.data), "goal_pos": sim.model.body_pos[self.pad].copy()}

    def _on_pad(self, sim: FrankaSim) -> tuple[bool, bool]:
        """(both plates above the pad footprint, COM at the lying-flat height on the pad)."""
        d = sim.data
        pad = sim.model.body_pos[self.pad]
        rel = d.geom_xpos[self.plates, :2] - pad[:2]
        footprint = bool(np.all(np.abs(rel) < np.array(PAD_HALF_M[:2])))
        height = abs(d.xipos[self.dumbbell, 2] - (PAD_TOP_M + PLATE_APOTHEM_M)) < REST_HEIGHT_TOL_M
        return footprint, bool(height)

    def is_success(self, sim: FrankaSim) -> bool:
        footprint, height = self._on_pad(sim)
        if not (footprint and height):
            return False
        speed = np.linalg.norm(sim.data.qvel[self.body.dof_adr:self.body.dof_adr + 3])
        return bool(speed < REST_SPEED_M_S and sim.object_finger_contacts("dumbbell") == 0)

    def info(self, sim: FrankaSim) -> dict[str, float | bool]:
        footprint, height = self._on_pad(sim)
        return {"is_grasped": sim.object_finger_contacts("dumbbell") >= 2,
                "on_pad": footprint and height}

    def supported_weight_n(self, values: Mapping[str, float]) -> float:
        """The dumbbell's weight, m g [N]: it rests on the table and on the pad."""
        return 9.81 * values["object_mass"]

    def dense_reward(self, sim: FrankaSim) -> float:
        """``pick_place_reward``: reach the bar centre, grasp, lift, bring the dumbbell to its
        resting height on the pad."""
        d = sim.data
        goal = sim.model.body_pos[self.pad] + np.array([0.0, 0.0, PLATE_APOTHEM_M])
        goal[2] = PAD_TOP_M + PLATE_APOTHEM_M
        return pick_place_reward(sim.tcp_pose()[0], d.xipos[self.dumbbell], goal,
                                 sim.object_finger_contacts("dumbbell") >= 2,
                                 d.xipos[self.dumbbell, 2] - PLATE_APOTHEM_M,
                                 self.is_success(sim))
