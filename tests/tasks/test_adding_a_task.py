"""docs/adding_a_task.md, proven: a task added by two files outside the package
(tests/fixtures/reach_task.py, tests/fixtures/reach_scene.xml) is a full IMPACT env."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from fixtures.reach_task import ReachTask
from gymnasium.utils.env_checker import check_env

from impact_control.policy import stack_obs
from impact_envs.policies.experts import make_expert
from impact_envs.tasks.registry import task_class

ENV_ID = ReachTask.env_id


def test_the_added_task_passes_the_env_checkers():
    env = gym.make(ENV_ID)
    assert env.spec.max_episode_steps == ReachTask.max_episode_steps
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_spaces_and_validation_come_from_the_declaration():
    env = gym.make(ENV_ID)
    robot = {"ee_pos", "ee_rot6d", "gripper_width", "joint_pos", "joint_vel"}
    assert set(env.observation_space.spaces) == robot | {"goal_pos"}
    assert env.unwrapped.param_name == "target_height"
    with pytest.raises(ValueError, match="target_height=0.9 out of range; valid: 0.15 to 0.5 m"):
        env.reset(seed=0, options={"target_height": 0.9})
    assert task_class(ENV_ID) is ReachTask
    env.close()


@pytest.mark.parametrize("controller", ["impact", "impedance"])
def test_the_added_task_is_solved_by_its_registered_expert(controller):
    env = gym.make(ENV_ID, controller=controller)
    expert = make_expert(ENV_ID)
    obs, _ = env.reset(seed=3)
    expert.reset(1)
    for _ in range(ReachTask.max_episode_steps):
        obs, reward, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
        assert all(np.isfinite(v).all() for v in obs.values())
    assert info["success_once"]
    env.close()
