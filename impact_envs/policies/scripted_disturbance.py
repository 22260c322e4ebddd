"""Carry-and-hold expert: the pick-and-place expert without the place.

Approach, descend, grasp and lift exactly as ``PickPlaceExpert``; then move the object's
centre of mass to the observed ``goal_pos`` and hold it there for the rest of the episode (the
carry phase never ends). The grasp is only as accurate as the descent (the pick-and-place
expert closes the gripper within 15 mm of the grasp point), so the TCP target is the goal
plus the observed grasp offset ``ee_pos − object_pos`` (both sag together, so the offset does
not contain the load-induced tracking error). Compensating disturbances and added loads is the
controller's job.
"""

from __future__ import annotations

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.scripted import CARRY, PickPlaceExpert, PickPlaceSpec

NEVER = 10**9
"""Timeout that never expires [policy steps]."""
R_HOLD = np.diag([1.0, -1.0, -1.0])
"""TCP pointing down at the home yaw while carrying and holding (as the pick-and-place carry)."""


class CarryHoldExpert(PickPlaceExpert):
    """Batched pick-carry-hold expert implementing the Policy protocol."""

    def _waypoint(self, i: int, o: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        if self.phase[i] >= CARRY:
            offset = np.asarray(o["ee_pos"], dtype=float) - np.asarray(o["object_pos"], dtype=float)
            return np.asarray(o["goal_pos"], dtype=float) + offset, R_HOLD
        return super()._waypoint(i, o)

    def _phase_done(self, i: int, o: dict[str, np.ndarray], waypoint: np.ndarray) -> bool:
        if self.phase[i] >= CARRY:
            return False
        return super()._phase_done(i, o, waypoint)


def make_carry_hold_expert(grasp_z: float) -> CarryHoldExpert:
    """Expert for an object grasped at its centre of mass at TCP height ``grasp_z`` [m]."""
    spec = PickPlaceSpec(
        grasp_offset_obj=(0.0, 0.0, 0.0),
        grasp_z=grasp_z,
        hover_z=0.12,
        carry_z=0.16,
        place_z=grasp_z,
        timeouts_steps=(90, 60, 18, 450, NEVER, NEVER, NEVER, NEVER),
    )
    return CarryHoldExpert(spec)


def disturbance_expert(compensation: str = "none") -> CarryHoldExpert:
    """Pick, carry to the goal and hold: the expert of ``IMPACT/Disturbance-v1``.

    Raises:
        InvalidArgumentError: ``compensation`` other than ``"none"``: the pick-and-place
            experts compensate an object's weight, but this env's swept parameter is a
            disturbance force with a random direction and time profile.
    """
    from impact_envs.tasks.disturbance import REST_Z_M

    if compensation != "none":
        raise InvalidArgumentError(
            "IMPACT/Disturbance-v1 has no load-compensating expert (its parameter is a "
            "random, time-varying disturbance force, not a mass); valid: "
            "compensation='none'")
    return make_carry_hold_expert(REST_Z_M)
