"""A task declares its mass once (``TaskParam.is_mass``; issue 57): eval, collect and the
LeRobot plugin read it through ``Task.mass_param`` / ``bins.mass_info_key``, and ``info``
reports it under the name the task declares."""

from __future__ import annotations

import gymnasium as gym
import pytest

import impact_envs
from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.base import TaskParam
from impact_envs.tasks.bins import MASS_PARAM, mass_info_key
from impact_envs.tasks.registry import task_class

MASSES = {"IMPACT/Hammer-v1": "object_mass", "IMPACT/Dumbbell-v1": "object_mass",
          "IMPACT/HammerBasket-v1": "object_mass", "IMPACT/Disturbance-v1": "object_mass",
          "IMPACT/Calligraphy-v1": "tool_mass"}


def test_every_registered_task_declares_its_mass_once() -> None:
    for env_id in impact_envs.ENV_IDS:
        task = task_class(env_id)
        declared = [p.name for p in task.params if p.is_mass]
        assert declared[:1] == [MASSES[env_id.replace("-v2", "-v1")]], env_id
        assert task.mass_param() is not None and task.mass_param().unit == "kg"


@pytest.mark.parametrize("env_id", ["IMPACT/Calligraphy-v1", "IMPACT/Hammer-v1"])
def test_info_and_the_mass_key_name_the_declared_parameter(env_id: str) -> None:
    env = gym.make(env_id, object_mass=0.37)  # the shorthand sets the task's mass
    try:
        key = mass_info_key(env)
        assert key == MASSES[env_id]
        _, info = env.reset(seed=0)
        assert info[key] == pytest.approx(0.37)
    finally:
        env.close()


def test_an_env_without_a_task_keeps_object_mass() -> None:
    assert mass_info_key(object()) == MASS_PARAM == "object_mass"


def test_a_mass_must_be_in_kg() -> None:
    with pytest.raises(InvalidArgumentError, match="is_mass with unit 'N'"):
        TaskParam("push", 1.0, 0.0, 2.0, "N", is_mass=True)
