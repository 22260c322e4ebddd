"""The env's option arguments: importable from ``impact_envs``; an instance, a dict of its
fields or (observation only) an ``obs_mode`` string; anything else one line naming the valid
forms; the grasp force checked at construction against the limit the simulator uses."""

from __future__ import annotations

import gymnasium as gym
import pytest

import impact_envs
from impact_control.errors import InvalidArgumentError
from impact_envs import ObservationOptions, RenderOptions, RobotOptions
from impact_envs.envs.arguments import coerce_options
from impact_envs.robot.hand import MAX_GRASP_FORCE_N
from impact_envs.robot.sim import FrankaSim


def test_options_are_importable_from_the_package() -> None:
    from impact_envs.envs import options

    assert impact_envs.ObservationOptions is options.ObservationOptions
    assert impact_envs.RobotOptions is options.RobotOptions
    assert impact_envs.RenderOptions is options.RenderOptions
    assert {"ObservationOptions", "RobotOptions", "RenderOptions"} <= set(impact_envs.__all__)


# name: (argument, value, the options it stands for)
ACCEPTED = {
    "observation None": ("observation", None, ObservationOptions()),
    "observation str": ("observation", "rgb", ObservationOptions(obs_mode="rgb")),
    "observation str rgbd": ("observation", "rgbd", ObservationOptions(obs_mode="rgbd")),
    "observation dict": ("observation", {"obs_mode": "rgb"}, ObservationOptions(obs_mode="rgb")),
    "observation dict, cameras a list": (
        "observation", {"obs_mode": "state+rgb", "cameras": ["wrist"], "image_width": 48},
        ObservationOptions(obs_mode="state+rgb", cameras=("wrist",), image_width=48)),
    "observation instance": ("observation", ObservationOptions(obs_mode="rgbd"),
                             ObservationOptions(obs_mode="rgbd")),
    "robot dict": ("robot", {"grasp_force_n": 40.0, "sensor_noise": False},
                   RobotOptions(grasp_force_n=40.0, sensor_noise=False)),
    "robot empty dict": ("robot", {}, RobotOptions()),
    "render dict": ("render", {"camera": "side", "width": 64}, RenderOptions(camera="side",
                                                                             width=64)),
}


@pytest.mark.parametrize("case", sorted(ACCEPTED))
def test_accepted_forms(case: str) -> None:
    argument, value, expected = ACCEPTED[case]
    assert coerce_options(argument, value, type(expected)) == expected


# name: (argument, value, part of the one-line message)
REFUSED = {
    "observation unknown key": ("observation", {"obs_mod": "rgb"},
                                "invalid observation key(s) 'obs_mod'; valid keys of "
                                "ObservationOptions: obs_mode, cameras"),
    "observation bad mode string": ("observation", "pixels", "invalid obs_mode 'pixels'"),
    "observation bad mode in dict": ("observation", {"obs_mode": "depth"},
                                     "invalid obs_mode 'depth'"),
    "observation a list": ("observation", ["rgb"], "invalid observation ['rgb'] (list)"),
    "observation a number": ("observation", 3, "or a obs_mode string"),
    "observation the class": ("observation", ObservationOptions, "invalid observation"),
    "observation cameras a string": ("observation", {"obs_mode": "rgb", "cameras": "wrist"},
                                     "invalid cameras 'wrist'"),
    "robot a string": ("robot", "noisy", "invalid robot 'noisy' (str); valid: RobotOptions"),
    "robot unknown key": ("robot", {"grip_force": 10}, "valid keys of RobotOptions: "
                                                       "sensor_noise, grasp_force_n"),
    "robot a RenderOptions": ("robot", RenderOptions(), "invalid robot RenderOptions"),
    "robot grasp force too high in a dict": ("robot", {"grasp_force_n": 500.0},
                                             "invalid grasp_force_n 500.0"),
    "render a string": ("render", "side", "invalid render 'side' (str)"),
    "render unknown key": ("render", {"size": 64}, "valid keys of RenderOptions: width, "
                                                   "height, camera"),
    "render an ObservationOptions": ("render", ObservationOptions(), "invalid render"),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refused_forms_are_one_line(case: str) -> None:
    argument, value, message = REFUSED[case]
    cls = {"observation": ObservationOptions, "robot": RobotOptions,
           "render": RenderOptions}[argument]
    with pytest.raises(InvalidArgumentError) as info:
        coerce_options(argument, value, cls)
    assert message in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("kwargs", [
    {"observation": {"obs_mod": "rgb"}},
    {"observation": 1.5},
    {"robot": "fast"},
    {"robot": {"grasp_force_n": 200.0}},
    {"render": ["overview"]},
])
def test_gym_make_refuses_before_building(kwargs: dict) -> None:
    """The env itself refuses (no AttributeError from deep inside the constructor)."""
    with pytest.raises(InvalidArgumentError):
        gym.make("IMPACT/Dumbbell-v1", **kwargs)


def test_gym_make_takes_a_dict_and_a_string() -> None:
    """``observation="rgb"`` and ``robot={...}`` used to raise AttributeError."""
    env = gym.make("IMPACT/Hammer-v1", observation="rgb",
                   robot={"sensor_noise": False, "grasp_force_n": 100})
    try:
        assert env.unwrapped.observation_options == ObservationOptions(obs_mode="rgb")
        assert "overview_rgb" in env.observation_space.spaces
        assert "object_pos" not in env.observation_space.spaces
        forcerange = env.unwrapped.sim.model.actuator_forcerange
        assert forcerange[env.unwrapped.sim.gripper_act][1] == 200.0
    finally:
        env.close()


@pytest.mark.parametrize("force", [0.5, 70.0, MAX_GRASP_FORCE_N])
def test_grasp_forces_within_the_hand_limit(force: float) -> None:
    assert RobotOptions(grasp_force_n=force).grasp_force_n == force


@pytest.mark.parametrize("force", [0.0, 0, 200.0 + 1e-6, 1000.0, -1.0, float("nan"),
                                   float("inf"), True, "70"])
def test_grasp_forces_outside_every_hand_are_one_line_at_construction(force: object) -> None:
    """Without a hand, the options check against the largest hand (the authors' 200 N)."""
    with pytest.raises(InvalidArgumentError, match=r"^invalid grasp_force_n .*at most 200 N"):
        RobotOptions(grasp_force_n=force)


@pytest.mark.parametrize("force", [MAX_GRASP_FORCE_N + 1e-6, 150, 200.0])
def test_grasp_forces_above_the_franka_hand_are_one_line(force: float) -> None:
    """Naming the Franka Hand refuses at construction; leaving the hand to the task refuses
    when a Franka Hand task is built (every task but HammerBasket)."""
    with pytest.raises(InvalidArgumentError, match=r"^invalid grasp_force_n .*at most 140 N"):
        RobotOptions(grasp_force_n=force, hand="franka_hand")
    with pytest.raises(InvalidArgumentError, match=r"^invalid grasp_force_n .*at most 140 N"):
        gym.make("IMPACT/Hammer-v1", robot=RobotOptions(grasp_force_n=force))


def test_no_grasp_force_means_the_hands_default() -> None:
    assert RobotOptions().grasp("franka_hand") == ("franka_hand", 70.0)
    assert RobotOptions().grasp("authors_sim") == ("authors_sim", 200.0)
    assert RobotOptions(hand="franka_hand").grasp("authors_sim") == ("franka_hand", 70.0)
    with pytest.raises(InvalidArgumentError, match=r"^invalid hand 'paw'.*franka_hand"):
        RobotOptions(hand="paw")


@pytest.mark.parametrize("force", [0.0, 141.0, 200.0])
def test_the_simulator_uses_the_same_limit(force: float) -> None:
    """RobotOptions and FrankaSim share MAX_GRASP_FORCE_N: what one accepts the other does."""
    with pytest.raises(InvalidArgumentError, match=r"^invalid grasp_force_n"):
        FrankaSim("hammer_scene.xml", ("hammer",), grasp_force_n=force)
    sim = FrankaSim("hammer_scene.xml", ("hammer",), grasp_force_n=MAX_GRASP_FORCE_N)
    assert sim.model.actuator_forcerange[sim.gripper_act][1] == 2.0 * MAX_GRASP_FORCE_N
