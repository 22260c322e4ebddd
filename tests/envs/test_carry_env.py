"""``ImpactEnv.carry_controller``: an episode that starts with the controller state the previous
one left (the authors' benchmark, controller activated once per bin; docs/eval.md, "Carried
controller state")."""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_control.policy import stack_obs
from impact_envs.envs.carry import ControllerCarry, episode_views
from impact_envs.envs.options import RobotOptions
from impact_envs.policies.experts import make_expert

ENV_ID = "IMPACT/Hammer-v1"
MASS = {"object_mass": 2.5}
STEPS = 110  # the scripted expert has lifted the 2.5 kg hammer for about 0.7 s: a hold


SCRATCH = ("tick.buffer", "sf.buffer", "imp.buffer")
"""Buffers that also hold per-tick scratch and outputs (written before they are read), which
``controller.reset`` leaves as they were: a used env's differ from a new env's there."""


def _env() -> gym.Env:
    return gym.make(ENV_ID, controller_preset="authors_sim",
                    robot=RobotOptions(torque_reading="commanded"))


def _arrays(env: gym.Env) -> dict[str, np.ndarray]:
    return {k: v.copy() for k, v in env.unwrapped.controller.state_arrays().items()}


def _target_filter(env: gym.Env) -> np.ndarray:
    return episode_views(env.unwrapped.controller)["target_filter"].copy()


@dataclass
class Episode:
    env: gym.Env
    end: dict[str, np.ndarray]
    """The controller's arrays at the end of the first episode."""
    end_info: dict
    carry: ControllerCarry
    """``controller_carry()`` at the end of the first episode."""
    fresh: dict[str, np.ndarray]
    """A new env's controller arrays after ``reset(seed=1)``."""


@pytest.fixture(scope="module")
def episode() -> Episode:
    """STEPS steps of a 2.5 kg Hammer episode under ``authors_sim`` (the payload model holds)."""
    env, expert = _env(), make_expert(ENV_ID)
    obs, _ = env.reset(seed=0, options=MASS)
    expert.reset(1)
    for _ in range(STEPS):
        obs, _, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
    other = _env()
    other.reset(seed=1, options=MASS)
    fresh = _arrays(other)
    other.close()
    yield Episode(env, _arrays(env), info, env.unwrapped.controller_carry(), fresh)
    env.close()


def _tf_slice(env: gym.Env) -> slice:
    """Where the target filter lies in the optional stages' buffer."""
    ctrl = env.unwrapped.controller
    view = episode_views(ctrl)["target_filter"]
    start = (view.__array_interface__["data"][0]
             - ctrl.optional.packed.buffer.__array_interface__["data"][0]) // view.itemsize
    return slice(start, start + view.size)


def test_the_episode_left_a_state_worth_carrying(episode: Episode) -> None:
    pay = episode.env.unwrapped.controller.optional.payload.state
    assert pay.holding[0] == 1.0 and pay.hold_time_s[0] > 0.5
    assert episode.end_info["wrench_slow_world"][2] > 5.0  # the slow filter holds the load
    for name in ("sf.buffer", "lim.buffer", "opt.buffer", "imp.buffer"):  # the observer, the
        assert not np.array_equal(episode.end[name], episode.fresh[name]), name  # payload: opt
    ctrl = episode.env.unwrapped.controller
    for stage in (ctrl.optional.observer, ctrl.optional.payload):  # views of opt.buffer
        assert np.shares_memory(stage.packed.buffer, ctrl.optional.packed.buffer)
    assert np.linalg.norm(ctrl.optional.observer.wrench_world) > 5.0  # authors_sim's observer


def test_a_carried_episode_starts_where_the_last_one_ended(episode: Episode) -> None:
    env, carry = episode.env, episode.carry
    env.unwrapped.carry_controller(carry)
    _, info = env.reset(seed=1, options=MASS)
    start = _arrays(env)
    tf = _tf_slice(env)
    for name, end in episode.end.items():
        now = start[name]
        if name == "opt.buffer":  # everything but the target filter, which starts afresh
            np.testing.assert_array_equal(np.delete(now, np.r_[tf]), np.delete(end, np.r_[tf]))
            np.testing.assert_array_equal(now[tf], episode.fresh[name][tf])
        else:
            np.testing.assert_array_equal(now, end, err_msg=name)
    np.testing.assert_array_equal(info["wrench_slow_world"], episode.end_info["wrench_slow_world"])
    pay = env.unwrapped.controller.optional.payload.state
    assert pay.holding[0] == 1.0  # the payload model still holds, as the authors' does
    # the carry is used once: the next reset without one is the fresh reset state
    env.reset(seed=1, options=MASS)
    now = _arrays(env)
    bad = [name for name, fresh in episode.fresh.items()
           if name not in SCRATCH and not np.array_equal(now[name], fresh)]
    assert bad == []
    ctrl = env.unwrapped.controller
    assert not ctrl.slow_filter.wrench_slow_world.any()
    np.testing.assert_array_equal(ctrl.impedance.q_null, env.unwrapped.sim.data.qpos[:7])
    # and the arrays came back as they were taken: the carry holds copies
    for name, end in episode.end.items():
        np.testing.assert_array_equal(carry.arrays[name], end, err_msg=name)


def test_a_carried_episode_is_deterministic_and_differs_from_a_fresh_one(
        episode: Episode) -> None:
    env, base = episode.env, episode.env.unwrapped

    def first_step(start: ControllerCarry | None) -> dict:
        base.carry_controller(start)
        obs, _ = env.reset(seed=1, options=MASS)
        return env.step(np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]))[4]

    carried, again, fresh = first_step(episode.carry), first_step(episode.carry), first_step(None)
    for key in ("tau_nm", "wrench_slow_world", "wrench_ext_world", "wrench_ff_world"):
        np.testing.assert_array_equal(carried[key], again[key], err_msg=key)
    assert not np.allclose(carried["tau_nm"], fresh["tau_nm"], atol=1e-3)
    assert np.linalg.norm(carried["wrench_slow_world"]) > 5.0 > np.linalg.norm(
        fresh["wrench_slow_world"])


def test_a_pending_carry_is_part_of_the_env_state(episode: Episode) -> None:
    env, base = episode.env, episode.env.unwrapped
    base.carry_controller(episode.carry)
    state = base.get_state()
    base.carry_controller(None)
    base.set_state(state)
    env.reset(seed=1, options=MASS)
    np.testing.assert_array_equal(_arrays(env)["sf.buffer"], episode.end["sf.buffer"])


def test_bad_carries_are_refused_in_one_line(episode: Episode) -> None:
    base = episode.env.unwrapped
    with pytest.raises(InvalidArgumentError, match="needs a ControllerCarry") as err:
        base.carry_controller({"arrays": {}})
    assert "\n" not in str(err.value)
    other = gym.make(ENV_ID)  # default preset, link-side torque reading
    try:
        with pytest.raises(InvalidArgumentError, match="another env .*preset") as err:
            base.carry_controller(other.unwrapped.controller_carry())
        assert "\n" not in str(err.value)
    finally:
        other.close()
    assert base._carry is None  # a refused carry arms nothing
