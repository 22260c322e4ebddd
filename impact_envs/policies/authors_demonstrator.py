"""The paper authors' pick-and-place demonstrator for ``IMPACT/HammerBasket-v1``, rebuilt from
its facts (``../shared/reference/authors_impact.md``, "Their demonstrator and their
baselines' data"): the expert whose demos their Diffusion Policies learned from (issue 55).

What makes it theirs, and unlike ``PickPlaceExpert`` (which ramps *absolute* targets):

- **Targets re-based on the measured pose.** Each step the target is the measured TCP plus
  ``min(1, max_step_m / d)`` of the way to the phase's waypoint (``d`` the distance from the
  measured TCP), plus the height offset. Under impedance a sagging hand is never pulled up by
  position error: only the offset and the step toward the waypoint lift it.
- **The offset** ``m g / K_z`` (``K_z`` 400 N/m) is added on every step of the lift, the hold
  after it, the transit and the descent to the basket, not on the approach and the grasp. Their
  ``m`` is the simulator's mass (privileged, ``offset_mass_kg=None``); a fixed
  ``offset_mass_kg`` is the *mass-blind* offset a Vanilla policy trained at one mass learns.
- **Phases end on a tolerance or a timeout**, and the next starts either way: approach
  0.20 m above the grasp point and descent (0.02 m, 3 s each); grasp (close, hold 0.4 s); lift
  to 0.25 m above the grasp point (0.02 m, 10 s); hold 1 s; transit at that height over the
  basket (0.03 m, 5 s); descent to the basket's origin + 0.10 m (0.03 m, 5 s); open (0.5 s);
  up.

Two choices, both measured (docs/hammer_basket.md, "Their demonstrator as an expert"):

- **The grasp** (``grasp``): ``"theirs"`` keeps the home orientation and closes around the body
  origin; ``"ours"`` closes square to the handle around its centreline
  (``scripted_hammer_basket``). Theirs loses about one grasp in four with our fingers; the
  success filter drops those demos.
- **The rate** (``RATE_MAPPINGS``): they publish at 50 Hz, we act at 30 Hz. ``"lead"`` keeps
  their 0.04 m per step: the target's lead over the measured TCP, i.e. the force the
  impedance pulls with, is theirs, and so are the deltas their 30 Hz recording stores.
  ``"speed"`` scales the step to 0.04 m x 50/30 per step, their nominal speed of the target.

``authors_demonstrator`` is what ``impact-collect --expert authors`` builds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.lie import matrix_from_rot6d, rot6d_from_matrix
from impact_control.rates import POLICY_HZ
from impact_envs.policies.experts import check_expert_obs
from impact_envs.policies.scripted import CLOSED, GRAVITY, OPEN, _yaw_frame

APPROACH, DESCEND, GRASP, LIFT, HOLD, TRANSIT, LOWER, RELEASE, UP = range(9)
"""The demonstrator's phases, in order."""

OFFSET_PHASES = (LIFT, HOLD, TRANSIT, LOWER)
"""Phases whose targets carry the height offset."""

THEIR_PUBLISH_HZ = 50.0
"""Their demonstrator's publishing rate (``step_rate``) [Hz]."""

RATE_MAPPINGS = ("lead", "speed")
"""How their 50 Hz step maps to our 30 Hz policy step (module docstring)."""

GRASPS = ("ours", "theirs")
"""Grasp geometries (module docstring)."""


@dataclass(frozen=True)
class RebasedSpec:
    """Their demonstrator's values (authors_impact.md) [m, s, N/m].

    Attributes:
        max_step_m: The largest step of the target toward the waypoint, per policy step.
        approach_above_m: Approach height above the grasp point.
        lift_above_m: Lift and transit height above the grasp point.
        place_above_basket_m: Release height above the basket's origin.
        tol_near_m: Waypoint tolerance near the object (approach, descent, lift).
        tol_transit_m: Waypoint tolerance in transit and descent to the basket.
        timeouts_s: Per-phase timeouts, in the order of the phases (hold phases: their
            duration).
        stiffness_z_n_per_m: The ``K_z`` of the offset ``m g / K_z``.
    """

    max_step_m: float = 0.04
    approach_above_m: float = 0.20
    lift_above_m: float = 0.25
    place_above_basket_m: float = 0.10
    tol_near_m: float = 0.02
    tol_transit_m: float = 0.03
    timeouts_s: tuple[float, ...] = (3.0, 3.0, 0.4, 10.0, 1.0, 5.0, 5.0, 0.5, 60.0)
    stiffness_z_n_per_m: float = 400.0


def rebased_spec(rate_mapping: str = "lead") -> RebasedSpec:
    """Their values with the step mapped to our policy rate by ``rate_mapping``."""
    check_choice("rate_mapping", rate_mapping, RATE_MAPPINGS)
    if rate_mapping == "lead":
        return RebasedSpec()
    return RebasedSpec(max_step_m=RebasedSpec().max_step_m * THEIR_PUBLISH_HZ / POLICY_HZ)


class RebasedDemonstrator:
    """Batched HammerBasket demonstrator with their re-based targets (module docstring);
    the Policy protocol (``reset``, ``act``)."""

    required_observations = ("ee_pos", "ee_rot6d", "object_pos", "object_rot6d", "goal_pos")

    def __init__(self, offset_mass_kg: float | None = None,
                 spec: RebasedSpec | None = None, grasp: str = "ours") -> None:
        from impact_envs.policies.scripted_hammer_basket import hammer_basket_expert

        check_choice("grasp", grasp, GRASPS)
        self.spec = spec or RebasedSpec()
        self.offset_mass_kg = offset_mass_kg
        self.grasp_name = grasp
        their_grasp = {"grasp_yaw_obj_rad": 0.0, "grasp_y_obj_m": 0.0} if grasp == "theirs" else {}
        self.geometry = hammer_basket_expert(**their_grasp).spec  # grasp point, height, yaw
        self.reset(1, np.zeros(1))

    def reset(self, n_envs: int, object_mass_kg: np.ndarray | None = None) -> None:
        """Start ``n_envs`` episodes; the masses are read only by the privileged offset."""
        self.n = int(n_envs)
        mass = (np.zeros(self.n) if object_mass_kg is None
                else np.asarray(object_mass_kg, dtype=float).reshape(self.n))
        if self.offset_mass_kg is not None:
            mass = np.full(self.n, float(self.offset_mass_kg))
        self.offset_z = mass * GRAVITY / self.spec.stiffness_z_n_per_m
        self.phase = np.zeros(self.n, dtype=int)
        self.steps = np.zeros(self.n, dtype=int)
        self.grasp = np.zeros((self.n, 3))
        self.rot = [np.eye(3)] * self.n
        self.target = [None] * self.n

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Actions (B, 10): TCP target position, rot6d, gripper."""
        check_expert_obs(obs, self.required_observations, self.n, type(self).__name__)
        out = np.zeros((self.n, 10), dtype=np.float32)
        for i in range(self.n):
            out[i] = self._act_one(i, {k: np.asarray(v[i], dtype=float) for k, v in obs.items()})
        return out

    def _start(self, i: int, o: dict[str, np.ndarray]) -> None:
        """Fix the grasp point and yaw from the first observation (the hammer rests)."""
        g = self.geometry
        rot = matrix_from_rot6d(o["object_rot6d"])
        point = o["object_pos"] + rot @ np.asarray(g.grasp_offset_obj)
        self.grasp[i] = (point[0], point[1], g.grasp_z)
        c, s = np.cos(g.grasp_yaw_obj_rad), np.sin(g.grasp_yaw_obj_rad)
        self.rot[i] = _yaw_frame(np.array([c * rot[0, 0] - s * rot[1, 0],
                                           s * rot[0, 0] + c * rot[1, 0], 0.0]))

    def waypoint(self, i: int, goal: np.ndarray) -> np.ndarray:
        """The waypoint of env ``i``'s phase [m, world] (``goal``: the basket's origin)."""
        s, g, phase = self.spec, self.grasp[i], self.phase[i]
        high = g[2] + s.lift_above_m
        if phase == APPROACH:
            return np.array([g[0], g[1], g[2] + s.approach_above_m])
        if phase in (DESCEND, GRASP):
            return g.copy()
        if phase in (LIFT, HOLD):
            return np.array([g[0], g[1], high])
        if phase == TRANSIT:
            return np.array([goal[0], goal[1], high])
        if phase in (LOWER, RELEASE):
            return np.array([goal[0], goal[1], goal[2] + s.place_above_basket_m])
        return np.array([goal[0], goal[1], high])

    def _act_one(self, i: int, o: dict[str, np.ndarray]) -> np.ndarray:
        s, phase = self.spec, self.phase[i]
        if self.target[i] is None:
            self._start(i, o)
        w, p = self.waypoint(i, o["goal_pos"]), o["ee_pos"]
        held = phase in (GRASP, HOLD, RELEASE)
        if held:  # their hold_position: republish the last target (set by the phase before)
            target = self.target[i]
        else:
            d = float(np.linalg.norm(w - p))
            target = p + min(1.0, s.max_step_m / d if d > 0.0 else 1.0) * (w - p)
            if phase in OFFSET_PHASES:
                target = target + np.array([0.0, 0.0, self.offset_z[i]])
        self.target[i] = target
        self.steps[i] += 1
        tol = s.tol_near_m if phase <= LIFT else s.tol_transit_m
        timeout = self.steps[i] >= round(s.timeouts_s[phase] * POLICY_HZ)
        if phase < UP and (timeout or (not held and np.linalg.norm(p - w) < tol)):
            self.phase[i], self.steps[i] = phase + 1, 0
        grip = CLOSED if GRASP <= phase <= LOWER else OPEN
        return np.concatenate([target, rot6d_from_matrix(self.rot[i]), [grip]])


EXPERT_DEFAULTS = {"grasp": "theirs", "rate_mapping": "lead"}
"""What ``impact-collect --expert authors`` uses (chosen by measurement, docs/hammer_basket.md)."""


def authors_demonstrator(compensation: str = "privileged") -> RebasedDemonstrator:
    """Their demonstrator as a scripted expert (``make_expert(..., expert="authors")``):
    ``compensation`` ``"privileged"`` adds their ``m g / K`` offset from the true mass,
    ``"none"`` no offset (an ablation); ``EXPERT_DEFAULTS`` fix the grasp and the rate."""
    if compensation not in ("privileged", "none"):
        raise InvalidArgumentError(
            f"the authors' demonstrator has no compensation {compensation!r}; valid: "
            "privileged (their m g / K offset), none")
    return RebasedDemonstrator(offset_mass_kg=None if compensation == "privileged" else 0.0,
                               spec=rebased_spec(EXPERT_DEFAULTS["rate_mapping"]),
                               grasp=EXPERT_DEFAULTS["grasp"])
