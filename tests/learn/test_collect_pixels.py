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
