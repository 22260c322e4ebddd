"""IMPACT: Gymnasium environments and the internal-model predictive controller.

Importing this package registers the environments, one per task (``tasks/registry.py``), e.g.
``gym.make("IMPACT/Hammer-v2")`` (``-v1`` stays registered: ``impact_envs/versions.py``). On a
machine without a display it first picks MuJoCo's headless GL backend when ``MUJOCO_GL`` is
unset (``_gl.py``; before anything imports mujoco). The envs' option classes are importable
from here: ``from impact_envs import ObservationOptions, RenderOptions, RobotOptions``.
"""

from __future__ import annotations

from pathlib import Path as _Path

from impact_control import __version__  # noqa: E402 - one version for the distribution
from impact_control import jit_cache as _jit_cache
from impact_envs import _gl  # noqa: F401, I001 - first: MuJoCo reads MUJOCO_GL on import
from impact_envs.envs.options import ObservationOptions, RenderOptions, RobotOptions
from impact_envs.tasks.calligraphy import CalligraphyTask as _CalligraphyTask
from impact_envs.tasks.disturbance import DisturbanceTask as _DisturbanceTask
from impact_envs.tasks.dumbbell import DumbbellTask as _DumbbellTask
from impact_envs.tasks.hammer import HammerTask as _HammerTask
from impact_envs.tasks.hammer_basket import HammerBasketTask as _HammerBasketTask
from impact_envs.tasks.registry import TASKS as _TASKS
from impact_envs.tasks.registry import register_task as _register_task
from impact_envs.versions import parse as _parse

ENV_IDS = tuple(_register_task(t) for t in (_HammerTask, _DumbbellTask, _CalligraphyTask,
                                              _DisturbanceTask, _HammerBasketTask))
"""The built-in envs, one per task, at their current version."""
REGISTERED_IDS = tuple(_env_id for _env_id in _TASKS if _parse(_env_id) is not None)
"""Every registered version of the built-in envs (``ENV_IDS`` and the kept ``-v1`` ids)."""

_PACKAGE_DIR = _Path(__file__).resolve().parent
_jit_cache.ensure_fresh_kernel_cache((_PACKAGE_DIR / "loop", _PACKAGE_DIR / "robot"),
                                     depends_on=(_jit_cache.PACKAGE_DIR,))

__all__ = ["ENV_IDS", "REGISTERED_IDS", "ObservationOptions", "RenderOptions", "RobotOptions",
           "__version__"]
