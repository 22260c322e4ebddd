"""Scripted experts, looked up by task name (or by env id, through the task registry).

A task's expert is written for it, so policies depend on tasks, never the reverse. The
built-in experts are imported on first use; a new task adds its own with ``register_expert``
(docs/adding_a_task.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from importlib import import_module

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_control.policy import Policy
from impact_envs.versions import check_not_retired

ExpertFactory = Callable[[str], Policy]
"""``factory(compensation) -> Policy`` (``compensation``: ``scripted.COMPENSATIONS``)."""

_BUILTIN = {
    "hammer": "impact_envs.policies.scripted:hammer_expert",
    "dumbbell": "impact_envs.policies.scripted:dumbbell_expert",
    "calligraphy": "impact_envs.policies.scripted_calligraphy:calligraphy_expert",
    "disturbance": "impact_envs.policies.scripted_disturbance:disturbance_expert",
    "hammer_basket": "impact_envs.policies.scripted_hammer_basket:hammer_basket_expert",
}
_REGISTERED: dict[str, ExpertFactory] = {}
_OTHERS = {
    ("hammer_basket", "authors"):
        "impact_envs.policies.authors_demonstrator:authors_demonstrator",
}
"""Experts other than a task's scripted one: (task name, expert name) -> factory."""
EXPERTS = ("scripted", "authors")
"""Expert names (``make_expert``'s ``expert``): the task's own, or its authors' demonstrator."""


def register_expert(task_name: str, factory: ExpertFactory) -> None:
    """Make ``make_expert`` build ``factory(compensation)`` for the task called ``task_name``."""
    _REGISTERED[task_name] = factory


def _other(task_name: str, expert: str) -> ExpertFactory:
    """The factory of a task's non-scripted ``expert``; one line naming the valid ones."""
    if (task_name, expert) not in _OTHERS:
        valid = ["scripted"] + [e for t, e in _OTHERS if t == task_name]
        raise InvalidArgumentError(
            f"no expert {expert!r} for task {task_name!r}; valid: {', '.join(valid)}")
    module, name = _OTHERS[task_name, expert].split(":")
    return getattr(import_module(module), name)


def _factory(task_name: str) -> ExpertFactory | None:
    if task_name in _REGISTERED:
        return _REGISTERED[task_name]
    if task_name in _BUILTIN:
        module, name = _BUILTIN[task_name].split(":")
        return getattr(import_module(module), name)
    return None


def make_expert(task: str, compensation: str = "none", expert: str = "scripted") -> Policy:
    """The scripted expert of a task, by task name (``"hammer"``) or env id
    (``"IMPACT/Hammer-v1"``); ``compensation``: how it meets a load's sag; ``expert``:
    ``"scripted"`` (the task's own) or ``"authors"`` (the paper authors' demonstrator, where
    the task has one: HammerBasket).

    Raises:
        InvalidArgumentError: Unknown task or env id (a retired one: the line naming its
            current id, ``versions.retired``), no expert for it, or a compensation
            the expert does not offer, or an expert the task lacks (each a one-line error
            naming the valid choices).
    """
    from impact_envs.tasks.registry import TASKS  # filled by ``import impact_envs``

    if "/" in task and task not in TASKS:
        check_not_retired(task)  # a retired id: the line naming its current version
        raise InvalidArgumentError(
            f"no scripted expert for {task!r}: not a registered IMPACT task; valid: "
            f"{', '.join(TASKS)}, or a task name")
    name = TASKS[task].name if "/" in task else task
    if expert != "scripted":
        return _other(name, expert)(compensation)
    factory = _factory(name)
    if factory is None:
        valid = sorted({*_BUILTIN, *_REGISTERED})
        raise InvalidArgumentError(
            f"no scripted expert for task {name!r}; valid: {', '.join(valid)}")
    return factory(compensation)


def check_expert_obs(obs: object, keys: Sequence[str], n_envs: int, expert: str) -> None:
    """One-line ``InvalidArgumentError`` unless ``obs`` is a batched ``Dict`` observation of
    ``n_envs`` rows holding every entry in ``keys``: a scripted expert reads the object's and
    the goal's poses, which the image modes (``"rgb"``, ``"rgbd"``) hide from a policy."""
    if not isinstance(obs, Mapping):
        raise InvalidArgumentError(
            f"{expert}.act takes the env's Dict observation batched as {{key: (B, ...)}} "
            f"(impact_control.policy.stack_obs), not {type(obs).__name__}")
    missing = [k for k in keys if k not in obs]
    if missing:
        raise InvalidArgumentError(
            f"{expert} needs the state observation entries {', '.join(missing)}, which this "
            "observation lacks (the image modes 'rgb' and 'rgbd' hide them); make the env with "
            "observation=ObservationOptions(obs_mode='state') or 'state+rgb'")
    for key in keys:
        shape = np.shape(obs[key])
        if len(shape) < 2 or shape[0] != n_envs:
            raise InvalidArgumentError(
                f"{expert}.act: observation {key!r} has shape {shape}; valid: a batch of "
                f"reset(n_envs)'s {n_envs} rows, (B, ...) with B = {n_envs} "
                "(impact_control.policy.stack_obs([obs]) for one env)")
