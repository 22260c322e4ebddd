"""Load a LeRobot export with lerobot's own ``LeRobotDataset`` and dump what it returns.

Run by the LeRobot virtualenv's Python (docs/lerobot.md), not by the project's::

    LEROBOT_PYTHON tests/learn/lerobot_load.py DATASET_DIR OUT.npz

It writes ``OUT.npz`` holding ``num_frames``, ``num_episodes``, ``episode_lengths`` (from
lerobot's episode metadata), the whole ``action`` and ``index`` columns, and, for a few frames
read through ``dataset[i]`` (parquet row plus decoded video frames), ``item_index``,
``item_action``, ``item_state`` and ``item_<camera>`` (C, H, W) float in [0, 1].
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import torch


def _define_missing_torchvision_ops() -> None:
    """torchvision's PyPI wheel is built against CUDA torch; with the CPU torch its C ops do
    not load and its import fails registering fake kernels for ``nms``/``qnms``. Declare those
    two schemas so the import (of which LeRobot's dataset code needs only transforms) works.
    Nothing here runs when the ops load."""
    import importlib.util

    spec = importlib.util.find_spec("torchvision")
    if spec is None or spec.origin is None:
        return
    try:
        torch.ops.load_library(str(Path(spec.origin).parent / "_C.so"))
    except OSError:
        lib = torch.library.Library("torchvision", "DEF")  # noqa: TOR901
        for op in ("nms", "qnms"):
            lib.define(f"{op}(Tensor dets, Tensor scores, float iou_threshold) -> Tensor")
        _define_missing_torchvision_ops.lib = lib  # keep the library alive


def main(root: str, out: str) -> None:
    _define_missing_torchvision_ops()
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("impact/export-check", root=root)
    lengths = [int(e["length"]) for e in ds.meta.episodes]
    picks = sorted({0, 1, lengths[0] - 1, lengths[0], len(ds) // 2, len(ds) - 1})
    dump = {"num_frames": np.array(len(ds)), "num_episodes": np.array(ds.num_episodes),
            "episode_lengths": np.array(lengths),
            "action": np.stack([np.asarray(a) for a in ds.hf_dataset["action"]]),
            "index": np.asarray(ds.hf_dataset["index"]), "item_index": np.array(picks)}
    items = [ds[i] for i in picks]
    dump["item_action"] = np.stack([it["action"].numpy() for it in items])
    dump["item_state"] = np.stack([it["observation.state"].numpy() for it in items])
    for key in ds.meta.camera_keys:
        dump[f"item_{key}"] = np.stack([it[key].numpy() for it in items])
    np.savez(out, **dump)
    print(f"loaded {len(ds)} frames, {ds.num_episodes} episodes, cameras {ds.meta.camera_keys}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
