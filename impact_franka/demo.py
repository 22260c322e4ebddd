"""A policy for a first run of ``PolicyTarget`` on a robot: a slow horizontal circle.

``CirclePolicy`` follows the project's ``Policy`` protocol (``reset``, ``act`` on a batch) and
needs nothing but the robot's own observations: it moves the TCP target on a circle of
``radius_m`` around where the TCP was at its first step, once per ``period_s``, keeping that
orientation, gripper open. examples/robot_policy.py runs it.
"""

from __future__ import annotations

import math

import numpy as np

from impact_control.rates import POLICY_HZ


class CirclePolicy:
    """Targets on a horizontal circle around the first observed TCP position."""

    def __init__(self, radius_m: float = 0.03, period_s: float = 4.0) -> None:
        self.radius_m, self.period_s = float(radius_m), float(period_s)
        self.reset(1)

    def reset(self, n_envs: int) -> None:
        self._center: np.ndarray | None = None
        self._rot6d: np.ndarray | None = None
        self._steps = 0

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        if self._center is None:  # start on the circle's edge nearest the TCP: no jump
            self._center = obs["ee_pos"][0].astype(float) - [self.radius_m, 0.0, 0.0]
            self._rot6d = obs["ee_rot6d"][0].astype(float)
        self._steps += 1
        phase = 2.0 * math.pi * self._steps / (self.period_s * POLICY_HZ)
        pos = self._center + self.radius_m * np.array([math.cos(phase), math.sin(phase), 0.0])
        return np.concatenate([pos, self._rot6d, [-1.0]])[None].astype(np.float32)
