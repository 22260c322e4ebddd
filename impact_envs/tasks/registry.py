"""Registered tasks: one Gymnasium env per task, from the task's own declaration.

``register_task(TaskClass)`` registers ``TaskClass.env_id`` with ``max_episode_steps`` from the
task and, as entry point, the task's documented ``ImpactEnv`` subclass (``env_entry_point``)
or the generic ``ImpactEnv`` given the task. ``import impact_envs`` registers the four
built-in tasks this way; a new task's module calls it once (docs/adding_a_task.md).
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.base import Task
from impact_envs.versions import check_not_retired

TASKS: dict[str, type[Task]] = {}
"""Env id -> task class, in registration order."""


def register_task(task_cls: type[Task]) -> str:
    """Register the env of ``task_cls``; returns its id (a second call is a no-op)."""
    env_id = task_cls.env_id
    TASKS[env_id] = task_cls
    if env_id not in registry:
        generic = task_cls.env_entry_point is None
        register(
            id=env_id,
            entry_point=task_cls.env_entry_point or "impact_envs.envs.base:ImpactEnv",
            max_episode_steps=task_cls.max_episode_steps,
            # Gymnasium's passive checker latches its "reset was called" flag even when the
            # first reset is refused (bad options), after which every step raises TypeError
            # inside the checker; the envs validate their own inputs and tests/envs/test_envs.py
            # runs the full checker, so gym.make adds no passive checker (docs/envs.md).
            disable_env_checker=True,
            kwargs={"task": f"{task_cls.__module__}:{task_cls.__qualname__}"} if generic else {},
        )
    return env_id


def task_class(env_id: str) -> type[Task]:
    """The task registered under ``env_id`` (a one-line error naming the valid ids). The
    built-in tasks are registered by then: importing this module runs ``impact_envs``'s
    ``__init__`` first, which registers them."""
    check_not_retired(env_id)
    if env_id not in TASKS:
        raise InvalidArgumentError(f"unknown env {env_id!r}; valid: {', '.join(TASKS)}")
    return TASKS[env_id]
