"""IMPACT: Gymnasium environments and the internal-model predictive controller.

Importing this package registers the environments, one per task (``tasks/registry.py``), e.g.
``gym.make("IMPACT/Hammer-v0")``.
"""

from __future__ import annotations

from impact_envs import jit_cache as _jit_cache
from impact_envs.tasks.calligraphy import CalligraphyTask as _CalligraphyTask
from impact_envs.tasks.disturbance import DisturbanceTask as _DisturbanceTask
from impact_envs.tasks.dumbbell import DumbbellTask as _DumbbellTask
from impact_envs.tasks.hammer import HammerTask as _HammerTask
from impact_envs.tasks.registry import register_task as _register_task

__version__ = "0.1.0"

ENV_IDS = tuple(_register_task(t) for t in (_HammerTask, _DumbbellTask, _CalligraphyTask,
                                              _DisturbanceTask))
"""The built-in envs, one per task."""

_jit_cache.ensure_fresh_kernel_cache()
