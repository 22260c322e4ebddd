"""HammerBasket: the paper authors' released simulation benchmark, rebuilt from its facts
(../shared/reference/authors_impact.md; docs/hammer_basket.md gives each value's source).

Their protocol, as far as a task owns it: the spawn ranges (hammer body origin x 0.25–0.40 m,
y −0.40 to −0.20 m, no yaw, 5 mm above its resting height; a free 2.2 kg basket x 0.30–0.40 m,
y 0.10–0.30 m), their home posture, 60 s episodes (1800 steps at 30 Hz) and their success
test: at the end of the episode the hammer's body origin lies within ±0.1875 m of the basket
centre in x and y (no height, release or contact check). The scene (work table 0.23 m above
the robot base, hammer, basket, contacts) is ``assets/hammer_basket_scene.xml``; the hand is
their 200 N one (``robot/hand.HANDS["authors_sim"]``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

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

TABLE_TOP_M = 0.23
"""Work-table top above the robot base [m] (theirs: 0.53 m table, 0.30 m pedestal)."""
HAMMER_DROP_Z_M = TABLE_TOP_M + 0.03 + 0.005
"""Spawn height of the hammer's body origin [m]: their rule, table + 0.03 m + 5 mm clearance."""
BASKET_Z_M = TABLE_TOP_M + 0.005
"""Height of the basket's origin [m]: its 10 mm floor resting on the table."""
SUCCESS_HALF_M = 0.1875
"""Their success box: half width in x and y around the basket centre [m] (the inner walls)."""
GRASP_OFFSET_FROM_COM_M = (-0.0439, -0.0082, -0.0015)
"""The body origin (their grasp point) relative to the centre of mass, hammer frame [m]
(the scene's ``<inertial pos>``, negated)."""
HANDLE_YAW_RAD = -0.1204
"""The handle's yaw in the hammer frame [rad] (-6.9 deg: their mesh's handle centreline runs
from y = 0.034 m at its end to 0.011 m at the head; the scene's handle box)."""
HANDLE_Y_AT_ORIGIN_M = 0.015
"""Where the handle's centreline crosses the body origin's x, hammer frame y [m] (their mesh:
at x = 0 the handle spans y 0.004-0.025 m; the scene's handle box: 0.0015-0.0285 m)."""
SETTLED_SPEED_M_S = 0.01
"""A hammer moving slower than this [m/s] (its body origin) and turning slower than
``SETTLED_SPIN_RAD_S`` is at rest (``outcome_settled``)."""
SETTLED_SPIN_RAD_S = 0.1
FELL_BELOW_M = TABLE_TOP_M - 0.10
"""A hammer origin below this height [m] has left the table: nothing brings it back."""
HOME_Q = np.array([0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4])
"""Their home posture [rad] (the scene keyframe), without noise, as their reset does."""


class HammerBasketTask(Task):
    """Pick the hammer up anywhere and leave it over the basket by the end of the episode."""

    name = "hammer_basket"
    env_id = current_id("HammerBasket")
    env_entry_point = "impact_envs.envs.hammer_basket:HammerBasketEnv"
    scene_xml = "hammer_basket_scene.xml"
    object_bodies = ("hammer",)
    params = (TaskParam("object_mass", 0.1, 0.05, 12.0, "kg", is_mass=True),)
    observations = (*OBJECT_POSE,
                    ObsEntry("object_origin_pos", 3, -2.0, 2.0, "m",
                             "hammer body origin (their grasp point), world frame"),
                    ObsEntry("goal_pos", 3, -2.0, 2.0, "m", "basket centre, world frame"))
    privileged_observations = ("object_pos", "object_rot6d", "object_origin_pos", "goal_pos")
    max_episode_steps = 1800
    workspace_low = np.array([0.10, -0.55, TABLE_TOP_M - 0.01])
    workspace_high = np.array([0.80, 0.55, 0.85])
    success_ends_episode = False
    hand = "authors_sim"

    hammer_xy_low = np.array([0.25, -0.40])
    hammer_xy_high = np.array([0.40, -0.20])
    basket_xy_low = np.array([0.30, 0.10])
    basket_xy_high = np.array([0.40, 0.30])

    def bind(self, sim: FrankaSim) -> None:
        m = sim.model
        self.mass = BodyMass(m, "hammer")
        self.body = FreeBody(m, "hammer", "hammer_free")
        self.hammer = self.body.id
        self.basket_body = FreeBody(m, "basket", "basket_free")
        self.basket = self.basket_body.id

    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        self.mass.set(sim.model, values["object_mass"])

    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        d = sim.data
        self.body.place(d, rng.uniform(self.hammer_xy_low, self.hammer_xy_high),
                        HAMMER_DROP_Z_M, 0.0)
        self.basket_body.place(d, rng.uniform(self.basket_xy_low, self.basket_xy_high),
                               BASKET_Z_M, 0.0)
        return HOME_Q.copy()

    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        d = sim.data
        return {**self.body.observe(d), "object_origin_pos": d.xpos[self.hammer].copy(),
                "goal_pos": d.xpos[self.basket].copy()}

    def is_success(self, sim: FrankaSim) -> bool:
        """Their test: body origin within ±0.1875 m of the basket centre in x and y."""
        rel = sim.data.xpos[self.hammer, :2] - sim.data.xpos[self.basket, :2]
        return bool(np.all(np.abs(rel) <= SUCCESS_HALF_M))

    def info(self, sim: FrankaSim) -> dict[str, float | bool]:
        return {"is_grasped": sim.object_finger_contacts("hammer") >= 2}

    def outcome_settled(self, sim: FrankaSim) -> bool:
        """Their test holds with the hammer let go (no finger touches it) and at rest, or the
        hammer has left the table. Whether a policy ever picks a placed hammer up again is
        not a property of the scene: ``--end-early`` was checked against full-length episodes
        (docs/eval.md, "Ending an episode early")."""
        d = sim.data
        if d.xpos[self.hammer, 2] < FELL_BELOW_M:
            return True
        if not self.is_success(sim) or sim.object_finger_contacts("hammer") > 0:
            return False
        vel = d.qvel[self.body.dof_adr:self.body.dof_adr + 6]
        return bool(np.linalg.norm(vel[:3]) < SETTLED_SPEED_M_S
                    and np.linalg.norm(vel[3:]) < SETTLED_SPIN_RAD_S)

    def supported_weight_n(self, values: Mapping[str, float]) -> float:
        """The hammer's weight, m g [N]: it rests on the table and in the basket."""
        return 9.81 * values["object_mass"]

    def dense_reward(self, sim: FrankaSim) -> float:
        """``pick_place_reward``: reach the hammer's body origin, grasp, lift, carry it over
        the basket (goal: 5 cm above the basket centre)."""
        d = sim.data
        goal = d.xpos[self.basket] + np.array([0.0, 0.0, 0.05])
        lift = d.xipos[self.hammer, 2] - (TABLE_TOP_M + 0.03)
        return pick_place_reward(sim.tcp_pose()[0], d.xpos[self.hammer], goal,
                                 sim.object_finger_contacts("hammer") >= 2, lift,
                                 self.is_success(sim))
