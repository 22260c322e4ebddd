"""Pick-and-place expert: the optional carry dwell (``PickPlaceSpec.carry_dwell_steps``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.experts import make_expert
from impact_envs.policies.scripted import CARRY, LOWER
from impact_experiments.adaptation import protocol_expert


def _carry_obs(goal: np.ndarray, carry_z: float) -> dict[str, np.ndarray]:
    """One env's observation with the TCP and the object already at the carry waypoint."""
    ee = np.array([goal[0], goal[1], carry_z])
    rot6d = np.array([1.0, 0.0, 0.0, 0.0, -1.0, 0.0])
    return {"ee_pos": ee[None], "ee_rot6d": rot6d[None], "gripper_width": np.array([[0.03]]),
            "object_pos": (ee - [0, 0, 0.05])[None], "object_rot6d": rot6d[None],
            "goal_pos": goal[None]}


@pytest.mark.parametrize("dwell", [0, 7])
def test_carry_ends_after_the_dwell_at_the_waypoint(dwell):
    expert = make_expert("IMPACT/Dumbbell-v1")
    expert.spec = replace(expert.spec, carry_dwell_steps=dwell)
    expert.reset(1)
    goal = np.array([0.35, -0.17, 0.0])
    obs = _carry_obs(goal, expert.spec.carry_z)
    expert.phase[0] = CARRY
    expert.target[0] = obs["ee_pos"][0].copy()  # target already on the waypoint
    expert.rot[0] = np.diag([1.0, -1.0, -1.0])
    steps = 0
    while expert.phase[0] == CARRY:
        action = expert.act(obs)
        np.testing.assert_allclose(action[0, :3], obs["ee_pos"][0])  # holds still
        steps += 1
        assert steps < 100
    assert expert.phase[0] == LOWER
    assert steps == max(dwell, 1)  # no dwell: the first step that sees the TCP there


def test_dwell_extends_the_carry_timeout():
    spec = replace(make_expert("IMPACT/Dumbbell-v1").spec, carry_dwell_steps=90)
    assert spec.timeout_steps(CARRY) == spec.timeouts_steps[CARRY] + 90
    assert spec.timeout_steps(LOWER) == spec.timeouts_steps[LOWER]


def test_protocol_expert_validates_env_and_hold():
    assert protocol_expert("IMPACT/Hammer-v1", 2.0).spec.carry_dwell_steps == 60
    with pytest.raises(InvalidArgumentError, match="valid: IMPACT/Dumbbell-v1"):
        protocol_expert("IMPACT/Disturbance-v1", 1.0)
    with pytest.raises(InvalidArgumentError, match="--hold-s must be >= 0"):
        protocol_expert("IMPACT/Dumbbell-v1", -1.0)


@pytest.mark.parametrize("family", ["Hammer", "Dumbbell", "Calligraphy", "Disturbance",
                                    "HammerBasket"])
def test_a_retired_id_names_its_current_version(family):
    """make_expert said "not a registered IMPACT task" for a -v0 id: now the line gym.make and
    impact-eval give (impact_envs.versions.retired), naming -v1, for every family and for a
    module-qualified id too."""
    from impact_envs.versions import retired

    for env_id in (f"IMPACT/{family}-v0", f"impact_envs:IMPACT/{family}-v0"):
        with pytest.raises(InvalidArgumentError) as err:
            make_expert(env_id)
        assert str(err.value) == retired(env_id) and "\n" not in str(err.value)
        assert f"use {env_id[:-1]}1" in str(err.value)


@pytest.mark.parametrize("env_id", ["IMPACT/Hammer-v3", "IMPACT/Nope-v0", "Other/Hammer"])
def test_an_id_that_was_never_registered_is_still_not_a_registered_task(env_id):
    with pytest.raises(InvalidArgumentError, match="not a registered IMPACT task; valid: "
                                                   "IMPACT/Hammer-v1"):
        make_expert(env_id)
