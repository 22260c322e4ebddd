"""The ``impact_lerobot`` plugin inside LeRobot 0.4.4, run by the LeRobot virtualenv's Python
(``tests/learn/lerobot_venv.sh``), not by the project's::

    LEROBOT_PYTHON tests/lerobot_plugin/lerobot_plugin_check.py env OUT.json [ARG ...]
    LEROBOT_PYTHON tests/lerobot_plugin/lerobot_plugin_check.py policy DIR

``env``: LeRobot's own plugin loader (``load_plugin``) and command-line parser (draccus, as
``lerobot-eval`` parses ``--env.*``) build the config from ``--env.type=impact`` and the ARGs,
LeRobot's ``make_env`` makes the vector env, which is reset (seed 7) and stepped with seeded
random actions until its episode ends; each observation goes through LeRobot's
``preprocess_observation``. OUT.json records what LeRobot saw.

``policy``: a tiny LeRobot ``DiffusionPolicy`` with random weights for the ``impact`` env's
default features, normalized with the env's observation and action bounds, saved to DIR with
its processors (what ``lerobot-eval --policy.path=DIR`` loads). For wiring checks only.
"""

from __future__ import annotations

import json
import sys
from dataclasses import make_dataclass

import numpy as np
import torch

from impact_learn.lerobot_compat import define_missing_torchvision_ops


def parse_env(args: list[str]):  # noqa: ANN201 - LeRobot's EnvConfig, imported lazily
    """``--env.ARG`` parsed by LeRobot as ``lerobot-eval`` does, after its plugin loader."""
    import draccus
    from lerobot.configs.parser import load_plugin
    from lerobot.envs.configs import EnvConfig

    load_plugin("impact_lerobot")
    holder = make_dataclass("Holder", [("env", EnvConfig)])  # a real type: draccus reads it
    return draccus.parse(holder, args=["--env.type=impact", *args]).env


def shapes(batch: dict) -> dict[str, list[int]]:
    return {k: list(v.shape) for k, v in batch.items() if hasattr(v, "shape")}


def check_env(out: str, args: list[str]) -> None:
    """Parse, make, reset and step the env through LeRobot; write what it saw to ``out``."""
    from lerobot.envs.factory import make_env
    from lerobot.envs.utils import env_to_policy_features, preprocess_observation

    from impact_lerobot.settings import mass_param

    cfg = parse_env(args)
    vec = make_env(cfg, n_envs=1)[cfg.type][0]
    vec.action_space.seed(0)
    obs, info = vec.reset(seed=[7])
    policy_features = env_to_policy_features(cfg)
    record = {"config_class": type(cfg).__name__, "type": cfg.type, "gym_id": cfg.gym_id,
              "settings": repr(cfg.settings), "features_map": cfg.features_map,
              "policy_features": {k: list(f.shape) for k, f in policy_features.items()},
              "max_episode_steps": int(vec.call("_max_episode_steps")[0]),
              "reset_mass": float(info[mass_param(cfg.settings.task_class).name][0]),
              "steps": [], "lerobot_obs": [shapes(preprocess_observation(obs))]}
    for _ in range(record["max_episode_steps"]):
        obs, _, terminated, truncated, info = vec.step(vec.action_space.sample())
        record["lerobot_obs"].append(shapes(preprocess_observation(obs)))
        final = info.get("final_info", {})
        record["steps"].append({"terminated": bool(terminated[0]), "truncated": bool(truncated[0]),
                                "is_success": bool(info["is_success"][0]),
                                "final_is_success": (bool(final["is_success"][0])
                                                     if "is_success" in final else None)})
        if terminated[0] or truncated[0]:
            break
    vec.close()
    with open(out, "w") as f:
        json.dump(record, f, indent=1)


def save_policy(folder: str) -> None:
    """A tiny random-weight DiffusionPolicy for the default ``impact`` env, with processors."""
    import gymnasium as gym
    from lerobot.configs.types import FeatureType
    from lerobot.envs.utils import env_to_policy_features
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
    from lerobot.policies.factory import make_pre_post_processors

    cfg = parse_env([])
    features = env_to_policy_features(cfg)
    outputs = {k: f for k, f in features.items() if f.type is FeatureType.ACTION}
    inputs = {k: f for k, f in features.items() if k not in outputs}
    policy_cfg = DiffusionConfig(input_features=inputs, output_features=outputs, device="cpu",
                                 n_obs_steps=2, horizon=16, n_action_steps=8,
                                 down_dims=(32, 64), noise_scheduler_type="DDIM",
                                 num_inference_steps=2)
    env = gym.make(cfg.gym_id, **cfg.gym_kwargs)
    stats = {name: _bounds(env, key) for key, name in cfg.features_map.items()}
    env.close()
    torch.manual_seed(0)
    policy = DiffusionPolicy(policy_cfg)
    pre, post = make_pre_post_processors(policy_cfg, dataset_stats=stats)
    for part in (policy, pre, post):
        part.save_pretrained(folder)
    print(f"saved a random DiffusionPolicy ({sum(p.numel() for p in policy.parameters())} "
          f"parameters) to {folder}")


def _bounds(env, key: str) -> dict[str, np.ndarray]:  # noqa: ANN001 - a gym env
    space = env.action_space if key == "action" else env.observation_space[key]
    low, high = space.low.astype(np.float32), space.high.astype(np.float32)
    return {"min": low, "max": high, "mean": (low + high) / 2, "std": (high - low) / 2}


if __name__ == "__main__":
    define_missing_torchvision_ops()
    if sys.argv[1] == "env":
        check_env(sys.argv[2], sys.argv[3:])
    else:
        save_policy(sys.argv[2])
