"""``impact-bench --episode``: what one camera policy's episode costs, split into physics,
controller (and the rest of the env step), rendering and the policy (issue 56, item 1).

The scripted expert drives the env (so the arm does what an episode does: reach, grasp,
carry), while a visuomotor Diffusion Policy of the shipped camera recipe's shape
(``hammer/vanilla_rgb``'s config, untrained weights: the same cost) sees every observation
and replans as it would, its actions discarded. Each variant renders the cameras as the env's
``"rgb"`` mode does; ``skip`` renders only the frames the policy reads
(``FrameReadingPolicy``). Physics is raw ``mj_step`` of the same scene over one policy step's
ticks, timed in the same run; "controller and env" is the env step without rendering, less
physics. Wall time per policy step, best of ``--repeat`` runs, scaled to a full episode.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import torch

from impact_control.policy import stack_obs
from impact_envs.envs.options import ObservationOptions
from impact_envs.policies.diffusion.config import DiffusionConfig, ImageEncoderConfig
from impact_envs.policies.diffusion.model import make_network
from impact_envs.policies.diffusion.normalizer import AffineMap, Normalizer
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_envs.policies.experts import make_expert

RECIPE = (Path(__file__).resolve().parents[1]
          / "impact_envs/checkpoints/hammer/vanilla_rgb/config.json")
"""The shipped camera policy's config: the network whose cost is measured."""
PARTS = ("physics (raw mj_step)", "controller and env", "rendering", "policy")


def camera_policy(cameras: tuple[str, ...], obs_dims: dict[str, int], horizon: int,
                  action_steps: int) -> DiffusionPolicy:
    """An untrained visuomotor DP of the recipe's shape on ``cameras``' images."""
    cfg = DiffusionConfig.from_dict(json.loads(RECIPE.read_text()))
    vision = replace(cfg.vision or ImageEncoderConfig(),
                     image_keys=tuple(f"{c}_rgb" for c in cameras))
    cfg = replace(cfg, obs_keys=tuple(obs_dims), horizon=horizon, n_action_steps=action_steps,
                  vision=vision, action_xyz="delta_measured")
    torch.manual_seed(0)
    dim = sum(obs_dims.values())
    net = make_network(cfg, dim)
    identity = [AffineMap(torch.ones(n), torch.zeros(n)) for n in (dim, 10)]
    return DiffusionPolicy(cfg, net, Normalizer(*identity), obs_dims)


def _run(env_id: str, opts: ObservationOptions, skip: bool, steps: int, seed: int,
         mass: float, shape: tuple[int, int], physics_s: float) -> dict[str, float]:
    """Seconds per policy step of each part, for one variant (``physics_s``: raw
    ``mj_step`` per policy step, measured by the caller)."""
    env = gym.make(env_id, controller="impact", object_mass=mass, observation=opts)
    state_keys = ("ee_pos", "ee_rot6d", "gripper_width")
    policy = camera_policy(opts.cameras, {k: env.observation_space[k].shape[0]
                                          for k in state_keys}, *shape)
    expert, pixels = make_expert(env_id), env.unwrapped._pixels
    render, spent = pixels.render, {"rendering": 0.0, "policy": 0.0, "env": 0.0}

    def timed_render(data):  # the env's own renders, timed where they happen
        t0 = time.perf_counter()
        images = render(data)
        spent["rendering"] += time.perf_counter() - t0
        return images

    pixels.render = timed_render
    expert_env = gym.make(env_id, controller="impact", object_mass=mass)  # the expert's view
    obs, _ = env.reset(seed=seed)  # its render makes the GL context: not timed
    state, _ = expert_env.reset(seed=seed)
    expert.reset(1)
    policy.reset(1)
    policy.act(stack_obs([obs]))  # torch's first call (warm-up), then a fresh queue
    policy.reset(1)
    spent.update(rendering=0.0)
    for _ in range(steps):
        t0 = time.perf_counter()
        policy.act(stack_obs([obs]))
        spent["policy"] += time.perf_counter() - t0
        action = expert.act(stack_obs([state]))[0]
        if skip and not policy.frames_read_next()[0]:
            env.unwrapped.skip_next_images()
        t0 = time.perf_counter()
        obs = env.step(action)[0]
        spent["env"] += time.perf_counter() - t0
        state = expert_env.step(action)[0]
    env.close()
    expert_env.close()
    return {"physics (raw mj_step)": physics_s,
            "controller and env": (spent["env"] - spent["rendering"]) / steps - physics_s,
            "rendering": spent["rendering"] / steps, "policy": spent["policy"] / steps}


def episode_costs(env_id: str, cameras: tuple[str, ...], size: int, steps: int, seed: int,
                  mass: float, repeat: int, shape: tuple[int, int],
                  physics_s: float) -> dict[str, dict]:
    """Variant label -> part (``PARTS``) -> best seconds per policy step."""
    best: dict[str, dict] = {}
    for _ in range(repeat):
        for shadows in (True, False):
            for skip in (False, True):
                label = (f"{'shadows' if shadows else 'no shadows'}, "
                         f"{'frames read only' if skip else 'every frame'}")
                opts = ObservationOptions("rgb", cameras, size, size, shadows)
                got = _run(env_id, opts, skip, steps, seed, mass, shape, physics_s)
                was = best.setdefault(label, got)
                best[label] = {k: min(v, was[k]) for k, v in got.items()}
    return best


def print_episode_table(costs: dict[str, dict], episode_steps: int, size: int,
                        cameras: tuple[str, ...]) -> None:
    """Per policy step [ms] and per episode [s], with the ratio to raw ``mj_step``."""
    print(f"one camera-policy episode ({', '.join(cameras)}, {size}x{size} px, "
          f"{episode_steps} policy steps), wall time, best of the runs:")
    print(f"{'':<34}" + "".join(f"{p:>22}" for p in PARTS) + f"{'s/episode':>11}"
          f"{'vs raw mj_step':>16}")
    for label, row in costs.items():
        total = sum(row.values())
        print(f"{label:<34}" + "".join(f"{1e3 * row[p]:>19.2f} ms" for p in PARTS)
              + f"{total * episode_steps:>11.1f}{total / row[PARTS[0]]:>15.1f}x")
