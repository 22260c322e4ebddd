"""Writing the LeRobot v3.0 files of ``lerobot_export`` (parquet tables, MP4s, metadata)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import zarr

from impact_learn.dataset import ACTION_KEY
from impact_learn.lerobot_layout import (
    CHUNKS_SIZE,
    CODEBASE_VERSION,
    DATA_PATH,
    EPISODES_PATH,
    VIDEO_PATH,
    ExportConfig,
    Layout,
    features,
    plan_layout,
)
from impact_learn.lerobot_stats import ImageHistogram, vector_stats
from impact_learn.lerobot_video import Mp4Writer


def _pa():  # noqa: ANN202 - pyarrow is an optional dependency
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        from impact_control.errors import InvalidArgumentError

        raise InvalidArgumentError(
            "the LeRobot export needs pyarrow; valid: pip install 'impact-robotics[lerobot]'"
        ) from None
    return pa, pq


def _frame_columns(root: zarr.Group, layout: Layout, ends: np.ndarray,
                   fps: int) -> dict[str, np.ndarray]:
    """Every non-video column of every frame: ``{feature: (N,) or (N, d)}``."""
    data, n = root["data"], int(ends[-1])
    starts = np.concatenate([[0], ends[:-1]])
    episode = np.repeat(np.arange(len(ends)), ends - starts)
    frame = np.arange(n) - starts[episode]
    cols: dict[str, np.ndarray] = {}
    for name, keys in layout.vectors():
        cols[name] = np.concatenate([data[k][:n] for k in keys], 1).astype(np.float32)
    cols["action"] = np.asarray(data[ACTION_KEY][:n], dtype=np.float32)
    cols["timestamp"] = (frame / fps).astype(np.float32)
    cols["frame_index"], cols["episode_index"] = frame.astype(np.int64), episode.astype(np.int64)
    cols["index"], cols["task_index"] = np.arange(n, dtype=np.int64), np.zeros(n, np.int64)
    return cols


def _table(cols: dict[str, np.ndarray], rows: slice) -> Any:
    """A pyarrow table of ``rows``: vectors as fixed-size lists, scalars as plain columns."""
    pa, _ = _pa()
    arrays = {}
    for name, values in cols.items():
        part = values[rows]
        if part.ndim == 2:
            arrays[name] = pa.FixedSizeListArray.from_arrays(pa.array(part.ravel()),
                                                             part.shape[1])
        else:
            arrays[name] = pa.array(part)
    return pa.table(arrays)


def _location(file_number: int) -> dict[str, int]:
    return {"chunk_index": file_number // CHUNKS_SIZE, "file_index": file_number % CHUNKS_SIZE}


def _write_videos(root: zarr.Group, layout: Layout, out: Path, ends: np.ndarray,
                  cfg: ExportConfig, episodes: dict[str, list]) -> dict[str, ImageHistogram]:
    """One MP4 per camera and file of ``episodes_per_file`` episodes; fills the episodes'
    ``videos/...`` columns and returns each camera's histogram."""
    starts, fps = np.concatenate([[0], ends[:-1]]), cfg.video.fps
    hists = {}
    for name, key in layout.cameras.items():
        arr, hist = root[f"data/{key}"], ImageHistogram()
        h, w = arr.shape[1:3]
        for first in range(0, len(ends), cfg.episodes_per_file):
            loc = _location(first // cfg.episodes_per_file)
            writer = Mp4Writer(out / VIDEO_PATH.format(video_key=name, **loc), w, h, cfg.video)
            for ep in range(first, min(first + cfg.episodes_per_file, len(ends))):
                frames = np.asarray(arr[int(starts[ep]):int(ends[ep])])
                begin = writer.frames
                writer.write(frames)
                hist.add(frames)
                for col, value in (("chunk_index", loc["chunk_index"]),
                                   ("file_index", loc["file_index"]),
                                   ("from_timestamp", begin / fps),
                                   ("to_timestamp", writer.frames / fps)):
                    episodes.setdefault(f"videos/{name}/{col}", []).append(value)
            writer.close()
        hists[name] = hist
    return hists


def _episode_table(root: zarr.Group, ends: np.ndarray, task: str, cfg: ExportConfig,
                   videos: dict[str, list]) -> Any:
    pa, _ = _pa()
    n_ep = len(ends)
    starts = np.concatenate([[0], ends[:-1]])
    files = [_location(ep // cfg.episodes_per_file) for ep in range(n_ep)]
    cols: dict[str, Any] = {
        "episode_index": pa.array(np.arange(n_ep, dtype=np.int64)),
        "tasks": pa.array([[task]] * n_ep, type=pa.list_(pa.string())),
        "length": pa.array((ends - starts).astype(np.int64)),
        "data/chunk_index": pa.array([f["chunk_index"] for f in files], type=pa.int64()),
        "data/file_index": pa.array([f["file_index"] for f in files], type=pa.int64()),
        "dataset_from_index": pa.array(starts.astype(np.int64)),
        "dataset_to_index": pa.array(ends.astype(np.int64)),
    }
    for name, values in videos.items():
        kind = pa.float64() if name.endswith("timestamp") else pa.int64()
        cols[name] = pa.array(values, type=kind)
    cols["meta/episodes/chunk_index"] = pa.array(np.zeros(n_ep, np.int64))
    cols["meta/episodes/file_index"] = pa.array(np.zeros(n_ep, np.int64))
    cols["impact/episode_param"] = pa.array(np.asarray(root["meta/episode_param"][:n_ep]))
    cols["impact/episode_seed"] = pa.array(np.asarray(root["meta/episode_seed"][:n_ep]))
    return pa.table(cols)


def write_dataset(root: zarr.Group, out: Path, cfg: ExportConfig) -> dict[str, Any]:
    """Write every file of the dataset under ``out``; returns the export's summary."""
    import pandas as pd

    pa, pq = _pa()
    attrs = dict(root.attrs)
    env_id = str(attrs.get("env_id", "unknown"))
    task = cfg.task or env_id
    ends = np.asarray(root["meta/episode_ends"][:], dtype=np.int64)
    layout = plan_layout(root["data"], env_id)
    feats = features(root["data"], layout, cfg.video)
    cols = _frame_columns(root, layout, ends, cfg.video.fps)
    for first in range(0, len(ends), cfg.episodes_per_file):
        last = min(first + cfg.episodes_per_file, len(ends)) - 1
        rows = slice(int(ends[first - 1]) if first else 0, int(ends[last]))
        path = out / DATA_PATH.format(**_location(first // cfg.episodes_per_file))
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(_table(cols, rows), path)
    videos: dict[str, list] = {}
    hists = _write_videos(root, layout, out, ends, cfg, videos)
    episodes_path = out / EPISODES_PATH.format(chunk_index=0, file_index=0)
    episodes_path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(_episode_table(root, ends, task, cfg, videos), episodes_path)
    pd.DataFrame({"task_index": [0]}, index=pd.Index([task], name="task")).to_parquet(
        out / "meta/tasks.parquet")
    stats = {name: vector_stats(values) for name, values in cols.items()}
    stats.update({name: hist.stats() for name, hist in hists.items()})
    (out / "meta/stats.json").write_text(json.dumps(stats, indent=2))
    info = {"codebase_version": CODEBASE_VERSION, "robot_type": "franka_fr3",
            "total_episodes": len(ends), "total_frames": int(ends[-1]), "total_tasks": 1,
            "chunks_size": CHUNKS_SIZE, "data_files_size_in_mb": 100,
            "video_files_size_in_mb": 200, "fps": cfg.video.fps,
            "splits": {"train": f"0:{len(ends)}"}, "data_path": DATA_PATH,
            "video_path": VIDEO_PATH if layout.cameras else None, "features": feats,
            "impact": {"env_id": env_id, "observation": attrs.get("observation"),
                       "param_name": attrs.get("param_name")}}
    (out / "meta/info.json").write_text(json.dumps(info, indent=4))
    return {"episodes": len(ends), "frames": int(ends[-1]), "features": list(feats),
            "skipped": list(layout.skipped), "out": str(cfg.out)}
