"""The LeRobot v3.0 layout of an export: file paths, feature names, what each store entry
becomes (``Layout``), and the export's options (``ExportConfig``); docs/lerobot.md."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import zarr

from impact_control.errors import InvalidArgumentError
from impact_learn.dataset import ACTION_KEY
from impact_learn.lerobot_video import VideoOptions

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000
"""Files per ``chunk-CCC`` folder."""
CHUNK_FILE = "chunk-{chunk_index:03d}/file-{file_index:03d}"
DATA_PATH = f"data/{CHUNK_FILE}.parquet"
VIDEO_PATH = f"videos/{{video_key}}/{CHUNK_FILE}.mp4"
EPISODES_PATH = f"meta/episodes/{CHUNK_FILE}.parquet"
ACTION_NAMES = ["x", "y", "z", *(f"rot6d_{i}" for i in range(6)), "gripper"]
INDEX_FEATURES = ("timestamp", "frame_index", "episode_index", "index", "task_index")
STATE_FEATURE = "observation.state"
ENV_STATE_FEATURE = "observation.environment_state"
IMAGE_FEATURE_PREFIX = "observation.images."
"""A camera's feature is this prefix and the camera name (``observation.images.wrist``)."""


@dataclass(frozen=True)
class ExportConfig:
    """What to export and how.

    Attributes:
        data: The ``impact-collect`` store.
        out: The dataset folder to create (must not exist).
        task: The task text of every frame (None: the store's env id).
        episodes_per_file: Episodes per data parquet file and per MP4 file.
        video: MP4 encoding options (``fps`` is the env's 30 Hz policy rate).
    """

    data: str
    out: str
    task: str | None = None
    episodes_per_file: int = 1000
    video: VideoOptions = field(default_factory=VideoOptions)

    def __post_init__(self) -> None:
        if self.episodes_per_file < 1:
            raise InvalidArgumentError(
                f"--episodes-per-file must be >= 1, got {self.episodes_per_file}")


@dataclass(frozen=True)
class Layout:
    """Which store arrays become which LeRobot feature.

    Attributes:
        state_keys: Concatenated into ``observation.state`` (the robot's own entries and the
            task's non-privileged ones).
        env_keys: Concatenated into ``observation.environment_state`` (the task's privileged
            entries: object pose, goal; only in state and ``state+rgb`` stores).
        cameras: ``{feature name: store key}`` of the RGB cameras.
        skipped: Store arrays not exported (depth images).
    """

    state_keys: tuple[str, ...]
    env_keys: tuple[str, ...]
    cameras: dict[str, str]
    skipped: tuple[str, ...]

    def vectors(self) -> tuple[tuple[str, tuple[str, ...]], ...]:
        """``(feature, keys)`` of the vector features that have entries, in feature order
        (``observation.state``, then ``observation.environment_state``)."""
        pairs = ((STATE_FEATURE, self.state_keys), (ENV_STATE_FEATURE, self.env_keys))
        return tuple((name, keys) for name, keys in pairs if keys)


@dataclass(frozen=True)
class EnvEntries:
    """An env's state observation entries (all empty when the env cannot be made).

    Attributes:
        order: Entry names in the env's observation order.
        sizes: Values per entry.
        hidden: The task's privileged entries (``Task.privileged_observations``).
    """

    order: tuple[str, ...]
    sizes: dict[str, int]
    hidden: tuple[str, ...]


def env_entries(env_id: str) -> EnvEntries:
    """The state observation entries of ``env_id`` (made once, in ``"state"`` mode)."""
    import gymnasium as gym

    from impact_envs.envs.pixels import privileged_keys

    try:
        env = gym.make(env_id)
    except gym.error.Error:
        return EnvEntries((), {}, ())
    try:
        task = getattr(env.unwrapped, "task", None)
        hidden = privileged_keys(task) if task is not None else ()
        spaces = env.observation_space.spaces
        return EnvEntries(tuple(spaces), {k: int(s.shape[0]) for k, s in spaces.items()},
                          hidden)
    finally:
        env.close()


def layout_of(frame_ranks: Mapping[str, int], order: Sequence[str],
              hidden: Collection[str]) -> Layout:
    """The ``Layout`` of observation entries with ``frame_ranks`` (dimensions of one frame:
    1 for a vector, 3 for an image); vectors in ``order`` (then by name), cameras
    (``<camera>_rgb``) by name, other images skipped, ``hidden`` vectors as environment
    state."""
    rank = {k: i for i, k in enumerate(order)}
    keys = sorted(frame_ranks, key=lambda k: (rank.get(k, len(rank)), k))
    state, env, cameras, skipped = [], [], {}, []
    for key in keys:
        if frame_ranks[key] == 3 and key.endswith("_rgb"):
            cameras[f"{IMAGE_FEATURE_PREFIX}{key[:-4]}"] = key
        elif frame_ranks[key] == 3:
            skipped.append(key)
        else:
            (env if key in hidden else state).append(key)
    return Layout(tuple(state), tuple(env), cameras, tuple(skipped))


def plan_layout(data: zarr.Group, env_id: str) -> Layout:
    """The ``Layout`` of a store's ``data`` group; vectors in the env's observation order
    (then by name: zarr lists arrays in no fixed order), cameras by name."""
    entries = env_entries(env_id)
    ranks = {k: arr.ndim - 1 for k, arr in data.arrays() if k != ACTION_KEY}
    return layout_of(ranks, entries.order, entries.hidden)


def entry_names(sizes: Mapping[str, int], keys: Sequence[str]) -> list[str]:
    """Names of the values of ``keys`` concatenated: ``ee_pos.0``, ``ee_pos.1``, ..."""
    return [f"{k}.{i}" for k in keys for i in range(sizes[k])]


def features(data: zarr.Group, layout: Layout, video: VideoOptions) -> dict[str, Any]:
    """``info.json``'s ``features``: vectors, cameras, the action and the index columns."""
    feats: dict[str, Any] = {}
    for name, keys in layout.vectors():
        names = entry_names({k: data[k].shape[1] for k in keys}, keys)
        feats[name] = {"dtype": "float32", "shape": [len(names)], "names": names}
    for name, key in layout.cameras.items():
        h, w, c = data[key].shape[1:]
        feats[name] = {"dtype": "video", "shape": [h, w, c],
                       "names": ["height", "width", "channels"],
                       "info": {"video.height": h, "video.width": w, "video.codec": "h264",
                                "video.pix_fmt": "yuv420p", "video.is_depth_map": False,
                                "video.fps": video.fps, "video.channels": c,
                                "video.crf": video.crf, "video.g": video.gop_frames,
                                "has_audio": False}}
    feats["action"] = {"dtype": "float32", "shape": [10], "names": ACTION_NAMES}
    for name in INDEX_FEATURES:
        feats[name] = {"dtype": "float32" if name == "timestamp" else "int64", "shape": [1],
                       "names": None}
    return feats
