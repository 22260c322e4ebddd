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
from pathlib import Path
from typing import Any

import zarr

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_learn.dataset import checked_layout
from impact_learn.lerobot_layout import (  # noqa: F401 - the layout's names, re-exported
    ACTION_NAMES,
    CHUNKS_SIZE,
    CODEBASE_VERSION,
    DATA_PATH,
    ENV_STATE_FEATURE,
    EPISODES_PATH,
    IMAGE_FEATURE_PREFIX,
    INDEX_FEATURES,
    STATE_FEATURE,
    VIDEO_PATH,
    EnvEntries,
    ExportConfig,
    Layout,
    entry_names,
    env_entries,
    features,
    layout_of,
    plan_layout,
)
from impact_learn.lerobot_video import VideoOptions
from impact_learn.lerobot_write import write_dataset
from impact_learn.store_check import scan_store


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


