"""Scripted calligraphy expert: follow the observed pen-tip reference with the TCP.

The task publishes the pen-tip target of the next policy step as ``goal_pos`` (hover above the
paper between strokes, on the paper while writing). The expert points the hand straight down
at the home yaw, puts the TCP ``tip_offset_m`` above the target tip point, keeps the gripper
closed on the pen and moves its target at a bounded speed (the first move from home is long).
Pressing is not the expert's job: the task adds the normal-force command while the commanded
tip is on the paper (docs/envs.md).

While writing (the reference is on the paper) it corrects the tangential (x, y) tip error
with a PI law on the observed pen tip, as a writer steers the pen against paper drag and
joint friction; the normal direction is never corrected (no force sensing in observations).

There is no load compensation (``calligraphy_expert`` refuses it): raising
the targets by ``m g / K_z`` lifts the commanded tip off the paper, and the task presses only
while the commanded tip is on it (docs/envs.md).
"""

from __future__ import annotations

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_control.lie import rot6d_from_matrix
from impact_control.rates import POLICY_HZ
from impact_envs.policies.experts import check_expert_obs

R_DOWN = np.diag([1.0, -1.0, -1.0])
"""TCP pointing down with its x axis along world +x (the home yaw)."""


class CalligraphyExpert:
    """Batched pen-following expert implementing the Policy protocol.

    Args:
        tip_offset_m: pen tip distance below the TCP along the TCP z axis [m].
        surface_z: height of the writing surface [m]; the reference is "writing" at or below
            ``surface_z + 1 mm``.
        speed_m_s: maximum target speed [m/s] (the reference itself moves slower).
    """

    kp = 1.0
    """Proportional gain of the tangential tip correction [m/m]."""
    ki_per_s = 12.0
    """Integral gain of the tangential tip correction [1/s]."""
    max_correction_m = 0.03
    required_observations = ("ee_pos", "goal_pos", "object_pos")
    """The state entries it reads (``experts.check_expert_obs``: one line when any is absent)."""

    def __init__(self, tip_offset_m: float, surface_z: float, speed_m_s: float = 0.25) -> None:
        self.tip_offset_m = float(tip_offset_m)
        self.surface_z = float(surface_z)
        self.speed_m_s = float(speed_m_s)
        self.reset(1)

    def reset(self, n_envs: int, object_mass_kg: np.ndarray | None = None) -> None:
        """Start ``n_envs`` episodes (``object_mass_kg``, the tool masses, is not used)."""
        self.n = int(n_envs)
        self.target: list[np.ndarray | None] = [None] * self.n
        self.prev_goal = np.full((self.n, 3), np.nan)
        self.integral = np.zeros((self.n, 2))

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Actions (B, 10): TCP target position [m], rot6d (pointing down), gripper closed."""
        check_expert_obs(obs, self.required_observations, self.n, type(self).__name__)
        out = np.zeros((self.n, 10), dtype=np.float32)
        rot6d = rot6d_from_matrix(R_DOWN)
        max_step = self.speed_m_s / POLICY_HZ
        for i in range(self.n):
            goal_tcp = np.asarray(obs["goal_pos"][i], dtype=float) + [0, 0, self.tip_offset_m]
            if self.target[i] is None:
                self.target[i] = np.asarray(obs["ee_pos"][i], dtype=float).copy()
            delta = goal_tcp - self.target[i]
            dist = float(np.linalg.norm(delta))
            if dist > max_step:
                goal_tcp = self.target[i] + delta * max_step / dist
            self.target[i] = goal_tcp
            target = self.target[i].copy()
            target[:2] += self._correction(i, obs["goal_pos"][i], obs["object_pos"][i])
            out[i] = np.concatenate([target, rot6d, [1.0]])
        return out

    def _correction(self, i: int, goal: np.ndarray, tip: np.ndarray) -> np.ndarray:
        """PI correction of the tangential tip error [m, world xy] while writing, else 0."""
        prev, self.prev_goal[i] = self.prev_goal[i].copy(), goal
        on_paper = self.surface_z + 1e-3
        if not (goal[2] <= on_paper and prev[2] <= on_paper):
            self.integral[i] = 0.0
            return np.zeros(2)
        err = prev[:2] - np.asarray(tip[:2], dtype=float)  # reference now vs tip now
        lim = self.max_correction_m
        self.integral[i] = np.clip(self.integral[i] + self.ki_per_s * err / POLICY_HZ, -lim, lim)
        return np.clip(self.kp * err + self.integral[i], -lim, lim)


def calligraphy_expert(compensation: str = "none") -> CalligraphyExpert:
    """The pen-following expert of ``IMPACT/Calligraphy-v1``.

    Raises:
        InvalidArgumentError: ``compensation`` other than ``"none"``: raised targets would lift
            the commanded tip off the paper, and the task presses only while it is on it.
    """
    from impact_envs.tasks.calligraphy import PAPER_TOP_M, PEN_TIP_OFFSET_M

    if compensation != "none":
        raise InvalidArgumentError(
            "IMPACT/Calligraphy-v1 has no load-compensating expert (raised targets lift the "
            "commanded pen tip off the paper, so the task would never press); valid: "
            "compensation='none'")
    return CalligraphyExpert(PEN_TIP_OFFSET_M, PAPER_TOP_M)
