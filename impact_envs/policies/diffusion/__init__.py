"""State-based Diffusion Policy baseline (Vanilla DP / Augmented DP).

Public API (imported lazily, so ``import impact_envs.policies.diffusion`` stays cheap)::

    DiffusionConfig                       hyper-parameters (config.py)
    DiffusionPolicy.load(dir, seed=0)     trained policy, Policy protocol (policy.py)
    RunOptions, CollectConfig, measure_inference, InferenceCost

The functions ``train.train`` (``impact-train``) and ``collect.collect`` (``impact-collect``)
share their module's name, so import them from the modules::

    from impact_envs.policies.diffusion.train import train
    from impact_envs.policies.diffusion.collect import collect
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "DiffusionConfig": "config",
    "DiffusionPolicy": "policy",
    "RunOptions": "train",
    "CollectConfig": "collect_config",
    "measure_inference": "bench",
    "InferenceCost": "bench",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{_EXPORTS[name]}"), name)
