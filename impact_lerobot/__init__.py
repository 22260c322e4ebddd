"""IMPACT's envs as a LeRobot env plugin (lerobot 0.4.4; docs/lerobot.md, "LeRobot env plugin").

Importing this package registers ``gym_impact/<task>`` for every built-in env (``env.py``);
without LeRobot the settings (``settings.py``) and the feature mapping (``features.py``) work
as they are. LeRobot imports the package and its modules with
``--env.discover_packages_path=impact_lerobot``; ``lerobot_config.py`` then registers the env
type ``impact`` (it imports LeRobot, so only LeRobot's loader and code that has LeRobot import
it)::

    lerobot-eval --env.discover_packages_path=impact_lerobot --env.type=impact \\
        --env.task=Hammer-v1 --policy.path=DIR --eval.n_episodes=10 --eval.batch_size=1
"""

from __future__ import annotations

from impact_envs import _gl  # noqa: F401, I001 - first: the headless GL backend before mujoco
from impact_lerobot.env import LeRobotObservations, make_lerobot_env, register_envs
from impact_lerobot.features import Feature, ObservationPlan, observation_plan
from impact_lerobot.settings import GYM_NAMESPACE, OBS_MODES, TASKS, PluginSettings

GYM_IDS = register_envs()
"""The registered ``gym_impact/<task>`` ids."""

__all__ = ["GYM_IDS", "GYM_NAMESPACE", "OBS_MODES", "TASKS", "Feature", "LeRobotObservations",
           "ObservationPlan", "PluginSettings", "make_lerobot_env", "observation_plan"]
