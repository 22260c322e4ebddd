"""get_state / set_state, deepcopy and pickle of every IMPACT env."""

from __future__ import annotations

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_control.policy import stack_obs
from impact_control.presets import preset_config
from impact_envs import ENV_IDS
from impact_envs.policies.experts import make_expert


def _flat(obs: dict, reward: float, info: dict) -> np.ndarray:
    return np.concatenate([*(np.ravel(obs[k]) for k in sorted(obs)), info["tau_nm"],
                           info["wrench_pred_world"], [reward, info["energy_j"]]])


def _rollout(env, actions) -> np.ndarray:
    rows = []
    for a in actions:
        obs, reward, _, _, info = env.step(a)
        rows.append(_flat(obs, reward, info))
    return np.array(rows)


def _expert_actions(env_id: str, n: int, seed: int = 4) -> tuple[gym.Env, list]:
    """An env after ``n`` expert steps (mid-episode, the internal model learning) and the
    expert's next 40 actions computed on a throwaway copy of the trajectory."""
    env = gym.make(env_id, controller="impact")
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    for _ in range(n):
        obs, *_ = env.step(expert.act(stack_obs([obs]))[0])
    scout = gym.make(env_id, controller="impact").unwrapped
    scout.set_state(env.unwrapped.get_state())
    actions, o = [], obs
    for _ in range(40):
        a = expert.act(stack_obs([o]))[0]
        actions.append(a)
        o, *_ = scout.step(a)
    return env, actions


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_set_state_reproduces_a_trajectory_bit_for_bit(env_id):
    env, actions = _expert_actions(env_id, 120)
    env = env.unwrapped
    state = env.get_state()
    first = _rollout(env, actions)
    env.set_state(state)
    np.testing.assert_array_equal(_rollout(env, actions), first)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_deepcopy_and_pickle_step_identically(env_id):
    env, actions = _expert_actions(env_id, 90)
    base = env.unwrapped
    wrapped = copy.deepcopy(env)  # gym.make's wrappers (time limit, order check) included
    copies = [copy.deepcopy(base), pickle.loads(pickle.dumps(base))]
    reference = _rollout(base, actions)
    for c in [*copies, wrapped]:
        np.testing.assert_array_equal(_rollout(c, actions), reference)


def _cut_weight(state):
    name = next(iter(state.weights))
    state.weights[name] = state.weights[name][:1].copy()


def _cut_array(state):
    state.arrays["controller.tick.buffer"] = state.arrays["controller.tick.buffer"][:-1]


def _drop_array(state):
    del state.arrays["controller.est.buffer"]


def _float32_array(state):
    name = "controller.imp.buffer"
    state.arrays[name] = state.arrays[name].astype(np.float32)


def _no_identity(state):
    del state.identity


def _not_a_generator(state):
    state.rng = 7


# name: (maker of the env the state comes from, damage to the state, message part)
BAD_STATES = {
    "another task": (lambda: gym.make("IMPACT/Dumbbell-v1"), None, "task"),
    "impedance env": (lambda: gym.make("IMPACT/Hammer-v1", controller="impedance"), None,
                      "controller"),
    "paper preset": (lambda: gym.make("IMPACT/Hammer-v1", controller_preset="paper"), None,
                     "preset"),
    "momentum estimator": (lambda: gym.make(
        "IMPACT/Hammer-v1", controller_preset=preset_config("default", estimator="momentum")),
        None, "config differ"),
    "weight cut to one row": (None, _cut_weight, "weight"),
    "array cut short": (None, _cut_array, "array controller"),
    "array missing": (None, _drop_array, "array names differ"),
    "array of another dtype": (None, _float32_array, "float32"),
    "no identity": (None, _no_identity, "another env"),
    "rng not a generator": (None, _not_a_generator, "rng is not a numpy Generator"),
    "not a state": (None, "text", "set_state needs an EnvState"),
}


@pytest.mark.parametrize("case", sorted(BAD_STATES))
def test_a_foreign_or_damaged_state_is_refused_and_changes_nothing(case):
    make_source, damage, message = BAD_STATES[case]
    env = gym.make("IMPACT/Hammer-v1")
    env.reset(seed=3)
    for _ in range(5):
        env.step(env.action_space.sample() * 0 + env.unwrapped.action_space.low)
    source = (make_source or (lambda: gym.make("IMPACT/Hammer-v1")))()
    source.reset(seed=8)
    state = source.unwrapped.get_state()
    if callable(damage):
        damage(state)
    elif damage is not None:
        state = damage
    before = env.unwrapped.get_state()
    with pytest.raises(InvalidArgumentError) as err:
        env.unwrapped.set_state(state)
    assert message in str(err.value) and "\n" not in str(err.value)
    after = env.unwrapped.get_state()
    assert all(np.array_equal(before.arrays[k], after.arrays[k]) for k in before.arrays)
    for name in ("body_mass", "body_pos", "body_inertia", "geom_size"):
        assert np.array_equal(getattr(before.model, name), getattr(after.model, name))
    assert np.array_equal(before.data.qpos, after.data.qpos)


def _stage_objects(ctrl: object) -> list[tuple[str, object]]:
    """The controller and every object of impact_control it holds, two levels deep."""
    found, todo = [("controller", ctrl)], [("controller", ctrl)]
    while todo:
        path, obj = todo.pop()
        for name, value in vars(obj).items():
            if type(value).__module__.startswith("impact_control") and hasattr(
                    value, "__dict__") and path.count(".") < 2:
                found.append((f"{path}.{name}", value))
                todo.append((f"{path}.{name}", value))
    return found


def _hidden_arrays(ctrl: object) -> list[str]:
    """Arrays of the controller's stages outside its named state and not declared
    ``STATELESS`` by their class."""
    live = list(ctrl.state_arrays().values())
    return [f"{path}.{name}" for path, obj in _stage_objects(ctrl)
            for name, value in vars(obj).items()
            if isinstance(value, np.ndarray) and value.size
            and name not in getattr(type(obj), "STATELESS", ())
            and not any(np.shares_memory(value, a) for a in live)]


@pytest.mark.parametrize("preset", ["default", "paper"])
def test_every_array_a_stage_keeps_is_in_the_snapshot_or_declared_stateless(preset):
    """A stage that keeps state outside ``kernels.ControllerState`` fails here, not silently
    in get_state / set_state: each of its arrays must share memory with a snapshot array or
    be named in its class's ``STATELESS``."""
    env = gym.make("IMPACT/Hammer-v1", controller="impact", controller_preset=preset)
    hidden = _hidden_arrays(env.unwrapped.controller)
    assert not hidden, f"arrays outside the controller's named state: {hidden}"
    env.close()


def test_a_stage_added_without_its_state_is_caught():
    """Negative control: a second slow filter hung on the controller but not wired into
    ``kernel_state()`` is reported by the check above."""
    from impact_control.slow_filter import SlowWrenchFilter

    env = gym.make("IMPACT/Hammer-v1", controller="impact")
    ctrl = env.unwrapped.controller
    ctrl.extra_filter = SlowWrenchFilter(ctrl.config.slow_wrench, ctrl.config.dt_s)
    assert any(h.startswith("controller.extra_filter.") for h in _hidden_arrays(ctrl))
    env.close()
