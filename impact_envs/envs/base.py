"""Gymnasium environment base: a 30 Hz policy over a 1 kHz torque controller on MuJoCo.

Each ``step(action)`` interpolates the TCP target from the previous action to the new one
(linear position, slerp orientation) over 33 or 34 control ticks (exactly 1000 ticks per 30
steps), runs the controller on *noisy* sensor readings every tick, and applies the torques.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from numbers import Integral
from typing import Any, Literal

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from impact_control.config import ControllerConfig
from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError
from impact_control.internal_model import ModelSnapshot
from impact_control.lie import matrix_from_rot6d, matrix_to_quat, rot6d_from_matrix, slerp
from impact_control.presets import Preset
from impact_control.rates import CONTROL_HZ, POLICY_HZ
from impact_envs._gl import make_renderer
from impact_envs.envs.arguments import (
    check_args,
    initial_params,
    load_task,
    pinned_options,
    refuse_unknown_keywords,
)
from impact_envs.envs.carry import ControllerCarry, apply_carry, check_carry, controller_carry
from impact_envs.envs.observation_space import state_space
from impact_envs.envs.options import ObservationOptions, RenderOptions, RobotOptions
from impact_envs.envs.pixels import PixelObservations, check_view
from impact_envs.envs.robot_parts import build_robot
from impact_envs.envs.state import EnvState, capture, restore
from impact_envs.loop import ClosedLoop, TickTargets
from impact_envs.tasks.base import Task, refresh_constants
from impact_envs.torch_threads import limit_torch_threads

ACTION_ENTRIES = ("x", "y", "z", *(f"rot6d[{i}]" for i in range(6)), "gripper")
"""What each of the 10 action entries is (TCP target position, rot6d, gripper command)."""


def check_finite_action(action: np.ndarray) -> None:
    """One-line error naming the entries of a (10,) ``action`` that are NaN or infinite."""
    bad = np.flatnonzero(~np.isfinite(action))
    if bad.size:
        entries = ", ".join(f"action[{i}] ({ACTION_ENTRIES[i]}) = {action[i]}" for i in bad)
        raise InvalidArgumentError(f"action holds non-finite values: {entries}; valid: finite "
                                   "numbers in every entry")


def ticks_for_step(k: int) -> int:
    """Control ticks in policy step ``k``: 33 or 34, summing to exactly 1000 per 30 steps."""
    return (k + 1) * CONTROL_HZ // POLICY_HZ - k * CONTROL_HZ // POLICY_HZ


class ImpactEnv(gym.Env):
    """Shared machinery of the IMPACT environments; each task subclass documents itself."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": POLICY_HZ}

    @classmethod
    def make_task(cls) -> Task:
        """The task this environment runs (a documented subclass overrides this; the generic
        env gets its task from the ``task`` argument)."""
        raise InvalidArgumentError(f"{cls.__name__} needs task='module:TaskClass'")

    def __init__(
        self,
        *,
        task: str | None = None,
        controller: Literal["impact", "impedance"] = "impact",
        object_mass: float | None = None,
        task_params: dict[str, float] | None = None,
        controller_preset: str | ControllerConfig | Preset = "default",
        robot: RobotOptions | Mapping[str, Any] | None = None,
        persist_internal_model: bool = False,
        terminate_on_success: bool = False,
        render_mode: str | None = None,
        render: RenderOptions | Mapping[str, Any] | None = None,
        reward_type: str = "sparse",
        observation: ObservationOptions | Mapping[str, Any] | str | None = None,
        env_version: int | None = None,
        **unknown: object,
    ) -> None:
        refuse_unknown_keywords(type(self), unknown)  # one line naming the valid keywords
        self._init_kwargs = {k: v for k, v in locals().items()
                             if k not in ("self", "__class__", "unknown")}
        """The constructor's arguments (``__deepcopy__`` and pickling rebuild from them)."""
        check_args(controller, reward_type, render_mode, self.metadata["render_modes"])
        self.task = task = self.make_task() if task is None else load_task(task)
        # resolved once, as the env's version pins them (preset name and config together)
        preset, robot, render, obs_opts = pinned_options(task, env_version, controller_preset,
                                                         robot, render, observation)
        self.reward_type, self.render_mode = reward_type, render_mode
        self.controller_mode = controller
        self.terminate_on_success = bool(terminate_on_success)
        self.persist_internal_model = bool(persist_internal_model)
        params = initial_params(task, object_mass, task_params)  # refused before building
        self.sim, self.dynamics, self.realism = build_robot(robot, task.scene_xml,
                                                            task.object_bodies, task.hand)
        self.robot_profile = robot.realism
        """The robot profile's name (``info["robot_profile"]``; ``RobotOptions.realism``)."""
        task.bind(self.sim)
        self._params = params
        self.controller_preset = preset.name
        """Name of the controller preset in use ("default", "paper"; "custom" otherwise)."""
        limit_torch_threads()
        self.controller = ImpactController(self.dynamics, preset.config, mode=controller)
        self.loop = ClosedLoop(self.sim, self.dynamics, self.controller,
                               task.before_tick if task.has_tick_hook else None,
                               command_loss_rate=self.realism.command_loss_rate)
        self._warm: ModelSnapshot | None = None
        self._carry: ControllerCarry | None = None
        self._camera, self._size = render.camera, (int(render.height), int(render.width))
        self._check_render(render)
        self._renderer: mujoco.Renderer | None = None
        self.action_space = spaces.Box(
            low=np.concatenate([task.workspace_low, -np.ones(7)]).astype(np.float32),
            high=np.concatenate([task.workspace_high, np.ones(7)]).astype(np.float32),
            dtype=np.float32,
        )
        self._state_space = state_space(self.dynamics, task)
        self.observation_options = obs_opts
        """What the observation holds (``ObservationOptions``; ``"state"`` mode by default)."""
        self._pixels = (PixelObservations(self.sim.model, task, obs_opts, self._state_space)
                        if obs_opts.uses_images else None)
        """Camera images in the observation (``envs/pixels.py``); None in ``"state"`` mode."""
        self.observation_space = self._state_space if self._pixels is None else self._pixels.space
        self._step_count, self._gripper_cmd, self._success_once = 0, -1.0, False
        self._target_pos, self._target_quat = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])

    def _check_render(self, render: RenderOptions) -> None:
        """The camera must be one of the scene's and the size fit its offscreen buffer."""
        check_view(self.sim.model, "render size", (render.camera,), render.width,
                   render.height)

    # ------------------------------------------------------------------ spaces
    # ------------------------------------------------------------------ params
    @property
    def param_name(self) -> str:
        """Name of the task's sweep parameter (e.g. ``object_mass``)."""
        return self.task.param_name

    def set_param(self, name: str, value: float) -> None:
        """Persistently set a task parameter (used by resets without options)."""
        self._params[name] = self.task.param(name).validate(value)

    def warm_start(self, snapshot: ModelSnapshot | None) -> None:
        """Start every later episode's internal model from ``snapshot`` (``None``: fresh).

        ``snapshot`` as returned by ``controller.internal_model.snapshot()`` (weights and replay
        samples, e.g. after an unscored warm-up episode): each ``reset`` restores a copy, so
        scored episodes stay independent of one another ("warm robot", docs/eval.md).
        """
        self._warm = snapshot

    def controller_carry(self) -> ControllerCarry:
        """A copy of the controller's whole state now (kernel buffers, internal model, replay
        sampler), for ``carry_controller``: take it at the end of an episode."""
        return controller_carry(self)

    def carry_controller(self, carry: ControllerCarry | None) -> None:
        """Start the next episode with the controller state ``carry`` (``None``: fresh).

        The next ``reset`` resets the scene and the arm as usual (new pose, parameters,
        target), resets the controller at the new pose, then overwrites its state with
        ``carry``'s: estimator and observer filters, slow filter, payload model, rate
        limiter's last command, null-space posture, contact guard, internal model with its
        replay and history. Only the target filter starts afresh (the env sets the target per
        episode; ``envs/carry.py`` says why). The carry is used by that one reset, and it
        replaces a ``warm_start`` snapshot for it. As the authors run their benchmark, the
        controller activated once for a bin of episodes ("Carried controller state",
        docs/eval.md).

        Raises:
            InvalidArgumentError: ``carry`` is not a ``ControllerCarry`` of an env made with
                the same arguments (the env is left as it was).
        """
        if carry is not None:
            check_carry(self, carry)
        self._carry = carry

    @property
    def target_pos_world(self) -> np.ndarray:
        """The TCP position target of the last action (or the start pose after reset) [m]."""
        return self._target_pos.copy()

    @property
    def target_quat_world(self) -> np.ndarray:
        """The TCP orientation target of the last action (w, x, y, z)."""
        return self._target_quat.copy()

    # ----------------------------------------------------------------- state
    def get_state(self) -> EnvState:
        """A full snapshot (simulator, arm model, controller, internal model with its replay,
        task, targets, rng) to branch an episode: ``set_state`` restores it in place."""
        return capture(self)

    def set_state(self, state: EnvState) -> None:
        """Restore a ``get_state`` snapshot of this env (or of one made with the same
        arguments); the same actions then reproduce the trajectory bit for bit."""
        restore(self, state)

    def __deepcopy__(self, memo: dict) -> ImpactEnv:
        """A new env with the same arguments, set to this one's state (a plain deep copy would
        lose the views into MuJoCo's data that the loop actuates through)."""
        new = type(self)(**copy.deepcopy(self._init_kwargs, memo))
        new.set_state(self.get_state())
        new.spec = self.spec
        return new

    def __getstate__(self) -> dict[str, Any]:
        """Pickle as constructor arguments + ``get_state()`` (rebuilt by ``__setstate__``)."""
        return {"kwargs": self._init_kwargs, "state": self.get_state(), "spec": self.spec}

    def __setstate__(self, saved: dict[str, Any]) -> None:
        self.__init__(**saved["kwargs"])
        self.set_state(saved["state"])
        self.spec = saved["spec"]

    # ------------------------------------------------------------------- reset
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if options is not None and not isinstance(options, Mapping):
            raise InvalidArgumentError(
                f"invalid reset options {options!r}; valid: None or a dict of task parameters "
                f"({', '.join(p.name for p in self.task.params)})")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, Integral)):
            raise InvalidArgumentError(f"invalid seed {seed!r}; valid: None or an integer >= 0")
        super().reset(seed=seed)
        params = dict(self._params)
        for name, value in (options or {}).items():
            params[name] = self.task.param(name).validate(value)
        sim, rng = self.sim, self.np_random
        self.task.apply_params(sim, params)
        refresh_constants(sim)
        self._episode_params = params
        q0 = self.task.initialize_episode(sim, rng)
        sim.reset_robot(q0, 0.04, rng)
        mujoco.mj_forward(sim.model, sim.data)
        # the env ticks through its closed loop's own compiled kernel, not ``compute``: no
        # entry of ``compute`` is resolved (on a fresh machine, a compile per controller shape)
        self.controller.reset(q0, keep_internal_model=self.persist_internal_model,
                              resolve_tick=False)
        carry, self._carry = self._carry, None
        if carry is not None:
            apply_carry(self, carry)
        elif self._warm is not None:
            self.controller.internal_model.restore(self._warm)
        self.dynamics.update(q0, np.zeros(7))
        self._target_pos = self.dynamics.pos_ee_world.copy()
        self._target_quat = matrix_to_quat(self.dynamics.rot_ee_world)
        self._gripper_cmd = -1.0
        self._step_count = 0
        self._success_once = False
        self._q_meas, self._dq_meas, _ = sim.read_sensors(rng)
        if self._pixels is not None:
            self._pixels.render_next()  # a reset's observation is always rendered
        return self._observation(), self._info(success=False, metrics=None)

    # -------------------------------------------------------------------- step
    def _decode_action(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidArgumentError(f"action must be a (10,) array of numbers: {exc}") from None
        if a.shape != (10,):
            raise InvalidArgumentError(
                f"action must be a (10,) array of numbers, got shape {a.shape}")
        check_finite_action(a)
        pos = np.clip(a[:3], self.task.workspace_low, self.task.workspace_high)
        quat = matrix_to_quat(matrix_from_rot6d(a[3:9]))
        if np.dot(quat, self._target_quat) < 0.0:
            quat = -quat
        return pos, quat, float(np.clip(a[9], -1.0, 1.0))

    def step(self, action: np.ndarray):
        pos1, quat1, gripper = self._decode_action(action)
        pos0, quat0 = self._target_pos, self._target_quat
        wrench_cmd, learn_mask = self.task.control_inputs(self.sim, np.asarray(action))
        metrics = self._run_ticks(pos0, quat0, pos1, quat1, gripper, wrench_cmd, learn_mask)
        self._target_pos, self._target_quat, self._gripper_cmd = pos1, quat1, gripper
        self._step_count += 1
        success = bool(self.task.is_success(self.sim))
        self._success_once |= success
        terminated = bool(success and self.terminate_on_success
                          and self.task.success_ends_episode)
        dense = self.reward_type == "dense"
        reward = self.task.dense_reward(self.sim) if dense else float(success)
        return self._observation(), reward, terminated, False, self._info(success, metrics)

    def _run_ticks(self, pos0, quat0, pos1, quat1, gripper: float,
                   wrench_cmd: np.ndarray | None, learn_mask: np.ndarray | None
                   ) -> dict[str, Any]:
        """Run the 33/34 control ticks of one policy step; return the step's metrics.

        The targets of all ticks are interpolated up front (one vectorized lerp / slerp), and
        the sensor-noise draws of all ticks come from one ``np_random`` call (nothing else
        draws from ``np_random`` during the ticks); energy and peak torque are reduced once per
        step from per-tick rows (``ClosedLoop.run``).
        """
        n = ticks_for_step(self._step_count)
        alphas = np.arange(1, n + 1) / n
        targets = TickTargets(pos0 + alphas[:, None] * (pos1 - pos0),
                              slerp(quat0, quat1, alphas),
                              self.np_random.standard_normal((n, 21)), gripper, wrench_cmd,
                              learn_mask)
        self.sim.drift_offsets(n * self.sim.dt, self.np_random)  # draws only if it drifts
        self.loop.loss_rng = self.np_random  # drawn from only if commands may be lost
        trace = self.loop.run(targets)
        self._q_meas, self._dq_meas = trace.q, trace.dq
        power = np.abs(np.einsum("ij,ij->i", trace.taus, trace.qvels))  # |tau . qdot| [W]
        return {"energy_j": float(np.sum(power * self.sim.dt)),
                "peak_torque_nm": float(np.abs(trace.taus).max()),
                "peak_robot_contact_force_n": trace.peak_robot_contact_n,
                "peak_object_contact_force_n": trace.peak_object_contact_n,
                "contact_robot_trace_n": trace.contact_robot_n,
                "contact_object_trace_n": trace.contact_object_n,
                **({} if trace.ff_into_contact_n is None  # loop.record_press_diagnostics off
                   else {"ff_into_contact_trace_n": trace.ff_into_contact_n,
                         "contact_object_net_trace_n": trace.contact_object_net_n})}

    # ------------------------------------------------------------- observation
    def _observation(self) -> dict[str, np.ndarray]:
        dyn = self.dynamics
        obs = {
            "ee_pos": dyn.pos_ee_world,
            "ee_rot6d": rot6d_from_matrix(dyn.rot_ee_world),
            "gripper_width": np.array([self.sim.gripper_width()]),
            "joint_pos": self._q_meas,
            "joint_vel": self._dq_meas,
        }
        obs.update(self.task.observation(self.sim))
        obs = {k: np.clip(np.asarray(obs[k], dtype=np.float32), space.low, space.high)
               for k, space in self._state_space.spaces.items()}
        return obs if self._pixels is None else self._pixels.observe(obs, self.sim.data)

    def _info(self, success: bool, metrics: dict[str, Any] | None) -> dict[str, Any]:
        s = self.controller.signals
        pos_error = self._target_pos - self.sim.tcp_pose()[0]
        info: dict[str, Any] = {
            "is_success": bool(success),
            "success_once": bool(self._success_once),
            self.param_name: float(self._episode_params[self.param_name]),
            "pose_error_m": float(np.linalg.norm(pos_error)),
            "pos_error_world": pos_error,
            "wrench_ext_world": s.wrench_ext_world.copy(),
            "wrench_slow_world": s.wrench_slow_world.copy(),
            "wrench_pred_world": s.wrench_pred_world.copy(),
            "wrench_ff_world": s.wrench_ff_world.copy(),
            "wrench_imp_world": s.wrench_imp_world.copy(),
            "gate_open": bool(s.gate_open),
            "controller_preset": self.controller_preset,
            "tau_nm": self.sim.tau_applied.copy(),
        }
        m = dict(metrics or {"energy_j": 0.0, "peak_torque_nm": 0.0,
                             "peak_robot_contact_force_n": 0.0,
                             "peak_object_contact_force_n": 0.0,
                             "contact_robot_trace_n": np.zeros(0),
                             "contact_object_trace_n": np.zeros(0)})
        info.update(m)  # contact with the scene, raw: the evaluation judges it (safety.py)
        info["contact_trace_dt_s"] = self.sim.dt
        info["supported_weight_n"] = self.task.supported_weight_n(self._episode_params)
        info["robot_profile"] = robot_profile(self)  # episodes.csv's robot_profile
        if self._pixels is not None:
            info["images_rendered"] = self._pixels.rendered
        info.update({k: float(v) for k, v in self._episode_params.items()})
        info.update(self.task.info(self.sim))
        return info

    # ----------------------------------------------------------------- render
    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            h, w = self._size
            self._renderer = make_renderer(self.sim.model, h, w)
        self._renderer.update_scene(self.sim.data, camera=self._camera)
        return self._renderer.render()

    def outcome_settled(self) -> bool:
        """Whether this episode's outcome can no longer change (the task's
        ``outcome_settled``; never for most tasks): ``impact-eval --end-early`` reads it."""
        return bool(self.task.outcome_settled(self.sim))

    def skip_next_images(self) -> None:
        """The next ``step``'s observation holds zero images instead of rendered ones, and its
        ``info["images_rendered"]`` is False: for a reader that will not look at them
        (``impact_control.policy.FrameReadingPolicy``). No effect in ``"state"`` mode."""
        if self._pixels is not None:
            self._pixels.skip_next()

    def close(self) -> None:
        if self._pixels is not None:
            self._pixels.close()
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


DEFAULT_ROBOT_PROFILE = "ideal"
"""The simulated robot's profile when the env sets none: the idealised arm of today's envs."""


def robot_profile(env: object) -> str:
    """Name of the simulated robot's profile, reported as ``info["robot_profile"]``: the env's
    ``robot_profile`` attribute, ``DEFAULT_ROBOT_PROFILE`` ("ideal") when it has none."""
    return str(getattr(env, "robot_profile", DEFAULT_ROBOT_PROFILE))
