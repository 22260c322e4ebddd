"""``impact-bench --pixels``: the cost of pixel observations per policy step and per camera.

On the scripted expert's trajectory (state mode, ``controller="impact"``), after every policy
step it renders each scene camera as in ``obs_mode="rgb"``, as in ``"rgbd"`` and as in
``"rgb"`` with ``shadows=False`` (``envs/pixels.py``; one renderer per camera and variant, made
and warmed before timing), and it times the whole env step in ``"state+rgb"`` mode with the
default cameras (the expert needs the object pose, so not ``"rgb"``; the images cost the
same). Costs are per policy step, best of ``--repeat`` runs (wall and process CPU time), and
printed as ratios to the state-mode env step and to raw ``mj_step`` over one policy step's
ticks, both measured in the same run.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from impact_control.policy import stack_obs
from impact_envs.envs.options import ObservationOptions
from impact_envs.envs.pixels import PixelObservations, scene_cameras
from impact_envs.policies.experts import make_expert

STATE_STEP = "env step, state (reference)"
VARIANTS = (("rgb", "rgb", True), ("rgbd", "rgb+depth", True), ("rgb", "rgb, no shadows", False))
"""Renders timed per camera: (obs_mode, row label, shadows)."""


def _timed(fn: Callable[[], object], total: dict[str, list[float]], key: str) -> object:
    """Call ``fn``, adding its wall and CPU time [s] to ``total[key]``."""
    wall0, cpu0 = time.perf_counter(), time.process_time()
    result = fn()
    spent = total.setdefault(key, [0.0, 0.0])
    spent[0] += time.perf_counter() - wall0
    spent[1] += time.process_time() - cpu0
    return result


def _renderers(env: gym.Env, size: int) -> dict[str, PixelObservations]:
    """One ``PixelObservations`` per camera and mode, rendered once (GL context made)."""
    base = env.unwrapped
    out = {}
    for camera in scene_cameras(base.sim.model):
        for mode, label, shadows in VARIANTS:
            opts = ObservationOptions(mode, (camera,), size, size, shadows)
            pix = PixelObservations(base.sim.model, base.task, opts, env.observation_space)
            pix.render(base.sim.data)
            out[f"render {camera} {label}"] = pix
    return out


def _state_run(env_id: str, steps: int, seed: int, mass: float, size: int,
               total: dict[str, list[float]]) -> None:
    """Expert episode prefix in state mode; times each step and each camera's renders."""
    env = gym.make(env_id, controller="impact", object_mass=mass)
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    renderers = _renderers(env, size)
    data = env.unwrapped.sim.data
    for _ in range(steps):
        action = expert.act(stack_obs([obs]))[0]
        obs = _timed(lambda a=action: env.step(a), total, STATE_STEP)[0]
        for key, pix in renderers.items():
            _timed(lambda p=pix: p.render(data), total, key)
    for pix in renderers.values():
        pix.close()
    env.close()


def _image_run(env_id: str, steps: int, seed: int, mass: float, size: int,
               total: dict[str, list[float]]) -> str:
    """The same prefix with ``obs_mode="state+rgb"`` and the default cameras; its row name."""
    opts = ObservationOptions("state+rgb", image_width=size, image_height=size)
    key = f"env step, state+rgb ({', '.join(opts.cameras)})"
    env = gym.make(env_id, controller="impact", object_mass=mass, observation=opts)
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    for _ in range(steps):
        action = expert.act(stack_obs([obs]))[0]
        obs = _timed(lambda a=action: env.step(a), total, key)[0]
    env.close()
    return key


def pixel_costs(env_id: str, steps: int, seed: int, mass: float, size: int,
                repeat: int) -> dict[str, np.ndarray]:
    """Row name -> best (wall, CPU) seconds per policy step over ``repeat`` runs."""
    best: dict[str, np.ndarray] = {}
    for _ in range(repeat):
        total: dict[str, list[float]] = {}
        _state_run(env_id, steps, seed, mass, size, total)
        _image_run(env_id, steps, seed, mass, size, total)
        for key, (wall, cpu) in total.items():
            per_step = np.array([wall, cpu]) / steps
            best[key] = np.minimum(best.get(key, per_step), per_step)
    return best


def print_pixel_table(costs: dict[str, np.ndarray], raw_step: np.ndarray, size: int) -> None:
    """Per policy step: ms (wall, CPU) and ratios to the state env step and raw mj_step.

    ``raw_step``: (wall, CPU) seconds of raw ``mj_step`` over one policy step's ticks.
    """
    ref = costs[STATE_STEP]
    print(f"pixel observations, {size}x{size} px, per policy step (one image per camera), "
          "best of the runs:")
    print(f"{'':<40}{'wall ms':>9}{'vs state step':>15}{'vs raw mj_step':>16}"
          f"{'CPU ms':>9}{'vs state step':>15}{'vs raw':>9}")
    for key, (wall, cpu) in costs.items():
        print(f"{key:<40}{1e3 * wall:>9.2f}{wall / ref[0]:>14.2f}x{wall / raw_step[0]:>15.2f}x"
              f"{1e3 * cpu:>9.2f}{cpu / ref[1]:>14.2f}x{cpu / raw_step[1]:>8.2f}x")
