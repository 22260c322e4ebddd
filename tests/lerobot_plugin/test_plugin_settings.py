"""``impact_lerobot``'s settings and feature mapping, without LeRobot: the fields, their
one-line refusals naming the valid choices, and the features each observation mode gives."""

from __future__ import annotations

import pytest
from gymnasium.envs.registration import registry

from impact_control.errors import InvalidArgumentError
from impact_envs import ENV_IDS, REGISTERED_IDS
from impact_envs.tasks.registry import task_class
from impact_learn.lerobot_export import ACTION_NAMES
from impact_lerobot import GYM_IDS, OBS_MODES, TASKS, PluginSettings, observation_plan
from impact_lerobot.settings import mass_param

ROBOT_NAMES = ([f"ee_pos.{i}" for i in range(3)] + [f"ee_rot6d.{i}" for i in range(6)])


def test_tasks_and_gym_ids_cover_every_registered_env() -> None:
    # every registered version (the kept -v1 tables ran gym_impact/Hammer-v1)
    assert tuple(env_id.removeprefix("IMPACT/") for env_id in REGISTERED_IDS) == TASKS
    assert set(ENV_IDS) < set(REGISTERED_IDS)
    assert tuple(f"gym_impact/{task}" for task in TASKS) == GYM_IDS
    for gym_id, env_id in zip(GYM_IDS, REGISTERED_IDS, strict=True):
        assert registry[gym_id].max_episode_steps == registry[env_id].max_episode_steps
        assert registry[gym_id].kwargs == {"task": gym_id.split("/")[1]}


def test_defaults() -> None:
    s = PluginSettings()
    assert (s.task, s.controller, s.controller_preset, s.obs_mode) == (
        "Hammer-v2", "impact", "default", "state")
    assert s.object_mass is None and s.mass_bin is None and s.episode_length is None
    assert (s.env_id, s.gym_id, s.steps) == ("IMPACT/Hammer-v2", "gym_impact/Hammer-v2", 750)
    assert PluginSettings(task="HammerBasket-v1", episode_length=40).steps == 40
    assert OBS_MODES == ("state", "rgb", "state+rgb")


@pytest.mark.parametrize(("fields", "valid"), [
    ({"task": "Nail-v0"}, "valid choices: Hammer-v1, Hammer-v2, Dumbbell-v1, Dumbbell-v2, "
                          "Calligraphy-v1, Calligraphy-v2, Disturbance-v1, Disturbance-v2, "
                          "HammerBasket-v1, HammerBasket-v2"),
    ({"controller": "pid"}, "valid choices: impedance, impact"),
    ({"controller_preset": "fast"},
     "valid choices: default, paper, keep_carried, lift_watch, authors_sim, authors_real"),
    ({"obs_mode": "rgbd"}, "valid choices: state, rgb, state+rgb"),
    ({"object_mass": 20.0}, "valid: 0.05 to 12.0 kg"),
    ({"object_mass": 1.0, "mass_bin": (1.0, 2.0)}, "valid: one of them"),
    ({"mass_bin": (2.0, 1.0)}, "lo < hi"),
    ({"mass_bin": (1.0, 2.0, 3.0)}, "two numbers (lo, hi)"),
    ({"mass_bin": (0.01, 1.0)}, "valid: 0.05 to 12.0 kg"),
    ({"task": "Calligraphy-v1", "mass_bin": (0.1, 9.0)}, "tool_mass=9.0 out of range"),
    ({"episode_length": 0}, "valid: an integer from 1 to 750"),
    ({"episode_length": 751}, "valid: an integer from 1 to 750"),
    ({"episode_length": True}, "valid: an integer from 1 to 750"),
    ({"cameras": ()}, "valid: a tuple of distinct camera names"),
    ({"image_width": 0}, "valid: an integer from 1 to 4096 px"),
])
def test_bad_values_are_one_line_errors_naming_the_valid_ones(fields: dict, valid: str) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        PluginSettings(**fields)
    assert valid in str(info.value) and "\n" not in str(info.value)


def test_lists_from_a_command_line_become_tuples() -> None:
    s = PluginSettings(cameras=["wrist"], mass_bin=[1, 2.5])
    assert s.cameras == ("wrist",) and s.mass_bin == (1, 2.5)


@pytest.mark.parametrize(("task", "param"), [
    ("Hammer-v1", "object_mass"), ("Dumbbell-v1", "object_mass"),
    ("Calligraphy-v1", "tool_mass"), ("Disturbance-v1", "object_mass"),
    ("HammerBasket-v1", "object_mass")])
def test_the_mass_parameter_of_each_task(task: str, param: str) -> None:
    assert mass_param(task_class(f"IMPACT/{task}")).name == param


def _features(**fields: object) -> dict[str, tuple]:
    return {f.env_key: (f.policy_key, f.kind, f.shape, f.names)
            for f in observation_plan(PluginSettings(**fields)).features()}


def test_hammer_state_features_follow_the_export() -> None:
    feats = _features()
    assert list(feats) == ["agent_pos", "environment_state", "action"]
    policy_key, kind, shape, names = feats["agent_pos"]
    assert (policy_key, kind, shape) == ("observation.state", "STATE", (24,))
    assert list(names[:9]) == ROBOT_NAMES and names[9] == "gripper_width.0"
    assert feats["environment_state"][:3] == ("observation.environment_state", "ENV", (12,))
    assert [n.rsplit(".", 1)[0] for n in feats["environment_state"][3]] == (
        ["goal_pos"] * 3 + ["object_pos"] * 3 + ["object_rot6d"] * 6)
    assert feats["action"] == ("action", "ACTION", (10,), tuple(ACTION_NAMES))


def test_image_modes_add_cameras_and_rgb_drops_privileged_entries() -> None:
    rgb = _features(obs_mode="rgb", cameras=("wrist", "overview"), image_width=32,
                    image_height=24)
    assert list(rgb) == ["agent_pos", "pixels/overview", "pixels/wrist", "action"]
    assert rgb["agent_pos"][2] == (24,)  # Hammer's task entries are all privileged
    assert rgb["pixels/wrist"] == ("observation.images.wrist", "VISUAL", (24, 32, 3), None)
    both = _features(obs_mode="state+rgb", cameras=("wrist",))
    assert list(both) == ["agent_pos", "environment_state", "pixels/wrist", "action"]
    # Calligraphy's goal is not privileged: it stays in the state in the rgb mode
    callig = _features(task="Calligraphy-v1", obs_mode="rgb", cameras=("overview",))
    assert "goal_pos.0" in callig["agent_pos"][3] and "environment_state" not in callig
