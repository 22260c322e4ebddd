"""``impact-collect --obs-mode``: image stores (``impact_learn/collect_pixels.py``, ``dataset.py``).

The expert acts on the full state; the store keeps the chosen mode's observation, images
compressed in chunks, and loads like a state store."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_envs.envs.options import ObservationOptions
from impact_learn.collect import collect
from impact_learn.collect_config import CollectConfig
from impact_learn.collect_pixels import CameraView, stored_dims
from impact_learn.dataset import (
    IMAGE_CHUNK_FRAMES,
    EpisodeMeta,
    ImageSpec,
    ReplayWriter,
    load_replay,
)

HAMMER = "IMPACT/Hammer-v1"
SMALL = ObservationOptions(obs_mode="rgb", cameras=("overview", "wrist"), image_width=32,
                           image_height=24, shadows=False)


def test_camera_view_sees_what_the_image_mode_env_sees():
    view = CameraView(gym.make(HAMMER), SMALL)
    env = gym.make(HAMMER, observation=SMALL)
    try:
        a, _ = view.reset(seed=3)
        b, _ = env.reset(seed=3)
        for _ in range(3):
            action = env.action_space.sample()
            a = view.step(action)[0]
            b = env.step(action)[0]
        assert set(view.stored_space.spaces) == set(b) and "object_pos" in a
        assert "object_pos" not in b and "goal_pos" not in b
        for key in b:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
        dims = stored_dims(view)
        assert dims["overview_rgb"] == ImageSpec((24, 32, 3), "uint8") and dims["ee_pos"] == 3
    finally:
        view.close()
        env.close()


def test_camera_view_refuses_an_image_mode_env():
    env = gym.make(HAMMER, observation=SMALL)
    with pytest.raises(InvalidArgumentError, match="made in 'state' mode"):
        CameraView(env, SMALL)
    env.close()


def _collect(out, episodes: int, obs: ObservationOptions = SMALL, **changes) -> int:
    cfg = CollectConfig(env_id=HAMMER, out=str(out), episodes=episodes, param=0.2, n_envs=1,
                        post_success_steps=0, progress=False, observation=obs, **changes)
    return collect(cfg)


def test_rgb_store_holds_the_modes_observation_and_resumes(tmp_path):
    assert _collect(tmp_path / "full.zarr", 2) == 2
    full = load_replay(tmp_path / "full.zarr")
    assert full.attrs["format_version"] == 2
    assert full.attrs["observation"] == {"obs_mode": "rgb", "cameras": ["overview", "wrist"],
                                         "image_width": 32, "image_height": 24,
                                         "shadows": False}
    assert "object_pos" not in full.data and "goal_pos" not in full.data
    n = int(full.episode_ends[-1])
    assert full.data["wrist_rgb"].shape == (n, 24, 32, 3)
    assert full.data["wrist_rgb"].dtype == np.uint8 and full.data["wrist_rgb"].std() > 1
    assert full.data["ee_pos"].shape == (n, 3)
    _collect(tmp_path / "cut.zarr", 1)
    with pytest.raises(InvalidArgumentError, match="collected with observation"):
        _collect(tmp_path / "cut.zarr", 2, obs=ObservationOptions(), resume=True)
    _collect(tmp_path / "cut.zarr", 2, resume=True)
    cut = load_replay(tmp_path / "cut.zarr")
    for key in full.data:
        np.testing.assert_array_equal(cut.data[key], full.data[key], err_msg=key)
    np.testing.assert_array_equal(cut.episode_ends, full.episode_ends)


def _image_episode(length: int, value: int) -> tuple[dict, np.ndarray]:
    obs = {"a": np.full((length, 2), value, np.float32),
           "cam_rgb": np.full((length, 4, 5, 3), value, np.uint8)}
    return obs, np.full((length, 10), value, np.float32)


def test_writer_image_arrays_chunked_truncated_and_checked(tmp_path):
    path, dims = tmp_path / "d.zarr", {"a": 2, "cam_rgb": ImageSpec((4, 5, 3), "uint8")}
    writer = ReplayWriter(path, dims, {"env_id": "X"})
    writer.append_episode(*_image_episode(70, 1), EpisodeMeta(0.2, 1, True, 0))
    arr = writer.root["data/cam_rgb"]
    assert arr.chunks == (IMAGE_CHUNK_FRAMES, 4, 5, 3) and arr.compressors[0].level == 9
    bad = {"a": np.zeros((3, 2)), "cam_rgb": np.zeros((3, 5, 4, 3))}
    with pytest.raises(InvalidArgumentError, match=r"valid: \(4, 5, 3\)"):
        writer.append_episode(bad, np.zeros((3, 10)), EpisodeMeta(0.2, 2, True, 1))
    writer.root["data/cam_rgb"].append(np.full((9, 4, 5, 3), 7, np.uint8))  # crash mid-append
    writer = ReplayWriter(path, dims, {"env_id": "X"}, append=True)
    writer.append_episode(*_image_episode(3, 2), EpisodeMeta(0.2, 3, True, 2))
    replay = load_replay(path)
    assert replay.episode_ends.tolist() == [70, 73]
    assert replay.data["cam_rgb"][:, 0, 0, 0].tolist() == [1] * 70 + [2] * 3


def test_resume_on_a_torn_last_image_chunk_is_one_line(tmp_path):
    path, dims = tmp_path / "d.zarr", {"a": 2, "cam_rgb": ImageSpec((4, 5, 3), "uint8")}
    writer = ReplayWriter(path, dims, {"env_id": "X"})
    writer.append_episode(*_image_episode(70, 1), EpisodeMeta(0.2, 1, True, 0))
    last = sorted(p for p in (path / "data/cam_rgb").rglob("*") if p.is_file()
                  and p.name[0].isdigit())[-1]
    last.write_bytes(b"\x00torn write")
    with pytest.raises(InvalidArgumentError) as err:
        ReplayWriter(path, dims, {"env_id": "X"}, append=True)
    assert "the store is damaged" in str(err.value) and "\n" not in str(err.value)


def _counting_views(n: int) -> tuple[list[CameraView], list[int]]:
    """``n`` Hammer ``CameraView``s (300-step episodes: the expert succeeds in about 200) and
    a one-element list counting their renders."""
    views = [CameraView(gym.make(HAMMER, max_episode_steps=300), SMALL) for _ in range(n)]
    count = [0]
    for view in views:
        render = view.pixels.render

        def counted(data, render=render):
            count[0] += 1
            return render(data)

        view.pixels.render = counted
    return views, count


class _OpenHandSecond:
    """The Hammer expert, except that the second env's hand never closes: its attempt fails."""

    def __init__(self) -> None:
        from impact_envs.policies.experts import make_expert

        self.expert = make_expert(HAMMER)

    def reset(self, n_envs: int, object_mass_kg: np.ndarray) -> None:
        self.expert.reset(n_envs, object_mass_kg=object_mass_kg)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        actions = np.array(self.expert.act(obs), dtype=np.float32)
        if len(actions) > 1:
            actions[1, -1] = 1.0  # the gripper command: open
        return actions


def test_screened_attempts_render_only_the_kept_ones_and_equal_eager_ones():
    """Of two attempts, one succeeds and one fails (its hand stays open): screening renders
    the success alone (its steps + the reset) and returns the same arrays."""
    from impact_learn.collect_run import AttemptSpec, run_attempts, run_screened

    spec = AttemptSpec([11, 12], [0.2, 0.2], "object_mass")
    views, count = _counting_views(2)
    try:
        eager = run_attempts(views, _OpenHandSecond(), spec, 5)
        eager_renders, count[0] = count[0], 0
        screened = run_screened(views, _OpenHandSecond(), spec, 5)
    finally:
        for view in views:
            view.close()
    assert [r.success for r in eager] == [True, False] == [r.success for r in screened]
    assert eager_renders == len(eager[0].actions) + len(eager[1].actions) + 2
    assert count[0] == len(eager[0].actions) + 1  # the kept attempt only
    assert "overview_rgb" not in screened[1].obs  # the failure was never rendered
    assert set(screened[0].obs) == set(eager[0].obs)
    for key, value in eager[0].obs.items():
        np.testing.assert_array_equal(screened[0].obs[key], value, err_msg=key)
    np.testing.assert_array_equal(screened[0].actions, eager[0].actions)


def test_a_kept_attempt_that_does_not_repeat_itself_stops_the_run(monkeypatch):
    from impact_learn import collect_run

    spec = collect_run.AttemptSpec([11], [0.2], "object_mass")
    real, calls = collect_run.run_attempts, []

    def second_run_fails(envs, expert, attempts, post):
        results = real(envs, expert, attempts, post)
        calls.append(1)
        if len(calls) == 2:
            results = [collect_run.EpisodeResult(r.obs, r.actions[:-1], False, r.param)
                       for r in results]
        return results

    monkeypatch.setattr(collect_run, "run_attempts", second_run_fails)
    views, _ = _counting_views(1)
    from impact_envs.policies.experts import make_expert

    try:
        with pytest.raises(collect_run.CollectionError, match="seed 11 succeeded in .* not again"):
            collect_run.run_screened(views, make_expert(HAMMER), spec, 0)
    finally:
        views[0].close()
