"""The Franka Hand's grasp-force range, shared by ``RobotOptions`` and the simulator.

The quoted datasheet figures are 70 N continuous and 140 N peak grasp force (docs/robot.md;
unconfirmed, ../shared/reference/fr3.md); ``impact-robot pick-place --grasp-force-n`` uses
the same 140 N bound. No kernel reads this module (it is not part of the numba kernel digest).
"""

from __future__ import annotations

import math
from numbers import Real

from impact_envs.errors import InvalidArgumentError

MAX_GRASP_FORCE_N = 140.0
"""Largest grasp force [N] the simulated Franka Hand accepts (its quoted peak force)."""

DEFAULT_GRASP_FORCE_N = 70.0
"""Default grasp force [N] (the Hand's quoted continuous force)."""


def check_grasp_force(value: object) -> None:
    """One-line ``InvalidArgumentError`` unless ``value`` is a real number (not a bool) above
    0 and at most ``MAX_GRASP_FORCE_N``."""
    if isinstance(value, bool) or not isinstance(value, Real) or not (
            math.isfinite(float(value)) and 0.0 < float(value) <= MAX_GRASP_FORCE_N):
        raise InvalidArgumentError(
            f"invalid grasp_force_n {value!r}; valid: a number above 0 and at most "
            f"{MAX_GRASP_FORCE_N:g} N (the Franka Hand's peak grasp force)")
