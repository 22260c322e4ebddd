"""A scripted pick-and-lift policy for robosuite's Lift and Stack, in delta-pose actions.

Waypoints for the grip site, from the observation each step: above the object, down to it,
close, lift (Lift: 25 cm; Stack: over the other cube, then down onto it and open). The action
is the waypoint error over the controller's largest step (5 cm, 0.5 rad), clipped to
``[-1, 1]``, plus the TCP's rotation back to its start orientation: the same actions for
robosuite's OSC and for our controllers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

STEP_M, STEP_RAD = 0.05, 0.5
"""The controllers' largest goal change per action (robosuite's OSC_POSE output range)."""

PHASES: dict[str, tuple[tuple[float, float] | None, int]] = {
    "above": ((0.004, 0.01), 60),
    "down": ((0.004, 0.005), 40),
    "close": (None, 15),
    "lift": ((0.01, 0.02), 50),
    "over": ((0.005, 0.015), 60),
    "lower": ((0.005, 0.008), 40),
    "release": (None, 10**9),
}
"""Per phase: the waypoint tolerance (lateral, vertical) [m] and the step budget."""


@dataclass
class PickLift:
    """Phase machine of one episode. ``place_on`` is the observation key of the cube to stack
    on (Stack), or None (Lift: lift and hold)."""

    object_key: str = "cube_pos"
    place_on: str | None = None
    lift_m: float = 0.25

    def reset(self, obs: dict[str, np.ndarray]) -> None:
        self.phase, self.count = "above", 0
        self.quat0 = obs["robot0_eef_quat"].copy()
        self.start = obs[self.object_key].copy()

    def _target(self, obs: dict[str, np.ndarray]) -> tuple[np.ndarray, float]:
        """The waypoint [m] and the gripper command of the current phase."""
        obj = obs[self.object_key]
        if self.phase == "above":
            return obj + [0.0, 0.0, 0.10], -1.0
        if self.phase == "down":
            return obj + [0.0, 0.0, -0.005], -1.0
        if self.phase == "close":
            return obj + [0.0, 0.0, -0.005], 1.0
        if self.phase == "lift" or self.place_on is None:
            return self.start + [0.0, 0.0, self.lift_m], 1.0
        other = obs[self.place_on]
        if self.phase == "over":
            return other + [0.0, 0.0, 0.12], 1.0
        if self.phase == "lower":
            return other + [0.0, 0.0, 0.055], 1.0
        return other + [0.0, 0.0, 0.08], -1.0  # "release"

    def _advance(self, err: np.ndarray) -> None:
        """Next phase when the waypoint is reached (lateral and vertical tolerances [m]) or
        the phase's step budget is spent (a controller that cannot reach a waypoint, e.g.
        sagging under the load, goes on from where it is)."""
        self.count += 1
        xy, z = float(np.linalg.norm(err[:2])), abs(float(err[2]))
        reached, budget = PHASES[self.phase]
        if self.phase == "lift" and self.place_on is None:
            return  # Lift: hold until the episode ends
        if (reached is not None and xy < reached[0] and z < reached[1]) or self.count >= budget:
            order = list(PHASES)
            self.phase, self.count = order[order.index(self.phase) + 1], 0

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The 7-D action (delta position, delta rotation, gripper) for this step."""
        target, grip = self._target(obs)
        err = target - obs["robot0_eef_pos"]
        self._advance(err)
        now = Rotation.from_quat(obs["robot0_eef_quat"])  # robosuite: (x, y, z, w)
        turn = (Rotation.from_quat(self.quat0) * now.inv()).as_rotvec()
        action = np.concatenate([err / STEP_M, turn / STEP_RAD])
        return np.append(np.clip(action, -1.0, 1.0), grip)
