"""Registered tasks: one Gymnasium env per task, from the task's own declaration.

``register_task(TaskClass)`` registers ``TaskClass.env_id`` with ``max_episode_steps`` from the
task and, as entry point, the task's documented ``ImpactEnv`` subclass (``env_entry_point``)
or the generic ``ImpactEnv`` given the task. A built-in task's id names its family's current
version; every version of the family that is not retired is registered too, each with its
``env_version`` (``impact_envs/versions.py``: ``IMPACT/Hammer-v1`` beside ``-v2``).
``import impact_envs`` registers the built-in tasks this way; a new task's module calls it once
(docs/adding_a_task.md).
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.base import Task
from impact_envs.versions import check_not_retired, parse, registered

TASKS: dict[str, type[Task]] = {}
"""Env id -> task class, in registration order (every registered version of a family)."""


def register_task(task_cls: type[Task]) -> str:
    """Register the env of ``task_cls`` (for a built-in family, each registered version);
    returns its id, the current version's (a second call is a no-op)."""
    env_id = task_cls.env_id
    parsed = parse(env_id)
    ids: dict[str, dict[str, object]] = {env_id: {}}
    if parsed is not None:
        family, _ = parsed
        ids = {env_id.replace(f"{family}-v{parsed[1]}", f"{family}-v{v.version}"):
               {"env_version": v.version} for v in registered(family)}
    for one_id, version in ids.items():
        TASKS[one_id] = task_cls
        if one_id in registry:
            continue
        kwargs = dict(version)
        if task_cls.env_entry_point is None:
            kwargs["task"] = f"{task_cls.__module__}:{task_cls.__qualname__}"
        register(
            id=one_id,
            entry_point=task_cls.env_entry_point or "impact_envs.envs.base:ImpactEnv",
            max_episode_steps=task_cls.max_episode_steps,
            # Gymnasium's passive checker latches its "reset was called" flag even when the
            # first reset is refused (bad options), after which every step raises TypeError
            # inside the checker; the envs validate their own inputs and tests/envs/test_envs.py
            # runs the full checker, so gym.make adds no passive checker (docs/envs.md).
            disable_env_checker=True,
            kwargs=kwargs,
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
