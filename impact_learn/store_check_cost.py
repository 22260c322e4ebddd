"""What the store checks cost (docs/diffusion_policy.md, "Checks of a store").

Usage::

    python -m impact_learn.store_check_cost --data data/hammer_rgb.zarr [--tile 10] [--repeat 3]

Prints one JSON line: the store's frames and bytes, then ``[wall, CPU]`` median seconds of

- ``read``: every array read into memory with zarr alone (what loading cost before the checks);
- ``load_replay``: the same read with every check (what ``impact-train`` pays);
- ``verify``: ``scan_store`` without keeping the data (what ``impact-export-lerobot`` and
  ``impact-collect --resume`` add before they start).

``--tile N`` first writes a store of N copies of ``--data``'s episodes (in a temporary folder,
removed afterwards) and measures that one, with the time the writer spent on checksums.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import zarr

from impact_learn.dataset import EpisodeMeta, ImageSpec, ReplayWriter, checked_layout, load_replay
from impact_learn.store_check import scan_store


def _median_s(fn: Callable[[], Any], repeat: int) -> list[float]:
    """Median wall and CPU seconds (this process, all threads) of ``fn`` over ``repeat`` runs;
    on a shared machine the CPU seconds are the steadier of the two."""
    wall, cpu = [], []
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return [round(statistics.median(wall), 3), round(statistics.median(cpu), 3)]


def _plain_read(path: Path) -> None:
    root = zarr.open_group(str(path), mode="r")
    for group in ("data", "meta"):
        for _, arr in root[group].arrays():
            np.asarray(arr[:])


def tile_store(source: Path, out: Path, copies: int) -> dict[str, float]:
    """Write ``copies`` times the episodes of ``source`` to ``out``; returns the writer's
    seconds in all and those spent on checksums (digests and saving the record)."""
    replay = load_replay(source)
    dims = {k: ImageSpec(v.shape[1:], str(v.dtype)) if v.ndim == 4 else v.shape[1]
            for k, v in replay.data.items() if k != "action"}
    writer = ReplayWriter(out, dims, replay.attrs)
    spent = {"checksums_s": 0.0}
    extend, to_attr = writer.sums.extend, writer.sums.to_attr

    def timed(fn: Callable) -> Callable:
        def call(*args: Any) -> Any:
            start = time.perf_counter()
            result = fn(*args)
            spent["checksums_s"] += time.perf_counter() - start
            return result
        return call

    writer.sums.extend, writer.sums.to_attr = timed(extend), timed(to_attr)
    starts = np.concatenate([[0], replay.episode_ends[:-1]])
    begin = time.perf_counter()
    for copy in range(copies):
        for ep, (a, b) in enumerate(zip(starts, replay.episode_ends, strict=True)):
            obs = {k: v[a:b] for k, v in replay.data.items() if k != "action"}
            meta = EpisodeMeta(float(replay.meta["episode_param"][ep]), copy * 1000 + ep, True,
                               copy * len(starts) + ep)
            writer.append_episode(obs, replay.data["action"][a:b], meta)
    return {"write_s": round(time.perf_counter() - begin, 3),
            "checksums_s": round(spent["checksums_s"], 3)}


def measure(path: Path, repeat: int) -> dict[str, Any]:
    """Frames, bytes and the median seconds of ``read``, ``load_replay`` and ``verify``."""
    layout = checked_layout(path)
    size = sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return {"episodes": len(layout.ends), "frames": int(layout.ends[-1]), "bytes": size,
            "read_s": _median_s(lambda: _plain_read(path), repeat),
            "load_replay_s": _median_s(lambda: load_replay(path), repeat),
            "verify_s": _median_s(lambda: scan_store(checked_layout(path), path, load=False),
                                  repeat)}


def main(argv: list[str] | None = None) -> None:
    """Entry point (``python -m impact_learn.store_check_cost``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="an impact-collect store")
    parser.add_argument("--tile", type=int, default=1, help="measure N copies of its episodes")
    parser.add_argument("--repeat", type=int, default=3, help="timings per quantity (median)")
    args = parser.parse_args(argv)
    if args.tile <= 1:
        print(json.dumps(measure(Path(args.data), args.repeat)))
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "tiled.zarr"
        written = tile_store(Path(args.data), out, args.tile)
        print(json.dumps({**measure(out, args.repeat), **written}))


if __name__ == "__main__":
    main()
