"""Scripted experts: the paper's motion-planning demonstrator as a batched, closed-loop policy.

The pick-and-place expert plans straight-line TCP waypoints (approach, descend, grasp, lift,
carry, lower, release, retreat) from the observed object and goal poses and moves the target
toward the current waypoint at a bounded speed. A phase ends when its condition is observed
(e.g. the object has actually risen) or after a timeout, so under plain impedance a heavy
object that sags simply runs into the timeout — exactly what a fixed demonstrator would do.

``compensation`` chooses how the expert meets a load's sag under plain impedance:

- ``"none"``: it commands the nominal waypoints (the sag is the controller's business).
- ``"closed_loop"``: as a teleoperator does, with no knowledge of the mass: while it holds
  the object and its nominal target is vertically still, it raises its command above the
  nominal waypoint in proportion to the TCP height error it observes (``lift_gain``) plus the
  integral of that error (``lift_gain_per_s``), moving the offset no faster than its own
  target speed; the offset is dropped at release. Like a teleoperator it also varies its carry
  height from episode to episode (``carry_jitter_m``).
  Used for the Augmented-DP demonstrations (docs/diffusion_policy.md).
- ``"privileged"``: an ablation only. It knows the mass and adds ``m g / K_z`` from the start
  of the lift, so in its demos every mass moves alike and the state does not tell how far to
  overshoot (the former Augmented demonstrator, docs/results.md §1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.lie import matrix_from_rot6d, rot6d_from_matrix
from impact_control.rates import POLICY_HZ
from impact_envs.policies.experts import check_expert_obs

GRAVITY = 9.81
OPEN, CLOSED = -1.0, 1.0
COMPENSATIONS = ("none", "closed_loop", "privileged")
"""Valid ``compensation`` modes of the pick-and-place expert (module docstring)."""

# phases
APPROACH, DESCEND, GRASP, LIFT, CARRY, LOWER, RELEASE, RETREAT = range(8)


@dataclass(frozen=True)
class PickPlaceSpec:
    """Geometry and timing of a pick-and-place task (all heights are TCP z in the world [m]).

    Attributes:
        grasp_offset_obj: grasp point in the object frame relative to ``object_pos`` [m].
        grasp_z: TCP height at grasp.
        hover_z: TCP height above the grasp point before descending.
        carry_z: TCP height while carrying.
        place_z: TCP height at release.
        place_offset_goal: where the grasp point goes relative to ``goal_pos``, expressed along
            the object's own x axis as it is carried [m].
        speed_m_s: target speed along straight lines [m/s].
        reach_tol_m: distance at which a waypoint counts as reached [m].
        lift_margin_m: the object counts as lifted when its height rose by ``carry_z -
            grasp_z - lift_margin_m``.
        stiffness_z_n_per_m: impedance stiffness used for the privileged load compensation.
        lift_gain: proportional gain of the closed-loop compensation: height offset per metre
            of observed TCP height error [-].
        lift_gain_per_s: integral gain of the closed-loop compensation: the integral part grows
            by this times the TCP height error per second [1/s].
        max_offset_m: bound of the closed-loop height offset, ``[0, max_offset_m]`` [m].
        carry_jitter_m: with closed-loop compensation, each episode carries at ``carry_z + u *
            carry_jitter_m``, u in [0, 1) a fixed function of the episode's first observation
            (so of the env seed): a teleoperator does not lift to the same height every time,
            and the demos then show carries from a range of heights [m].
        timeouts_steps: per-phase timeouts at 30 Hz.
        grasp_yaw_obj_rad: the TCP's yaw at the grasp about world z, relative to the object's
            own x axis [rad] (0: the fingers close across the object's x axis).
        carry_dwell_steps: with > 0, the carry ends only after the target has rested this many
            steps at the carry waypoint above the goal (the carry timeout grows by as much):
            the object is held still aloft, e.g. to watch the internal model adapt
            (``impact-protocol --hold-s``). 0: the carry ends once the TCP reaches it.
    """

    grasp_offset_obj: tuple[float, float, float]
    grasp_z: float
    hover_z: float
    carry_z: float
    place_z: float
    place_offset_goal: float = 0.0
    speed_m_s: float = 0.25
    reach_tol_m: float = 0.015
    lift_margin_m: float = 0.04
    stiffness_z_n_per_m: float = 400.0
    lift_gain: float = 1.0
    lift_gain_per_s: float = 2.0
    max_offset_m: float = 0.3
    carry_jitter_m: float = 0.15
    timeouts_steps: tuple[int, ...] = (90, 60, 18, 450, 150, 120, 15, 10_000)
    carry_dwell_steps: int = 0
    grasp_yaw_obj_rad: float = 0.0

    def timeout_steps(self, phase: int) -> int:
        """Timeout of ``phase`` [policy steps] (the carry's includes the dwell)."""
        return self.timeouts_steps[phase] + (self.carry_dwell_steps if phase == CARRY else 0)


def _unit_from_obs(o: dict[str, np.ndarray]) -> float:
    """A number in [0, 1) that is a fixed function of the object's and goal's first positions
    (randomized by the env seed), spread evenly over [0, 1) across episodes."""
    x = 1e4 * (o["object_pos"][0] + 2.0 * o["object_pos"][1] + 3.0 * o["goal_pos"][1])
    return float(x - np.floor(x))


def _yaw_frame(direction: np.ndarray) -> np.ndarray:
    """TCP rotation pointing down whose x axis is the horizontal ``direction`` (sign chosen
    to stay near the home yaw, world +x)."""
    d = np.array([direction[0], direction[1], 0.0])
    norm = np.linalg.norm(d)
    d = np.array([1.0, 0.0, 0.0]) if norm < 1e-6 else d / norm
    if d[0] < 0.0:
        d = -d
    z = np.array([0.0, 0.0, -1.0])
    return np.column_stack([d, np.cross(z, d), z])


def expert_masses(compensation: str, n_envs: int,
                  object_mass_kg: np.ndarray | None) -> np.ndarray:
    """Per-env object masses [kg] for an expert's reset (required by privileged compensation)."""
    if compensation == "privileged" and object_mass_kg is None:
        raise InvalidArgumentError("compensation='privileged' needs object_mass_kg in reset()")
    if object_mass_kg is None:
        return np.zeros(int(n_envs))
    return np.asarray(object_mass_kg, dtype=float).reshape(int(n_envs))


class PickPlaceExpert:
    """Batched closed-loop pick-and-place expert implementing the Policy protocol."""

    required_observations = ("ee_pos", "ee_rot6d", "gripper_width", "object_pos",
                             "object_rot6d", "goal_pos")
    """The state entries it reads (``experts.check_expert_obs``: one line when any is absent)."""

    def __init__(self, spec: PickPlaceSpec, compensation: str = "none") -> None:
        check_choice("compensation", compensation, COMPENSATIONS)
        self.spec = spec
        self.compensation = compensation
        self.reset(1, np.zeros(1))

    def reset(self, n_envs: int, object_mass_kg: np.ndarray | None = None) -> None:
        """Start ``n_envs`` new episodes; masses are needed only by privileged compensation."""
        self.n = int(n_envs)
        self.mass = expert_masses(self.compensation, self.n, object_mass_kg)
        self.phase = np.zeros(self.n, dtype=int)
        self.phase_steps = np.zeros(self.n, dtype=int)
        self.target = [None] * self.n
        self.rot = [None] * self.n
        self.grip = np.full(self.n, OPEN)
        self.obj_z0 = np.zeros(self.n)
        self.dwell = np.zeros(self.n, dtype=int)
        self.offset_z = np.zeros(self.n)
        self.integral_z = np.zeros(self.n)
        self.carry_z = np.full(self.n, self.spec.carry_z)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Actions (B, 10): TCP target position, rot6d, gripper."""
        check_expert_obs(obs, self.required_observations, self.n, type(self).__name__)
        out = np.zeros((self.n, 10), dtype=np.float32)
        for i in range(self.n):
            o = {k: np.asarray(v[i], dtype=float) for k, v in obs.items()}
            out[i] = self._act_one(i, o)
        return out

    # ------------------------------------------------------------------ helpers
    def _grasp_point(self, o: dict[str, np.ndarray]) -> np.ndarray:
        rot = matrix_from_rot6d(o["object_rot6d"])
        return o["object_pos"] + rot @ np.asarray(self.spec.grasp_offset_obj)

    def _waypoint(self, i: int, o: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        s, phase = self.spec, self.phase[i]
        obj_rot = matrix_from_rot6d(o["object_rot6d"])
        if phase <= GRASP:
            g = self._grasp_point(o) if phase < GRASP else self.target[i]
            z = {APPROACH: s.hover_z, DESCEND: s.grasp_z, GRASP: s.grasp_z}[phase]
            c, si = np.cos(s.grasp_yaw_obj_rad), np.sin(s.grasp_yaw_obj_rad)
            axis = np.array([c * obj_rot[0, 0] - si * obj_rot[1, 0],
                             si * obj_rot[0, 0] + c * obj_rot[1, 0], 0.0])
            return np.array([g[0], g[1], z]), _yaw_frame(axis)
        goal_rot = _yaw_frame(np.array([1.0, 0.0, 0.0]))
        sign = 1.0 if obj_rot[0, 0] >= 0.0 else -1.0
        goal_xy = o["goal_pos"][:2] + np.array([sign * s.place_offset_goal, 0.0])
        if phase == LIFT:
            return np.array([self.target[i][0], self.target[i][1], self.carry_z[i]]), self.rot[i]
        if phase == CARRY:
            return np.array([goal_xy[0], goal_xy[1], self.carry_z[i]]), goal_rot
        if phase in (LOWER, RELEASE):
            return np.array([goal_xy[0], goal_xy[1], s.place_z]), goal_rot
        return np.array([self.target[i][0], self.target[i][1], s.carry_z]), goal_rot

    def _phase_done(self, i: int, o: dict[str, np.ndarray], waypoint: np.ndarray) -> bool:
        s, phase = self.spec, self.phase[i]
        reached = (np.linalg.norm(self.target[i] - waypoint) < 1e-6
                   and np.linalg.norm(o["ee_pos"] - waypoint) < s.reach_tol_m)
        if phase == GRASP:
            return self.phase_steps[i] >= 12 and float(o["gripper_width"][0]) < 0.07
        if phase == LIFT:
            risen = o["object_pos"][2] - self.obj_z0[i]
            return risen > self.carry_z[i] - s.grasp_z - s.lift_margin_m
        if phase == RELEASE:
            return self.phase_steps[i] >= s.timeouts_steps[RELEASE]
        if phase == CARRY and s.carry_dwell_steps > 0:
            at_waypoint = np.linalg.norm(self.target[i] - waypoint) < 1e-6
            self.dwell[i] = self.dwell[i] + 1 if at_waypoint else 0
            return bool(self.dwell[i] >= s.carry_dwell_steps)
        return bool(reached)

    def _act_one(self, i: int, o: dict[str, np.ndarray]) -> np.ndarray:
        s = self.spec
        if self.target[i] is None:
            self.target[i] = o["ee_pos"].copy()
            self.rot[i] = matrix_from_rot6d(o["ee_rot6d"])
            if self.compensation == "closed_loop":
                self.carry_z[i] = s.carry_z + s.carry_jitter_m * _unit_from_obs(o)
        waypoint, rot = self._waypoint(i, o)
        step = s.speed_m_s / POLICY_HZ
        delta = waypoint - self.target[i]
        dist = np.linalg.norm(delta)
        z_before = self.target[i][2]
        self.target[i] = waypoint.copy() if dist <= step else self.target[i] + delta * step / dist
        self.rot[i] = rot
        if self.compensation == "closed_loop":
            self._integrate_offset(i, o, vertically_still=self.target[i][2] == z_before)
        self.phase_steps[i] += 1
        timeout = self.phase_steps[i] >= s.timeout_steps(self.phase[i])
        if self.phase[i] < RETREAT and (self._phase_done(i, o, waypoint) or timeout):
            self._advance(i, o)
        return self._emit(i)

    def _integrate_offset(self, i: int, o: dict[str, np.ndarray], vertically_still: bool) -> None:
        """Closed-loop compensation: integrate the TCP height error while holding the object
        with a vertically still target (so a moving target's tracking lag does not wind it
        up); the offset is kept through the lowering and dropped at release."""
        s = self.spec
        if not LIFT <= self.phase[i] <= LOWER:
            self.offset_z[i] = self.integral_z[i] = 0.0
            return
        if not vertically_still:
            return
        error = self.target[i][2] - float(o["ee_pos"][2])
        self.integral_z[i] = float(np.clip(
            self.integral_z[i] + s.lift_gain_per_s * error / POLICY_HZ, 0.0, s.max_offset_m))
        wanted = float(np.clip(s.lift_gain * error + self.integral_z[i], 0.0, s.max_offset_m))
        step = s.speed_m_s / POLICY_HZ
        self.offset_z[i] += float(np.clip(wanted - self.offset_z[i], -step, step))

    def _advance(self, i: int, o: dict[str, np.ndarray]) -> None:
        self.phase[i] += 1
        self.phase_steps[i] = 0
        if self.phase[i] == GRASP:
            self.grip[i] = CLOSED
        elif self.phase[i] == LIFT:
            self.obj_z0[i] = o["object_pos"][2]
        elif self.phase[i] == RELEASE:
            self.grip[i] = OPEN

    def _emit(self, i: int) -> np.ndarray:
        target = self.target[i].copy()
        holding = LIFT <= self.phase[i] <= LOWER
        if self.compensation == "privileged" and holding:
            target[2] += self.mass[i] * GRAVITY / self.spec.stiffness_z_n_per_m
        elif self.compensation == "closed_loop" and holding:
            target[2] += self.offset_z[i]
        return np.concatenate([target, rot6d_from_matrix(self.rot[i]), [self.grip[i]]])


def hammer_expert(compensation: str = "none") -> PickPlaceExpert:
    """The pick-and-place expert of ``IMPACT/Hammer-v1`` (grasp at the handle's COM)."""
    from impact_envs.tasks.hammer import HANDLE_HALF_HEIGHT_M, PAD_CLEARANCE_M

    spec = PickPlaceSpec(
        grasp_offset_obj=(0.0, 0.0, 0.0),
        grasp_z=HANDLE_HALF_HEIGHT_M + PAD_CLEARANCE_M,
        hover_z=0.12,
        carry_z=0.18,
        place_z=0.045,
        place_offset_goal=0.07,
    )
    return PickPlaceExpert(spec, compensation=compensation)


def dumbbell_expert(compensation: str = "none") -> PickPlaceExpert:
    """The pick-and-place expert of ``IMPACT/Dumbbell-v1`` (grasp at the bar centre)."""
    from impact_envs.tasks.dumbbell import PAD_TOP_M, PLATE_APOTHEM_M

    spec = PickPlaceSpec(
        grasp_offset_obj=(0.0, 0.0, 0.0),
        grasp_z=PLATE_APOTHEM_M,
        hover_z=0.14,
        carry_z=0.20,
        place_z=PAD_TOP_M + PLATE_APOTHEM_M + 0.004,
        place_offset_goal=0.0,
        lift_margin_m=0.07,
    )
    return PickPlaceExpert(spec, compensation=compensation)
