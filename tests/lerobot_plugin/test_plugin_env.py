"""The wrapped envs (``gym_impact/<task>``) on real steps, without LeRobot: LeRobot's keys
rebuilt from our own observation through the features' names, the Box action space, a
scalar ``info`` with ``is_success``, the mass settings, and the same vectors as the export
of a store recorded from the same steps."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.bins import draw_in_bin
from impact_learn.dataset import EpisodeMeta, ReplayWriter
from impact_lerobot import TASKS, PluginSettings, make_lerobot_env, observation_plan
from impact_lerobot.env import scalar_info

SEED, STEPS = 3, 2


def _actions(env: gym.Env, n: int) -> list[np.ndarray]:
    env.action_space.seed(SEED)
    return [env.action_space.sample() for _ in range(n)]


def _ours(settings: PluginSettings, actions: list[np.ndarray]) -> list[dict[str, np.ndarray]]:
    """Our env's own observations for the same seed and actions (reset, then each step)."""
    env = gym.make(settings.env_id, controller=settings.controller,
                   observation=settings.observation, terminate_on_success=True)
    obs = [env.reset(seed=SEED)[0]]
    obs += [env.step(a)[0] for a in actions]
    env.close()
    return obs


def _rebuilt(settings: PluginSettings, ours: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """LeRobot's vectors from our observation through the features' names (``ee_pos.1`` is
    ``ours["ee_pos"][1]``): an independent path from the wrapper's concatenation."""
    out = {}
    for f in observation_plan(settings).features():
        if f.kind in ("STATE", "ENV"):
            out[f.env_key] = np.array([ours[n.rsplit(".", 1)[0]][int(n.rsplit(".", 1)[1])]
                                       for n in f.names], dtype=np.float32)
    return out


@pytest.mark.parametrize("task", TASKS)
def test_every_task_steps_with_lerobot_keys(task: str) -> None:
    settings = PluginSettings(task=task, controller="impedance", episode_length=STEPS)
    env = gym.make(settings.gym_id, settings=settings, max_episode_steps=settings.steps)
    inner = gym.make(settings.env_id)
    assert env.action_space == inner.action_space and env.action_space.shape == (10,)
    assert isinstance(env.action_space, gym.spaces.Box)
    inner.close()
    actions = _actions(env, STEPS)
    got = [env.reset(seed=SEED)]
    got += [env.step(a) for a in actions]
    env.close()
    for (obs, *_, info), ours in zip(got, _ours(settings, actions), strict=True):
        assert set(obs) == {"agent_pos", "environment_state"}
        assert env.observation_space.contains(obs)
        for key, values in _rebuilt(settings, ours).items():
            np.testing.assert_array_equal(obs[key], values)
        assert isinstance(info["is_success"], bool)
        assert info == scalar_info(info) and info["controller_preset"] == "default"
    assert [s[2] for s in got[1:]] == [False] * STEPS  # not terminated (no success here)
    assert [s[3] for s in got[1:]] == [False] * (STEPS - 1) + [True]  # the episode length


def test_image_mode_gives_pixels_per_camera() -> None:
    settings = PluginSettings(obs_mode="rgb", cameras=("wrist", "overview"), image_width=32,
                              image_height=24, episode_length=STEPS)
    env = make_lerobot_env("Hammer-v2", settings)
    obs, _ = env.reset(seed=SEED)
    ours = _ours(settings, [])[0]
    assert set(obs) == {"agent_pos", "pixels"} and list(obs["pixels"]) == ["overview", "wrist"]
    for camera, image in obs["pixels"].items():
        assert image.dtype == np.uint8 and image.shape == (24, 32, 3)
        np.testing.assert_array_equal(image, ours[f"{camera}_rgb"])
    np.testing.assert_array_equal(obs["agent_pos"], _rebuilt(settings, ours)["agent_pos"])
    assert env.observation_space.contains(obs)
    env.close()


def test_fixed_mass_and_mass_bin() -> None:
    fixed = make_lerobot_env("Calligraphy-v1", PluginSettings(task="Calligraphy-v1",
                                                              object_mass=0.7))
    assert fixed.reset(seed=SEED)[1]["tool_mass"] == 0.7
    fixed.close()
    binned = make_lerobot_env("Hammer-v2", PluginSettings(mass_bin=(1.0, 2.0)))
    masses = [binned.reset(seed=s)[1]["object_mass"] for s in (5, 6, 5)]
    assert masses == [draw_in_bin(1.0, 2.0, s) for s in (5, 6, 5)]  # impact-eval's draw
    assert masses[0] != masses[1] and all(1.0 <= m < 2.0 for m in masses)
    unseeded = binned.reset()[1]["object_mass"]
    assert 1.0 <= unseeded < 2.0
    binned.close()


def test_settings_of_another_task_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="valid: a PluginSettings with task="):
        gym.make("gym_impact/Dumbbell-v1", settings=PluginSettings())


def test_vectors_equal_the_export_of_the_same_steps(tmp_path) -> None:
    """A store recorded from our env's steps, exported: its parquet rows and feature names are
    the wrapper's observations and the plugin's features."""
    pq = pytest.importorskip("pyarrow.parquet")
    from impact_learn.lerobot_export import ExportConfig, export_lerobot

    settings = PluginSettings(task="HammerBasket-v1", episode_length=STEPS)
    env = make_lerobot_env(settings.task, settings)
    actions = _actions(env, STEPS + 1)
    plugin = [env.reset(seed=SEED)[0]] + [env.step(a)[0] for a in actions[:STEPS]]
    env.close()
    ours = _ours(settings, actions[:STEPS])
    dims = {k: v.shape[0] for k, v in ours[0].items()}
    writer = ReplayWriter(tmp_path / "s.zarr", dims, {"env_id": settings.env_id,
                                                     "param_name": "object_mass"})
    writer.append_episode({k: np.stack([o[k] for o in ours]) for k in dims},
                          np.stack(actions), EpisodeMeta(0.1, SEED, False, 0))
    export_lerobot(ExportConfig(str(tmp_path / "s.zarr"), str(tmp_path / "lr")))
    info = json.loads((tmp_path / "lr/meta/info.json").read_text())["features"]
    rows = pq.read_table(tmp_path / "lr/data/chunk-000/file-000.parquet")
    for f in observation_plan(settings).features():
        assert tuple(info[f.policy_key]["names"]) == f.names
        assert tuple(info[f.policy_key]["shape"]) == f.shape
        if f.kind != "ACTION":
            exported = np.stack(rows.column(f.policy_key).to_numpy(zero_copy_only=False))
            np.testing.assert_array_equal(exported, np.stack([o[f.env_key] for o in plugin]))
