"""State-based Diffusion Policy baseline (Vanilla DP / Augmented DP): the runtime side.

Public API (imported lazily, so ``import impact_envs.policies.diffusion`` stays cheap)::

    DiffusionConfig                       hyper-parameters (config.py)
    DiffusionPolicy.load(dir, seed=0)     trained policy, Policy protocol (policy.py)

Collecting demonstrations and training live in the ``impact_learn`` package
(``impact-collect``, ``impact-train``).
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "DiffusionConfig": "config",
    "DiffusionPolicy": "policy",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{_EXPORTS[name]}"), name)
