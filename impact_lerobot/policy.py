"""A LeRobot policy checkpoint behind our policy protocol (``impact-eval --method lerobot_dp``).

``load_lerobot_policy(folder, env_id)`` loads what ``lerobot-train`` saves as
``pretrained_model`` (``config.json``, ``model.safetensors`` and the processors' JSON and
safetensors: no pickle) and wraps it in ``LeRobotPolicy``: ``reset(n_envs)`` and ``act(obs)``
on a batch of our observation dicts. Each batch is laid out as the plugin lays out one env's
observation for ``lerobot-eval`` (``features.ObservationPlan``, the export's order), so the
policy sees, value for value, what it sees under ``lerobot-eval``. The only difference is the
diffusion noise: ``seed_envs`` gives each env its own generator, so an episode's actions do
not depend on the batch it ran in (``lerobot-eval`` draws from torch's global generator).

LeRobot is imported on load only; without it the load is a one-line ``CheckpointError``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from impact_control.errors import CheckpointError
from impact_lerobot.features import ObservationPlan, observation_plan
from impact_lerobot.settings import ENV_NAMESPACE, PluginSettings

LEROBOT_MISSING = ("LeRobot is not installed here; the lerobot_* methods need lerobot 0.4.4 "
                   "(bash tests/learn/lerobot_venv.sh VENV, docs/lerobot.md)")


class LeRobotPolicy:
    """A loaded LeRobot policy and its processors behind ``reset`` / ``act`` on a batch.

    Args:
        policy: LeRobot's policy (``PreTrainedPolicy``, in eval mode).
        preprocessor, postprocessor: Its processors (normalization of the inputs, of the
            action).
        plan: How our observation dict becomes the policy's features.
        noise_shape: (horizon, action size) of one env's diffusion noise; None for a policy
            that takes no noise (not a diffusion policy).
    """

    def __init__(self, policy: Any, preprocessor: Any, postprocessor: Any,
                 plan: ObservationPlan, noise_shape: tuple[int, int] | None) -> None:
        self.policy, self.pre, self.post = policy, preprocessor, postprocessor
        self.plan, self.noise_shape = plan, noise_shape
        self._generators: list[Any] = []

    def reset(self, n_envs: int) -> None:
        """Clear LeRobot's observation and action queues; unseeded envs draw from seed n."""
        import torch

        self.policy.reset()
        self._generators = [torch.Generator().manual_seed(i) for i in range(n_envs)]

    def seed_envs(self, episode_seeds: Sequence[int]) -> None:
        """Env ``i`` draws its diffusion noise from ``episode_seeds[i]``."""
        import torch

        self._generators = [torch.Generator().manual_seed(int(s)) for s in episode_seeds]

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Actions ``(B, 10)`` for our batched observation ``obs``."""
        import torch

        batch = {name: torch.from_numpy(values)
                 for name, values in self.plan.policy_batch(obs).items()}
        extra = {}
        if self.noise_shape is not None:
            extra["noise"] = torch.stack([torch.randn(self.noise_shape, generator=g)
                                          for g in self._generators])
        with torch.no_grad():
            action = self.policy.select_action(self.pre(batch), **extra)
        return np.asarray(self.post(action).numpy(), dtype=np.float32)


def _lerobot_classes() -> tuple[Any, Any]:
    """LeRobot's policy loader and processor factory (CheckpointError without LeRobot)."""
    try:
        from impact_learn.lerobot_compat import define_missing_torchvision_ops

        define_missing_torchvision_ops()
        from lerobot.policies.factory import get_policy_class, make_pre_post_processors
    except ImportError:
        raise CheckpointError(LEROBOT_MISSING) from None
    return get_policy_class, make_pre_post_processors


def policy_type(config_file: Path) -> str:
    """The policy ``type`` that ``config_file`` (a checkpoint's ``config.json``) names; one-line
    ``CheckpointError`` naming the file if it is missing, unreadable, not JSON, not a JSON
    object, or without a non-empty string ``type``."""
    import json

    folder, valid = config_file.parent, "valid: the config.json lerobot-train saves"
    if not config_file.exists():
        raise CheckpointError(f"no LeRobot policy in {folder}: config.json is missing")
    where = f"cannot load LeRobot policy: {config_file}"
    if not config_file.is_file():
        raise CheckpointError(f"{where} is not a file; {valid}")
    try:
        config = json.loads(config_file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        what = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise CheckpointError(f"{where} cannot be read ({what}); {valid}") from None
    except json.JSONDecodeError as exc:
        raise CheckpointError(f"{where} is not JSON ({exc.msg} at line {exc.lineno} column "
                              f"{exc.colno}); {valid}") from None
    except RecursionError:
        raise CheckpointError(f"{where} is not a config (nested too deeply); {valid}") from None
    if not isinstance(config, dict):
        raise CheckpointError(f"{where} holds a JSON {_json_kind(config)}, not an object; "
                              f"{valid}")
    kind = config.get("type")
    if not isinstance(kind, str) or not kind.strip():
        shown = "no \"type\"" if "type" not in config else f"\"type\" {kind!r}"
        raise CheckpointError(f"{where} has {shown}; "
                              f"{valid}, whose \"type\" names the policy (e.g. \"diffusion\")")
    return kind


def _json_kind(value: object) -> str:
    """JSON's name for the type of a decoded ``value`` (not an object)."""
    names = {list: "array", str: "string", int: "number", float: "number", bool: "boolean",
             type(None): "null"}
    return names.get(type(value), type(value).__name__)


def check_features(config: Any, plan: ObservationPlan, folder: Path) -> None:
    """The checkpoint's input features must be the plan's (names and shapes), one line if not."""
    wanted = {f.policy_key: tuple(f.shape) for f in plan.features() if f.kind != "ACTION"}
    if plan.layout.cameras:  # LeRobot's image features are C x H x W
        wanted.update({f.policy_key: (f.shape[2], f.shape[0], f.shape[1])
                       for f in plan.features() if f.kind == "VISUAL"})
    have = {name: tuple(f.shape) for name, f in config.input_features.items()}
    if have != wanted:
        raise CheckpointError(f"checkpoint {folder} takes the features {have}, the env gives "
                              f"{wanted}; valid: a policy trained on this env's export")


def load_lerobot_policy(folder: Path, env_id: str,
                        settings: PluginSettings | None = None) -> LeRobotPolicy:
    """The LeRobot checkpoint in ``folder`` for ``env_id`` (``IMPACT/<task>``), observing as
    ``settings`` say (None: the task's defaults, state observations).

    Raises:
        CheckpointError: LeRobot is missing, the folder holds no LeRobot policy (its
            ``config.json`` missing, damaged or not a policy's, ``policy_type``), or its
            features are not this env's (one line each).
    """
    task = env_id.split(":", 1)[-1].removeprefix(f"{ENV_NAMESPACE}/")
    settings = PluginSettings(task=task) if settings is None else settings
    get_policy_class, make_pre_post_processors = _lerobot_classes()
    kind = policy_type(Path(folder) / "config.json")
    try:
        policy = get_policy_class(kind).from_pretrained(str(folder)).eval()
        pre, post = make_pre_post_processors(policy.config, pretrained_path=str(folder))
    except Exception as exc:  # noqa: BLE001 - any load failure means an unusable checkpoint
        msg = " ".join(str(exc).split())[:160]
        raise CheckpointError(f"cannot load LeRobot policy {folder}: {type(exc).__name__}: "
                              f"{msg}") from None
    plan = observation_plan(settings)
    check_features(policy.config, plan, Path(folder))
    noise_shape = ((int(policy.config.horizon), int(policy.config.action_feature.shape[0]))
                   if kind == "diffusion" else None)
    return LeRobotPolicy(policy, pre, post, plan, noise_shape)
