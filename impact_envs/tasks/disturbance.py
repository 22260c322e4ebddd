"""Disturbance task: carry a trough to a goal in the air and hold it under external forces.

After the trough is lifted, an external force acts on it while it is held (MuJoCo
``xfrc_applied`` at its centre of mass, every control tick) following a per-episode profile
drawn from the episode rng: constant, step, or slowly varying. A few seconds after the lift a
load is added (the body mass jumps by ``added_mass``, written directly without
``mj_setConst``, which would reset the state). The robot must bring the trough to the goal and
hold it there.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

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

KINDS = ("constant", "step", "slow")
"""Disturbance profile kinds."""
REST_Z_M = 0.03
"""Height of the trough's centre (= COM = grasp point) when it rests on the table [m]."""
LIFT_DZ_M = 0.04
"""The trough counts as lifted (disturbance clock starts) this far above rest [m]."""
GOAL_TOL_M = 0.03
"""The trough is "at the goal" when its COM is this close to the goal point [m]."""
HOLD_S = 2.0
"""Success: at the goal and grasped continuously for this long once the load has been added
and the disturbance has reached its final value [s]."""
SAMPLE_TICKS = 10
"""Hold status is sampled every 10 control ticks (100 Hz)."""


@dataclass(frozen=True)
class DisturbanceProfile:
    """External force on the trough as a function of the time since lift ``tau`` [s].

    Attributes:
        kind: "constant" (on from the lift), "step" (on from ``step_delay_s``) or "slow"
            (a smooth ramp ``magnitude_n (1 − cos(π tau / ramp_s)) / 2`` up to the magnitude
            at ``ramp_s``, constant afterwards).
        magnitude_n: peak force [N].
        direction: unit vector in the world frame.
        step_delay_s: onset of the step after the lift [s].
        ramp_s: duration of the slow ramp [s].
    """

    kind: str
    magnitude_n: float
    direction: tuple[float, float, float]
    step_delay_s: float
    ramp_s: float

    @classmethod
    def sample(cls, rng: np.random.Generator, magnitude_n: float) -> DisturbanceProfile:
        """Draw kind, direction (azimuth uniform, elevation ±30°), step onset and ramp time."""
        kind = KINDS[int(rng.integers(len(KINDS)))]
        azimuth = rng.uniform(-np.pi, np.pi)
        elevation = rng.uniform(-np.pi / 6, np.pi / 6)
        direction = (np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                     np.sin(elevation))
        return cls(kind, float(magnitude_n), tuple(float(x) for x in direction),
                   float(rng.uniform(1.0, 2.5)), float(rng.uniform(3.0, 5.0)))

    def scale(self, tau_s: float) -> float:
        """Force magnitude at ``tau_s`` seconds after the lift [N] (0 before the lift)."""
        if tau_s < 0.0:
            return 0.0
        if self.kind == "constant":
            return self.magnitude_n
        if self.kind == "step":
            return self.magnitude_n if tau_s >= self.step_delay_s else 0.0
        if tau_s >= self.ramp_s:
            return self.magnitude_n
        return 0.5 * self.magnitude_n * (1.0 - np.cos(np.pi * tau_s / self.ramp_s))

    def settled_s(self) -> float:
        """Time after the lift from which the force stays at its final value [s]."""
        return {"constant": 0.0, "step": self.step_delay_s, "slow": self.ramp_s}[self.kind]

    def force(self, tau_s: float) -> np.ndarray:
        """Force vector [N, world] at ``tau_s`` seconds after the lift."""
        return self.scale(tau_s) * np.asarray(self.direction)


class DisturbanceTask(Task):
    """Pick the trough, carry it to the goal point and hold it under disturbances."""

    has_tick_hook = True
    env_id = current_id("Disturbance")
    env_entry_point = "impact_envs.envs.disturbance:DisturbanceEnv"
    observations = (*OBJECT_POSE, ObsEntry("goal_pos", 3, -2.0, 2.0, "m", "hold goal"))
    privileged_observations = ("object_pos", "object_rot6d", "goal_pos")

    name = "disturbance"
    scene_xml = "disturbance_scene.xml"
    object_bodies = ("trough",)
    params = (TaskParam("disturbance_n", 2.0, 0.0, 40.0, "N"),
              TaskParam("object_mass", 0.3, 0.05, 5.0, "kg", is_mass=True),
              TaskParam("added_mass", 0.3, 0.0, 5.0, "kg"))
    max_episode_steps = 540
    workspace_low = np.array([0.15, -0.45, 0.0])
    workspace_high = np.array([0.70, 0.45, 0.60])

    trough_xy_low = np.array([0.36, 0.10])
    trough_xy_high = np.array([0.42, 0.18])
    trough_yaw_max_rad = np.pi / 6
    goal_low = np.array([0.36, -0.12, 0.20])
    goal_high = np.array([0.44, 0.00, 0.28])
    load_delay_s = (3.0, 4.0)
    """Range of the load change after the lift [s]."""

    def bind(self, sim: FrankaSim) -> None:
        m = sim.model
        self.mass = BodyMass(m, "trough")
        self.free = FreeBody(m, "trough", "trough_free")
        self.body = self.free.id
        self.goal_body = m.body("goal_marker").id
        self.sand = m.geom("trough_sand").id
        self.values = {p.name: p.default for p in self.params}
        self._new_episode_state(DisturbanceProfile("constant", 0.0, (1.0, 0.0, 0.0), 1.0, 4.0),
                                3.0)

    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        self.values = dict(values)
        self.mass.set(sim.model, values["object_mass"])
        sim.model.geom_rgba[self.sand, 3] = 0.0

    # ------------------------------------------------------------------ episode
    def _new_episode_state(self, profile: DisturbanceProfile, load_delay_s: float) -> None:
        self.profile = profile
        self.load_delay = load_delay_s
        self.t_lift: float | None = None
        self.t_load: float | None = None
        self.streak_start: float | None = None
        self.applied = np.zeros(3)
        self._tick = 0
        self._goal_error = np.inf
        self._held = False

    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        m, d = sim.model, sim.data
        xy = rng.uniform(self.trough_xy_low, self.trough_xy_high)
        yaw = rng.uniform(-self.trough_yaw_max_rad, self.trough_yaw_max_rad)
        self.free.place(d, xy, REST_Z_M, yaw)
        m.body_pos[self.goal_body] = rng.uniform(self.goal_low, self.goal_high)
        profile = DisturbanceProfile.sample(rng, self.values["disturbance_n"])
        self._new_episode_state(profile, float(rng.uniform(*self.load_delay_s)))
        return HOME_Q + rng.uniform(-0.03, 0.03, size=7)

    # ------------------------------------------------------------------ hooks
    def before_tick(self, sim: FrankaSim, time_s: float) -> None:
        """Start the clock at lift; apply the disturbance; add the load; track the hold."""
        d = sim.data
        if self.t_lift is None:
            if d.xipos[self.body, 2] < REST_Z_M + LIFT_DZ_M:
                return
            self.t_lift = time_s
            self._update_hold(sim, time_s)
        tau = time_s - self.t_lift
        # Only a held trough is pushed: the same force on a dropped (or never grasped) 0.3 kg
        # trough threw it off the table faster than the env's velocity check allows.
        self.applied = self.profile.force(tau) if self._held else np.zeros(3)
        d.xfrc_applied[self.body, :3] = self.applied
        if self.t_load is None and tau >= self.load_delay:
            self._add_load(sim)
            self.t_load = time_s
        self._tick += 1
        if self._tick % SAMPLE_TICKS == 0:
            self._update_hold(sim, time_s)

    def _add_load(self, sim: FrankaSim) -> None:
        """Mass jump, COM fixed, inertia scaled; no mj_setConst (it would reset the state)."""
        self.mass.set(sim.model, self.values["object_mass"] + self.values["added_mass"])
        sim.model.geom_rgba[self.sand, 3] = 1.0

    def _update_hold(self, sim: FrankaSim, time_s: float) -> None:
        goal = sim.model.body_pos[self.goal_body]
        self._goal_error = float(np.linalg.norm(sim.data.xipos[self.body] - goal))
        self._held = sim.object_finger_contacts("trough") >= 2
        if self._held and self._goal_error < GOAL_TOL_M:
            if self.streak_start is None:
                self.streak_start = time_s
        else:
            self.streak_start = None

    def hold_s(self, time_s: float) -> float:
        """How long the trough has been at the goal and held, counted from the moment the load
        was added and the disturbance reached its final value [s]."""
        if self.t_lift is None or self.t_load is None or self.streak_start is None:
            return 0.0
        events_done = self.t_lift + max(self.load_delay, self.profile.settled_s())
        return max(0.0, time_s - max(self.streak_start, events_done))

    # ------------------------------------------------------------- observation
    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        return {**self.free.observe(sim.data),
                "goal_pos": sim.model.body_pos[self.goal_body].copy()}

    def is_success(self, sim: FrankaSim) -> bool:
        return self.hold_s(float(sim.data.time)) >= HOLD_S

    def dense_reward(self, sim: FrankaSim) -> float:
        """``pick_place_reward`` toward the hold goal, plus up to 0.25 for the time held
        (of the ``HOLD_S`` needed), capped below the success value 1."""
        d, t = sim.data, float(sim.data.time)
        base = pick_place_reward(sim.tcp_pose()[0], d.xipos[self.body],
                                 sim.model.body_pos[self.goal_body],
                                 sim.object_finger_contacts("trough") >= 2,
                                 d.xipos[self.body, 2] - REST_Z_M, self.is_success(sim))
        if base >= 1.0:
            return 1.0
        return min(0.99, base + 0.25 * min(1.0, self.hold_s(t) / HOLD_S))

    def info(self, sim: FrankaSim) -> dict[str, float | bool | str]:
        t = float(sim.data.time)
        return {
            "disturbance_kind": self.profile.kind,
            "disturbance_force_world": self.applied.copy(),
            "lifted": self.t_lift is not None,
            "load_added": self.t_load is not None,
            "goal_error_m": self._goal_error,
            "is_grasped": self._held,
            "hold_s": self.hold_s(t),
        }

    def supported_weight_n(self, values: Mapping[str, float]) -> float:
        """The object's own weight, m g [N], without ``added_mass`` (as since issue 26: the
        load is added while the object is held aloft, and a set-down that also presses the
        added weight into the table counts as contact force)."""
        return 9.81 * values["object_mass"]
