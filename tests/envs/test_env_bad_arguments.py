"""Issue 53: bad constructor arguments and actions are one line on every registered env, never
silent: a parameter given two different values by two routes, an unknown ``gym.make``
keyword or ``task_params`` key, a non-finite action (told apart from a wrong shape); and
``--robot-set`` errors name each field's real type."""

from __future__ import annotations

import inspect
from types import MappingProxyType

import gymnasium as gym
import numpy as np
import pytest

import impact_envs
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_envs.envs.base import ACTION_ENTRIES, ImpactEnv
from impact_envs.envs.hammer import HammerEnv
from impact_envs.envs.options import (
    ROBOT_CHOICES,
    RobotOptions,
    apply_robot_overrides,
    robot_field_types,
)
from impact_envs.tasks.registry import TASKS

ENV_IDS = impact_envs.ENV_IDS
ENV_KEYWORDS = [p.name for p in inspect.signature(ImpactEnv.__init__).parameters.values()
                if p.kind is p.KEYWORD_ONLY]


def _one_line(err: pytest.ExceptionInfo) -> str:
    text = str(err.value)
    assert isinstance(err.value, ImpactError) and "\n" not in text
    return text


def _params(env_id: str) -> list[str]:
    return [p.name for p in TASKS[env_id].params]


# ------------------------------------------------------- one parameter, two routes
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_two_different_values_for_one_parameter_are_refused(env_id: str) -> None:
    """``object_mass=`` is the shorthand of the task's declared mass (Calligraphy: tool_mass;
    issue 57); given by both routes with different values it is refused in one line."""
    mass = TASKS[env_id].mass_param().name
    for shorthand, routed in ((4, {mass: 5}), (1.0, {mass: 1.0000001}),
                              (2, MappingProxyType({mass: np.float64(3.0)}))):
        with pytest.raises(InvalidArgumentError) as err:
            gym.make(env_id, object_mass=shorthand, task_params=routed)
        line = _one_line(err)
        assert "given twice" in line
        assert f"object_mass={shorthand!r}" in line
        assert f"task_params[{mass!r}]={routed[mass]!r}" in line


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_equal_values_by_two_routes_pass(env_id: str) -> None:
    name = TASKS[env_id].mass_param().name  # the shorthand's parameter (issue 57)
    env = gym.make(env_id, object_mass=2, task_params={name: np.float32(2.0)})
    _, info = env.reset(seed=0)
    assert info[name] == 2.0
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_task_params_must_be_a_dict_of_the_tasks_parameters(env_id: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        gym.make(env_id, task_params=[(_params(env_id)[0], 1.0)])
    assert "invalid task_params" in _one_line(err) and _params(env_id)[0] in str(err.value)
    with pytest.raises(InvalidArgumentError) as err:
        gym.make(env_id, task_params={"objct_mass": 1.0})
    line = _one_line(err)
    assert "'objct_mass'" in line and all(name in line for name in _params(env_id))


# ------------------------------------------------------------ unknown keywords
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_an_unknown_keyword_names_the_valid_ones_and_the_closest(env_id: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        gym.make(env_id, objct_mass=5)
    line = _one_line(err)
    assert "'objct_mass'" in line and "did you mean 'object_mass'?" in line
    assert all(name in line.split("valid: ")[1] for name in ENV_KEYWORDS)
    with pytest.raises(InvalidArgumentError) as err:  # nothing close, and two at once
        gym.make(env_id, speed=2, colour="red")
    line = _one_line(err)
    assert "'speed', 'colour'" in line and "did you mean" not in line
    assert all(name in line for name in ENV_KEYWORDS)


def test_the_class_itself_refuses_an_unknown_keyword_and_a_subclass_may_take_more() -> None:
    with pytest.raises(InvalidArgumentError, match="did you mean 'reward_type'"):
        HammerEnv(rewrd_type="dense")

    class Extended(HammerEnv):
        def __init__(self, *, extra: int = 0, **kwargs: object) -> None:
            self.extra = extra
            super().__init__(**kwargs)

    assert Extended(extra=3, object_mass=1.0).extra == 3
    with pytest.raises(InvalidArgumentError) as err:
        Extended(extra=3, objct_mass=1.0)  # **kwargs go on to ImpactEnv's own keywords
    line = _one_line(err)
    assert "'objct_mass'" in line and all(k in line for k in ["extra", *ENV_KEYWORDS])

    class TakesAnything(HammerEnv):
        def __init__(self, **kwargs: object) -> None:
            self.kwargs = kwargs

    assert TakesAnything(anything=1).kwargs == {"anything": 1}  # no list of valid ones


# ---------------------------------------------------------------------- actions
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_non_finite_action_is_its_own_error_naming_the_entries(env_id: str) -> None:
    env = gym.make(env_id)
    obs, _ = env.reset(seed=0)
    hold = np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]).astype(np.float32)
    for bad in ({0: np.nan}, {4: np.inf}, {2: -np.inf, 9: np.nan}):
        action = hold.copy()
        action[list(bad)] = list(bad.values())
        with pytest.raises(InvalidArgumentError) as err:
            env.step(action)
        line = _one_line(err)
        assert "non-finite" in line and "shape" not in line
        for i, value in bad.items():
            assert f"action[{i}] ({ACTION_ENTRIES[i]}) = {value}" in line
    for shape in ((9,), (10, 1), (11,)):  # a wrong shape stays a shape error, NaN or not
        for fill in (0.0, np.nan):
            with pytest.raises(InvalidArgumentError) as err:
                env.step(np.full(shape, fill))
            line = _one_line(err)
            assert f"got shape {shape}" in line and "non-finite" not in line
    assert env.unwrapped._step_count == 0  # nothing refused was stepped
    env.step(hold)
    env.close()


# ----------------------------------------------------------------- --robot-set
BAD_TEXT = {"int": "1.5", "float": "abc", "bool": "maybe", "str": ""}
VALID_NAMED = {"int": "valid: an integer", "float": "valid: a number",
               "bool": "valid: true or false"}


@pytest.mark.parametrize("field", sorted(robot_field_types()))
def test_every_robot_set_type_error_names_the_fields_type(field: str) -> None:
    kind, optional = robot_field_types()[field]
    bad = "nope" if field in ROBOT_CHOICES else BAD_TEXT[kind]
    with pytest.raises(InvalidArgumentError) as err:
        apply_robot_overrides(None, [f"{field}={bad}"])
    line = _one_line(err)
    if field in ROBOT_CHOICES:
        assert all(choice in line for choice in ROBOT_CHOICES[field])
    else:
        assert VALID_NAMED[kind] in line and f"{field}={bad!r}" in line
    assert ("none" in line) == optional


@pytest.mark.parametrize(("setting", "message"), [
    ("model_seed=1.5", "invalid --robot-set model_seed='1.5'; valid: an integer or none"),
    ("delay_ticks=1e0", "invalid --robot-set delay_ticks='1e0'; valid: an integer or none"),
    ("sensor_noise=maybe", "invalid --robot-set sensor_noise='maybe'; valid: true or false"),
    ("sensor_noise=none", "invalid --robot-set sensor_noise='none'; valid: true or false"),
    ("model_mass_error=none", "invalid --robot-set model_mass_error='none'; valid: a number"),
    ("torque_reading=sensor", "valid choices: link_side, commanded"),
    ("hand=left_hand", "valid choices: franka_hand, authors_sim, none"),
    ("realism=perfect", "invalid realism 'perfect'; valid choices: ideal, fr3"),
])
def test_robot_set_examples(setting: str, message: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        apply_robot_overrides(None, [setting])
    assert message in _one_line(err)


def test_robot_set_reads_each_type() -> None:
    robot = apply_robot_overrides(None, ["model_seed=7", "sensor_noise=FALSE", "hand=authors_sim",
                                         "grasp_force_n=150", "delay_ticks=none",
                                         "realism=fr3"])
    assert robot == RobotOptions(model_seed=7, sensor_noise=False, hand="authors_sim",
                                 grasp_force_n=150.0, realism="fr3")
    assert type(robot.model_seed) is int and type(robot.grasp_force_n) is float
    assert set(robot_field_types()[name][0] for name in robot_field_types()) <= set(BAD_TEXT)
