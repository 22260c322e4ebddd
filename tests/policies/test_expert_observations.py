"""The scripted experts on an observation they cannot act on (an image mode's, an unbatched
one, a wrong batch size, not a dict): one line saying what they need, never a bare KeyError."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import impact_envs  # noqa: F401 - registers the envs
from impact_control.errors import InvalidArgumentError
from impact_control.policy import stack_obs
from impact_envs.policies.experts import make_expert

ROBOT = {"ee_pos": (3,), "ee_rot6d": (6,), "gripper_width": (1,), "joint_pos": (7,),
         "joint_vel": (7,)}
"""The robot's own entries, which every observation mode keeps."""
IMAGE = {"overview_rgb": (8, 8, 3), "wrist_rgb": (8, 8, 3)}


def _batch(shapes: dict[str, tuple[int, ...]], n: int = 1) -> dict[str, np.ndarray]:
    return {k: np.zeros((n, *shape), np.float32) for k, shape in shapes.items()}


ENV_IDS = ["IMPACT/Hammer-v1", "IMPACT/Dumbbell-v1", "IMPACT/Calligraphy-v1",
           "IMPACT/Disturbance-v1"]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_an_image_mode_observation_names_the_missing_entries(env_id: str) -> None:
    """'rgb' keeps the robot's entries and Calligraphy's goal_pos, drops the object pose."""
    obs = _batch({**ROBOT, **IMAGE, **({"goal_pos": (3,)} if "Calli" in env_id else {})})
    expert = make_expert(env_id)
    expert.reset(1)
    with pytest.raises(InvalidArgumentError) as info:
        expert.act(obs)
    message = str(info.value)
    assert "needs the state observation entries" in message and "object_pos" in message
    assert "obs_mode='state') or 'state+rgb'" in message and "\n" not in message


@pytest.mark.parametrize("compensation", ["none", "closed_loop", "privileged"])
def test_every_compensation_mode_checks(compensation: str) -> None:
    expert = make_expert("IMPACT/Hammer-v1", compensation=compensation)
    expert.reset(2, np.ones(2))
    with pytest.raises(InvalidArgumentError, match="object_rot6d"):
        expert.act(_batch({**ROBOT, **IMAGE}, 2))


# name: (observation, part of the one-line message)
MALFORMED = {
    "not a dict": (np.zeros((1, 10)), "takes the env's Dict observation batched"),
    "a list of dicts": ([{}], "not list"),
    "unbatched": ({k: np.zeros(s) for k, s in {**ROBOT, "object_pos": (3,), "object_rot6d":
                                                (6,), "goal_pos": (3,)}.items()},
                  "has shape (3,); valid: a batch of reset(n_envs)'s 1 rows"),
    "batch of two after reset(1)": (_batch({**ROBOT, "object_pos": (3,), "object_rot6d": (6,),
                                            "goal_pos": (3,)}, 2), "has shape (2, 3)"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_malformed_observations_are_one_line(case: str) -> None:
    obs, message = MALFORMED[case]
    expert = make_expert("IMPACT/Dumbbell-v1")
    expert.reset(1)
    with pytest.raises(InvalidArgumentError) as info:
        expert.act(obs)
    assert message in str(info.value)


def test_a_real_rgb_observation_and_a_state_rgb_one() -> None:
    """The issue's case on the env itself, and the mode that does work for an expert."""
    env = gym.make("IMPACT/Hammer-v1", observation={"obs_mode": "rgb", "cameras": ["wrist"],
                                                    "image_width": 16, "image_height": 16})
    expert = make_expert("IMPACT/Hammer-v1")
    try:
        obs, _ = env.reset(seed=3)
        expert.reset(1)
        with pytest.raises(InvalidArgumentError, match="object_pos, object_rot6d, goal_pos"):
            expert.act(stack_obs([obs]))
    finally:
        env.close()
    state_rgb = {**_batch({**ROBOT, "object_pos": (3,), "object_rot6d": (6,),
                           "goal_pos": (3,)}), **_batch(IMAGE)}
    state_rgb["object_rot6d"][0] = [1, 0, 0, 0, 1, 0]
    state_rgb["ee_rot6d"][0] = [1, 0, 0, 0, -1, 0]
    expert.reset(1)
    assert expert.act(state_rgb).shape == (1, 10)
