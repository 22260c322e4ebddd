"""``impact-export-lerobot``: a demonstration store (state or images) as a LeRobot v3.0 dataset.

Usage::

    impact-export-lerobot --data data/hammer_rgb.zarr --out exports/hammer_rgb

Written from the documented v3.0 layout (docs/lerobot.md): ``meta/info.json``,
``meta/stats.json``, ``meta/tasks.parquet``, ``meta/episodes/chunk-000/file-000.parquet``,
``data/chunk-CCC/file-FFF.parquet`` (one row per frame) and, for each camera,
``videos/observation.images.<camera>/chunk-CCC/file-FFF.mp4`` (episodes one after another).
The store is checked in full first (every chunk against the checksum written with it); the
export is written to ``OUT.partial`` and renamed to ``OUT`` when complete.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import zarr

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_learn.dataset import ACTION_KEY, checked_layout
from impact_learn.lerobot_video import VideoOptions
from impact_learn.store_check import scan_store

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


def main(argv: list[str] | None = None) -> None:
    """Entry point of ``impact-export-lerobot``; bad input exits 2 with a one-line message."""
    parser = OneLineParser(prog="impact-export-lerobot",
                           description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="impact-collect store (*.zarr)")
    parser.add_argument("--out", required=True, help="dataset folder to create")
    parser.add_argument("--task", help="task text of every frame (default: the env id)")
    parser.add_argument("--crf", type=int, default=18, help="x264 quality, 0-51 (lower: better)")
    parser.add_argument("--gop", type=int, default=2, help="frames between keyframes")
    parser.add_argument("--episodes-per-file", type=int, default=1000,
                        help="episodes per parquet / MP4 file")
    args = parser.parse_args(argv)
    try:
        cfg = ExportConfig(args.data, args.out, args.task, args.episodes_per_file,
                           VideoOptions(crf=args.crf, gop_frames=args.gop))
        summary = export_lerobot(cfg)
    except ImpactError as exc:
        parser.exit(2, f"impact-export-lerobot: error: {exc}\n")
    print(json.dumps(summary))


def export_lerobot(cfg: ExportConfig) -> dict[str, Any]:
    """Write the dataset; returns a summary (episodes, frames, features, skipped arrays).

    The store is checked in full first (``store_check``: layout, finite states and actions,
    every chunk against its checksum) and the frame sizes before anything is written; the
    files go to ``OUT.partial``, created here and removed on any failure, then renamed to
    ``OUT``. An existing ``OUT`` or ``OUT.partial`` is refused, never removed."""
    from impact_learn.lerobot_write import write_dataset

    final, work = Path(cfg.out), Path(f"{cfg.out}.partial")
    for path in (final, work):
        if path.exists() or path.is_symlink():
            raise InvalidArgumentError(f"{path} exists; remove it or give another --out")
    layout = checked_layout(cfg.data)
    scan_store(layout, cfg.data, load=False)
    _check_frame_sizes(layout.root["data"])
    created = _make_folder(work)
    try:
        summary = write_dataset(layout.root, work, cfg)
        os.replace(work, final)
    except BaseException as exc:
        for folder in created:
            shutil.rmtree(folder, ignore_errors=True)
        if isinstance(exc, OSError):
            raise InvalidArgumentError(f"cannot write {work}: {exc.strerror or exc}; valid: "
                                       "an --out in a writable folder") from None
        raise
    return summary


def _make_folder(work: Path) -> list[Path]:
    """Create ``work`` and its missing parents; returns them, outermost first (what a failed
    export removes). A location that cannot be written is a one-line error."""
    missing = [p for p in (work, *work.parents) if not p.exists()][::-1]
    try:
        work.mkdir(parents=True)
    except OSError as exc:
        for folder in reversed(missing):
            if folder.is_dir():
                folder.rmdir()
        raise InvalidArgumentError(f"cannot create {work}: {exc.strerror or exc}; valid: an "
                                   "--out in a writable folder") from None
    return missing[:1]


def _check_frame_sizes(data: zarr.Group) -> None:
    """yuv420p video needs even frame sizes: refused before anything is written."""
    for key, arr in sorted(data.arrays()):
        if arr.ndim == 4 and key.endswith("_rgb") and (arr.shape[1] % 2 or arr.shape[2] % 2):
            raise InvalidArgumentError(
                f"cannot encode data/{key}'s {arr.shape[2]}x{arr.shape[1]} frames as yuv420p "
                "video; valid: even sizes")


if __name__ == "__main__":
    main()


