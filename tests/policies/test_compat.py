"""Checkpoint pre-flight against the env: every shipped checkpoint fits its own env, and a
checkpoint of another task, with NaN weights or other observation sizes is refused."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import gymnasium as gym
import pytest
from safetensors.torch import load_file, save_file

import impact_envs
from impact_control.errors import CheckpointError
from impact_envs.envs.options import ObservationOptions
from impact_envs.policies.diffusion.compat import check_policy_env
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_envs.versions import current_id, parse
from impact_eval.methods import env_short_name

ROOT = Path(impact_envs.__file__).parent / "checkpoints"
SHIPPED = sorted(p.parent for p in ROOT.glob("*/*/model.safetensors")
                 if not (p.parent / "policy_preprocessor.json").exists())
"""Our diffusion-policy checkpoints; LeRobot's (``hammer/lerobot_dp``, its processors' files
beside the model) load through ``impact_lerobot.policy``: tests/eval/test_eval_methods.py."""


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_shipped_checkpoints_fit_their_env(path: Path) -> None:
    """Each shipped checkpoint fits its env made as its demos were recorded (a visuomotor one
    with the store's cameras); a visuomotor checkpoint on a state env is one line."""
    policy = DiffusionPolicy.load(path)
    trained_on = policy.meta["dataset"]["attrs"]["env_id"]  # the env its demos came from
    assert env_short_name(trained_on) == path.parent.name  # the folder impact-eval looks in
    env_id = current_id(parse(trained_on)[0])  # its env's current version runs it
    recorded = policy.meta["dataset"]["attrs"].get("observation")
    kwargs = {}
    if recorded is not None:
        kwargs["observation"] = ObservationOptions(**{**recorded,
                                                      "cameras": tuple(recorded["cameras"])})
        with pytest.raises(CheckpointError, match="needs camera images"):
            check_policy_env(policy, env_id, gym.make(env_id), str(path))
    check_policy_env(policy, env_id, gym.make(env_id, **kwargs), str(path))


def test_checkpoint_of_another_task_is_refused() -> None:
    policy = DiffusionPolicy.load(ROOT / "calligraphy" / "vanilla")
    with pytest.raises(CheckpointError, match="trained on IMPACT/Calligraphy-v0, which "
                       "IMPACT/Hammer-v1 does not run"):
        check_policy_env(policy, "IMPACT/Hammer-v1", gym.make("IMPACT/Hammer-v1"), "x")


def test_nan_weights_are_refused(tmp_path: Path) -> None:
    copy = tmp_path / "ckpt"
    shutil.copytree(ROOT / "hammer" / "vanilla", copy)
    tensors = load_file(str(copy / "model.safetensors"))
    first = next(iter(tensors))
    tensors[first] = tensors[first] * float("nan")
    save_file(tensors, str(copy / "model.safetensors"))
    with pytest.raises(CheckpointError, match="non-finite weights"):
        check_policy_env(DiffusionPolicy.load(copy), "IMPACT/Hammer-v1",
                         gym.make("IMPACT/Hammer-v1"), str(copy))


def test_other_action_size_is_refused(tmp_path: Path) -> None:
    copy = tmp_path / "ckpt"
    shutil.copytree(ROOT / "hammer" / "vanilla", copy)
    meta = json.loads((copy / "meta.json").read_text())
    meta["action_dim"] = 7
    (copy / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(CheckpointError, match="outputs 7 action values, the env takes 10"):
        check_policy_env(DiffusionPolicy.load(copy), "IMPACT/Hammer-v1",
                         gym.make("IMPACT/Hammer-v1"), str(copy))
