"""Pre-flight check of a loaded diffusion-policy checkpoint against the env it will drive.

``DiffusionPolicy.load`` checks that a checkpoint is internally consistent. This module checks
that it fits an env: finite weights and normalizer, the task it was trained on (the demos'
``env_id``), its observation keys and sizes, its action size, and for a visuomotor checkpoint
the cameras, image size and shadows it was trained with. Any mismatch is one
``CheckpointError`` line, raised before an episode runs.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch

from impact_control.errors import CheckpointError
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_envs.versions import runs_checkpoint_of


def _bare_id(env_id: str) -> str:
    """``"mod:IMPACT/Hammer-v1"`` -> ``"IMPACT/Hammer-v1"``."""
    return env_id.rsplit(":", 1)[-1]


def trained_env_id(policy: DiffusionPolicy) -> str | None:
    """The env id of the checkpoint's demonstrations (None where the metadata has none)."""
    attrs = policy.meta.get("dataset", {}).get("attrs", {})
    env_id = attrs.get("env_id") if isinstance(attrs, dict) else None
    return str(env_id) if env_id else None


def check_policy_env(policy: DiffusionPolicy, env_id: str, env: gym.Env, where: str) -> None:
    """Raise ``CheckpointError`` unless ``policy`` (loaded from ``where``) fits ``env``."""
    tensors = [*policy.net.state_dict().values(), *policy.normalizer.state_dict().values()]
    if not all(torch.isfinite(t).all() for t in tensors if t.is_floating_point()):
        raise CheckpointError(f"checkpoint {where} holds non-finite weights (NaN/inf)")
    trained = trained_env_id(policy)
    if trained is not None and not runs_checkpoint_of(_bare_id(env_id), _bare_id(trained)):
        raise CheckpointError(
            f"checkpoint {where} was trained on {trained}, which {_bare_id(env_id)} does not "
            "run (impact_envs/versions.py: checkpoints_from)")
    spaces = getattr(env.observation_space, "spaces", {})
    for key, dim in policy.obs_dims.items():
        if key not in spaces:
            raise CheckpointError(
                f"checkpoint {where} needs observation {key!r}; the env has {sorted(spaces)}")
        size = int(np.prod(spaces[key].shape))
        if size != dim:
            raise CheckpointError(
                f"checkpoint {where} expects {key!r} of size {dim}, the env gives {size}")
    _check_cameras(policy, env, where)
    action_dim = int(np.prod(env.action_space.shape))
    checkpoint_dim = int(policy.meta.get("action_dim", action_dim))
    if checkpoint_dim != action_dim:
        raise CheckpointError(
            f"checkpoint {where} outputs {checkpoint_dim} action values, the env takes "
            f"{action_dim}")


CAMERA_FIELDS = ("cameras", "image_width", "image_height", "shadows")
"""What a visuomotor checkpoint's images depend on (the store's ``observation`` attribute)."""


def _check_cameras(policy: DiffusionPolicy, env: gym.Env, where: str) -> None:
    """A visuomotor checkpoint runs only on the camera setup of its demos."""
    if policy.cfg.vision is None:
        return
    attrs = policy.meta.get("dataset", {}).get("attrs", {})
    trained = attrs.get("observation") if isinstance(attrs, dict) else None
    options = getattr(env.unwrapped, "observation_options", None)
    if options is not None and not options.uses_images:
        raise CheckpointError(
            f"checkpoint {where} needs camera images {list(policy.cfg.vision.image_keys)}; "
            "the env observes the state only: make it with ObservationOptions(obs_mode='rgb', "
            "...) as the checkpoint's demos were recorded")
    if not isinstance(trained, dict) or options is None:
        return  # a checkpoint or env that does not say: the keys and sizes were checked
    for name in CAMERA_FIELDS:
        have, want = getattr(options, name), trained.get(name)
        if name == "cameras":
            have = list(have)
        if want is not None and have != want:
            raise CheckpointError(
                f"checkpoint {where} was trained with {name}={want!r}, the env renders "
                f"{name}={have!r}; make the env with those ObservationOptions")
