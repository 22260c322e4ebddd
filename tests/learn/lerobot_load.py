"""Load a LeRobot export with lerobot's own ``LeRobotDataset`` and dump what it returns.

Run by the LeRobot virtualenv's Python (``tests/learn/lerobot_venv.sh``, which also installs this
package; docs/lerobot.md), not by the project's::

    LEROBOT_PYTHON tests/learn/lerobot_load.py DATASET_DIR OUT.npz

It writes ``OUT.npz`` holding ``num_frames``, ``num_episodes``, ``episode_lengths`` (from
lerobot's episode metadata), the whole ``action`` and ``index`` columns, and, for a few frames
read through ``dataset[i]`` (parquet row plus decoded video frames), ``item_index``,
``item_action``, ``item_state`` and ``item_<camera>`` (C, H, W) float in [0, 1].
"""

from __future__ import annotations

import sys

import numpy as np

from impact_learn.lerobot_compat import define_missing_torchvision_ops


def main(root: str, out: str) -> None:
    define_missing_torchvision_ops()
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
