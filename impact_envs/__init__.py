"""IMPACT: Gymnasium environments and the internal-model predictive controller.

Importing this package registers the environments, e.g. ``gym.make("IMPACT/Hammer-v0")``.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from impact_envs import jit_cache as _jit_cache

__version__ = "0.1.0"

ENV_IDS = (
    "IMPACT/Hammer-v0",
    "IMPACT/Dumbbell-v0",
    "IMPACT/Calligraphy-v0",
    "IMPACT/Disturbance-v0",
)

_ENTRY_POINTS = {
    "IMPACT/Hammer-v0": ("impact_envs.envs.hammer:HammerEnv", 750),
    "IMPACT/Dumbbell-v0": ("impact_envs.envs.dumbbell:DumbbellEnv", 750),
    "IMPACT/Calligraphy-v0": ("impact_envs.envs.calligraphy:CalligraphyEnv", 600),
    "IMPACT/Disturbance-v0": ("impact_envs.envs.disturbance:DisturbanceEnv", 540),
}

for _env_id, (_entry, _steps) in _ENTRY_POINTS.items():
    if _env_id not in registry:
        register(id=_env_id, entry_point=_entry, max_episode_steps=_steps)

_jit_cache.ensure_fresh_kernel_cache()
