"""get_state / set_state, deepcopy and pickle of every IMPACT env."""

from __future__ import annotations

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest

from impact_envs import ENV_IDS
from impact_envs.policies.experts import make_expert
from impact_envs.policies.interface import stack_obs


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
