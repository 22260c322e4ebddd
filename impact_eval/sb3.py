"""Stable-Baselines3 models as impact-eval methods: any algorithm, either controller, the
wrapper's action mode and VecNormalize statistics.

A model trained on ``impact_envs.wrappers.RLActions`` is evaluated on envs wrapped the same
way: its mode is read from the zip's ``data`` JSON (the action space's shape and bounds),
without unpickling. Loading itself unpickles (SB3's format), so it needs the trust opt-in.
"""

from __future__ import annotations

import json
import os
import pickle
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np

from impact_control.errors import CheckpointError

TRUST_SB3_ENV_VAR = "IMPACT_TRUST_SB3"
"""Set to ``1`` (or pass ``impact-eval --trust-sb3``) to allow loading ``sb3:<zip>``: SB3's zip
format unpickles Python objects, so a crafted file executes code when loaded."""
VECNORMALIZE_NAMES = ("vec_normalize.pkl", "{stem}_vecnormalize.pkl")
"""VecNormalize statistics next to a zip that ``load_sb3`` applies to observations."""


def _zip_path(path: str) -> Path:
    p = Path(path)
    return p if p.is_file() else Path(path + ".zip")


def _zip_data(path: str) -> dict:
    """The zip's ``data`` JSON ({} when unreadable; loading then reports the problem)."""
    try:
        with zipfile.ZipFile(_zip_path(path)) as z:
            return json.loads(z.read("data"))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return {}


def sb3_action_mode(path: str) -> str | None:
    """``"delta"`` for a 7-D action space, ``"absolute"`` for a 10-D ``Box(-1, 1)`` (the
    ``RLActions`` modes), None for the env's own action space or an unreadable zip."""
    space = _zip_data(path).get("action_space", {})
    shape = space.get("_shape") if isinstance(space, dict) else None
    if shape == [7]:
        return "delta"
    if shape == [10] and all(str(space.get(k, "")).strip("[]").split() == [v] * 10
                             for k, v in (("low", "-1."), ("high", "1."))):
        return "absolute"
    return None


def _algorithms() -> list[type]:
    """Every algorithm class of stable_baselines3 (and sb3_contrib when installed)."""
    import stable_baselines3 as sb3
    from stable_baselines3.common.base_class import BaseAlgorithm

    modules = [sb3]
    try:
        import sb3_contrib

        modules.append(sb3_contrib)
    except ImportError:
        pass
    return [c for m in modules for c in vars(m).values()
            if isinstance(c, type) and issubclass(c, BaseAlgorithm)]


def _candidates(path: str) -> list[type]:
    """The algorithm named by the zip's policy class module first, then all others."""
    policy = _zip_data(path).get("policy_class", {})
    module = policy.get("__module__", "") if isinstance(policy, dict) else ""
    algo = module.split(".")[1] if module.count(".") >= 2 else ""
    algos = _algorithms()
    return sorted(algos, key=lambda c: c.__module__.split(".")[1:2] != [algo])


class SB3Policy:
    """A Stable-Baselines3 model behind the batched ``Policy`` protocol (deterministic)."""

    def __init__(self, model: object, vecnormalize: object | None = None) -> None:
        self.model, self.vecnormalize = model, vecnormalize

    def reset(self, n_envs: int) -> None:
        """SB3 feed-forward policies are stateless: nothing to clear."""

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Deterministic actions ``(B, action_dim)`` for a batched observation."""
        if self.vecnormalize is not None:
            obs = self.vecnormalize.normalize_obs(obs)
        action, _ = self.model.predict(obs, deterministic=True)  # type: ignore[attr-defined]
        return np.asarray(action, dtype=np.float32)


def _vecnormalize(path: str) -> object | None:
    zp = _zip_path(path)
    for name in VECNORMALIZE_NAMES:
        stats = zp.with_name(name.format(stem=zp.stem))
        if stats.is_file():
            with stats.open("rb") as f:
                return pickle.load(f)  # noqa: S301 - behind the trust opt-in, as SB3's own
    return None


def load_sb3(path: str, env: gym.Env) -> SB3Policy:
    """Load an SB3 zip (any algorithm; the one its policy class names is tried first) on CPU,
    with VecNormalize statistics found next to it.

    Raises:
        CheckpointError: missing file, unloadable file, an action space that does not fit
            ``env``, or loading not allowed (``$IMPACT_TRUST_SB3=1`` / ``--trust-sb3``).
    """
    if not _zip_path(path).is_file():
        raise CheckpointError(f"SB3 checkpoint {path} does not exist")
    if os.environ.get(TRUST_SB3_ENV_VAR) != "1":
        raise CheckpointError(
            f"refusing to load SB3 checkpoint {path}: SB3 zips are unpickled and can execute "
            f"code; pass --trust-sb3 (or set {TRUST_SB3_ENV_VAR}=1) only for files you trust")
    errors = []
    for cls in _candidates(path):
        try:
            model = cls.load(path, device="cpu")
        except Exception as exc:  # noqa: BLE001 - try the next algorithm
            errors.append(f"{cls.__name__}: {type(exc).__name__}")
            continue
        if model.action_space.shape != env.action_space.shape:
            raise CheckpointError(
                f"SB3 checkpoint {path} has action shape {model.action_space.shape}, "
                f"env has {env.action_space.shape}")
        return SB3Policy(model, _vecnormalize(path))
    raise CheckpointError(f"cannot load SB3 checkpoint {path} ({'; '.join(errors[:4])})")
