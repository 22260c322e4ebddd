"""Actions for reinforcement learning: a symmetric ``Box(-1, 1)`` over an IMPACT env's own.

The envs act on absolute TCP targets in metres (``Box(10,)``: position in the task's
workspace box, rot6d, gripper), which is what the scripted experts and the Diffusion Policies
emit. RL libraries expect a symmetric, normalized box; ``RLActions`` maps one onto the other:

- ``mode="absolute"`` (10 values in [-1, 1]): the position scaled to the workspace box
  (-1 its low corner, +1 its high corner), rot6d and gripper as they are (every rot6d in the
  box is a valid rotation, ``control.lie.matrix_from_rot6d``).
- ``mode="delta"`` (7 values in [-1, 1]): a change of the TCP *target* per policy step, as
  robosuite's and ManiSkill's delta end-effector controllers: translation up to
  ``max_step_m`` along each world axis, rotation vector up to ``max_turn_rad`` per axis applied
  in the world frame, then the gripper. Relative to the previous target, not the measured
  pose, so a sagging load does not make the target drift.

A physics blow-up (a random policy can throw an object faster than the env's velocity check
allows) ends the episode instead of raising: ``terminated=True``, reward 0 and
``info["failure_reason"] = "unstable: ..."``, with the last valid observation, so a training
run goes on with a reset (the base env raises ``SimulationError``, which impact-eval records).

Shipped checkpoints are unaffected (they act on the unwrapped env).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from impact_control.errors import InvalidArgumentError, SimulationError, check_choice
from impact_control.lie import quat_to_matrix, rot6d_from_matrix, so3_exp

ACTION_MODES = ("absolute", "delta")


def _check_positive_finite(name: str, value: object) -> None:
    """One-line error unless ``value`` is a finite real number > 0 (bools refused)."""
    ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
    if not ok or not (np.isfinite(float(value)) and float(value) > 0.0):
        raise InvalidArgumentError(f"invalid {name} {value!r}; valid: a finite number > 0")


class RLActions(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Box(-1, 1)`` actions for an IMPACT env (see the module docstring).

    Args:
        env: An IMPACT env (``gym.make("IMPACT/Hammer-v2", ...)``), possibly wrapped.
        mode: ``"absolute"`` or ``"delta"``.
        max_step_m: Largest translation of the target per step in ``"delta"`` mode [m].
        max_turn_rad: Largest rotation about each world axis per step in ``"delta"`` [rad].
    """

    def __init__(self, env: gym.Env, mode: str = "absolute", max_step_m: float = 0.02,
                 max_turn_rad: float = 0.1) -> None:
        check_choice("action mode", mode, ACTION_MODES)
        task = getattr(getattr(env, "unwrapped", None), "task", None)
        if not hasattr(task, "workspace_low"):
            raise InvalidArgumentError(
                f"RLActions wraps an IMPACT env (gym.make('IMPACT/Hammer-v1', ...)), got "
                f"{getattr(getattr(env, 'spec', None), 'id', None) or type(env).__name__}")
        for name, value in (("max_step_m", max_step_m), ("max_turn_rad", max_turn_rad)):
            _check_positive_finite(name, value)
        gym.utils.RecordConstructorArgs.__init__(self, mode=mode, max_step_m=max_step_m,
                                                 max_turn_rad=max_turn_rad)
        gym.ActionWrapper.__init__(self, env)
        self.mode, self.max_step_m, self.max_turn_rad = mode, float(max_step_m), float(max_turn_rad)
        self._low, self._high = task.workspace_low, task.workspace_high
        n = 10 if mode == "absolute" else 7
        self.action_space = spaces.Box(-1.0, 1.0, (n,), dtype=np.float32)

    def action(self, action: np.ndarray) -> np.ndarray:
        """The wrapped env's absolute action (10,) for a normalized one.

        Finite values outside [-1, 1] are clipped (as RL libraries expect); a wrong shape,
        a non-numeric or a non-finite action is refused with a one-line error.
        """
        a = np.clip(self._checked(action), -1.0, 1.0)
        out = np.empty(10, dtype=np.float32)
        if self.mode == "absolute":
            out[:3] = self._low + (a[:3] + 1.0) * 0.5 * (self._high - self._low)
            out[3:] = a[3:]
            return out
        base = self.env.unwrapped
        out[:3] = np.clip(base.target_pos_world + self.max_step_m * a[:3], self._low, self._high)
        turn = so3_exp(self.max_turn_rad * a[3:6])
        out[3:9] = rot6d_from_matrix(turn @ quat_to_matrix(base.target_quat_world))
        out[9] = a[6]
        return out

    def _checked(self, action: object) -> np.ndarray:
        """``action`` as float64 of this mode's shape, or ``InvalidArgumentError``."""
        n = self.action_space.shape[0]
        arr = np.asarray(action)
        if arr.dtype.kind not in "fiu" or arr.shape != (n,):
            raise InvalidArgumentError(
                f"invalid {self.mode} action of shape {arr.shape} and dtype {arr.dtype}; valid: "
                f"{n} numbers in [-1, 1] (RLActions mode {self.mode!r})")
        arr = arr.astype(np.float64)
        if not np.all(np.isfinite(arr)):
            raise InvalidArgumentError(
                f"invalid {self.mode} action {arr.tolist()}: not finite; valid: {n} finite "
                "numbers in [-1, 1]")
        return arr

    def reset(self, **kwargs):  # noqa: ANN003, ANN201 - gymnasium's signature
        obs, info = self.env.reset(**kwargs)
        self._last_obs = obs
        return obs, info

    def step(self, action: np.ndarray):  # noqa: ANN201 - gymnasium's signature
        """The wrapped env's step on the mapped action; a blow-up ends the episode."""
        try:
            obs, reward, terminated, truncated, info = self.env.step(self.action(action))
        except SimulationError as exc:
            info = {"is_success": False, "failure_reason": f"unstable: {exc}"}
            return self._last_obs, 0.0, True, False, info
        self._last_obs = obs
        return obs, reward, terminated, truncated, info
