"""Where on the table a HammerBasket table's episodes fail: success by the hammer's spawn.

Run ``python -m impact_experiments.hammer_basket_layout --table results/hammer_basket``.
For every episode of the table it resets ``IMPACT/HammerBasket-v1`` with the episode's seed
(the spawn depends on the seed alone, not on the mass or the method) and reads the hammer's
spawn (its body origin, x and y), then prints per method the success count inside and outside
a region of the spawn range (default: the near, far-side corner, x < 0.30 m and y < -0.35 m,
where the Vanilla DP's light-bin failures gather), and the episodes that failed under every
method of the table. Writes nothing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd

import impact_envs  # noqa: F401 - registers the envs
from impact_eval.metrics import wilson_interval

ENV_ID = "IMPACT/HammerBasket-v1"


def spawns(seeds: np.ndarray) -> pd.DataFrame:
    """Hammer body origin x, y [m] and basket centre x, y [m] at reset, per seed."""
    env = gym.make(ENV_ID)
    rows = []
    for seed in sorted(set(int(s) for s in seeds)):
        obs, _ = env.reset(seed=seed)
        rows.append({"seed": seed, "hammer_x": float(obs["object_origin_pos"][0]),
                     "hammer_y": float(obs["object_origin_pos"][1]),
                     "basket_x": float(obs["goal_pos"][0]),
                     "basket_y": float(obs["goal_pos"][1])})
    env.close()
    return pd.DataFrame(rows)


def _count(cell: pd.DataFrame) -> str:
    k, n = int(cell["success"].sum()), len(cell)
    if n == 0:
        return "–"
    low, high = wilson_interval(k, n)
    return f"{k}/{n} ({k / n:.2f}, {low:.2f}–{high:.2f})"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--table", type=Path, required=True, help="a bin sweep's folder")
    parser.add_argument("--x-below", type=float, default=0.30, help="region: hammer x < [m]")
    parser.add_argument("--y-below", type=float, default=-0.35, help="region: hammer y < [m]")
    args = parser.parse_args(argv)
    csv = args.table / "episodes.csv"
    if not csv.is_file():
        parser.error(f"--table {args.table}: no episodes.csv there; valid: a sweep's folder")
    episodes = pd.read_csv(csv)
    if not {"method", "seed", "success"} <= set(episodes.columns):
        parser.error(f"--table {args.table}: episodes.csv lacks method, seed or success")
    table = episodes.merge(spawns(episodes["seed"].to_numpy()), on="seed")
    inside = (table["hammer_x"] < args.x_below) & (table["hammer_y"] < args.y_below)
    print(f"region: hammer x < {args.x_below} m and y < {args.y_below} m "
          f"({inside[table['method'] == table['method'].iloc[0]].mean():.0%} of the "
          f"first method's episodes)")
    print("| method | inside | outside |\n|---|---|---|")
    for method, cell in table.groupby("method", sort=True):
        mask = inside[cell.index]
        print(f"| `{method}` | {_count(cell[mask])} | {_count(cell[~mask])} |")
    per_seed = table.groupby("seed")["success"].agg(["sum", "count"])
    all_fail = per_seed[(per_seed["sum"] == 0)].index
    shared = table[table["seed"].isin(all_fail)].drop_duplicates("seed")
    print(f"episodes failed under every method: {len(shared)} of {table['seed'].nunique()}, "
          f"{int(inside[shared.index].sum())} of them in the region")


if __name__ == "__main__":
    main()
