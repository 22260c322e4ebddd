"""A side-by-side video of one episode of a committed table under two methods (issue 58 item
4): the same paired seed and mass, e.g. IMPACT lifting the 5 kg hammer beside the Vanilla DP on
impedance alone, which cannot.

    python -m impact_experiments.side_by_side --table results/hammer_presets --value 5 \\
        --episode 19 --methods impact,vanilla_dp --out docs/img/hammer_5kg

Each method's episode is rerun as the sweep ran it (``rollout.LockstepBatch``: its env, policy,
seed and reset), rendering the env's ``rgb_array`` after the reset and every policy step. Its
outcome and length must equal the table's row, so the video shows that row (on the CPU that
recorded the table; elsewhere it refuses in one line). The frames are composed left to right,
each labelled, a finished episode holding its last frame, and written as ``OUT.mp4`` (30 fps)
with ``OUT.json``: the command, the rows shown and the sha256 of the raw frames, which a rerun
on the same machine reproduces (tests/experiments/test_side_by_side.py).
"""

from __future__ import annotations

import argparse
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.rates import POLICY_HZ


@dataclass(frozen=True)
class TableEpisode:
    """One row of a table's ``episodes.csv``: where it ran and how it ended."""

    method: str
    env_id: str
    param_name: str
    value: float
    seed: int
    success: bool
    length: int


class FrameList:
    """``video.EpisodeVideo``'s ``add``/``close``, keeping the frames in memory."""

    def __init__(self) -> None:
        self.frames: list[np.ndarray] = []

    def add(self, frame: np.ndarray | None) -> None:
        if frame is not None:
            self.frames.append(np.array(frame, dtype=np.uint8))

    def close(self) -> None:
        """Nothing to flush."""


def table_episode(table: Path, method: str, value: float, episode: int) -> TableEpisode:
    """The row of ``method`` at ``value``, episode ``episode`` (one line if there is none)."""
    rows = pd.read_csv(table / "episodes.csv")
    row = rows[(rows["method"] == method) & np.isclose(rows["param_value"], value)
               & (rows["episode"] == episode)]
    if len(row) != 1:
        raise InvalidArgumentError(
            f"{table}/episodes.csv has no row for method {method!r} at {value} episode "
            f"{episode}; valid methods: {', '.join(sorted(rows['method'].unique()))}")
    r = row.iloc[0]
    return TableEpisode(method, str(r["env_id"]), str(r["param_name"]), float(r["param_value"]),
                        int(r["seed"]), bool(r["success"]), int(r["length"]))


def rerun(episode: TableEpisode, max_steps: int | None = None) -> tuple[list[np.ndarray], dict]:
    """The episode's frames (reset, then one per step) and its metric columns, as the sweep
    ran it; ``max_steps`` truncates it (its row then is not the table's)."""
    import gymnasium as gym

    from impact_eval.envs import method_env
    from impact_eval.methods import resolve_method
    from impact_eval.rollout import EpisodeJob, LockstepBatch

    spec = resolve_method(episode.method)
    env = method_env(episode.env_id, spec, render=True)
    if max_steps is not None:
        env = gym.wrappers.TimeLimit(env, max_episode_steps=max_steps)
    frames, rows = FrameList(), {}
    try:
        policy = spec.build(episode.env_id, env)
        batch = LockstepBatch([env], policy, episode.param_name, 1.0 / POLICY_HZ, {0: frames})
        batch.run([EpisodeJob(episode.value, episode.seed, 0)],
                  lambda _i, columns: rows.update(columns))
    finally:
        env.close()
    return frames.frames, rows


def compose(clips: list[list[np.ndarray]], labels: list[str]) -> list[np.ndarray]:
    """Clips left to right, each labelled at its top left; shorter clips hold their last
    frame."""
    from PIL import Image, ImageDraw

    n = max(len(c) for c in clips)
    out = []
    for k in range(n):
        tiles = []
        for clip, label in zip(clips, labels, strict=True):
            image = Image.fromarray(clip[min(k, len(clip) - 1)])
            ImageDraw.Draw(image).text((6, 4), label, fill=(255, 255, 255))
            tiles.append(np.asarray(image))
        out.append(np.concatenate(tiles, axis=1))
    return out


def frames_sha256(frames: list[np.ndarray]) -> str:
    """sha256 over the raw frames (shape and bytes, in order)."""
    digest = hashlib.sha256()
    for frame in frames:
        digest.update(repr(frame.shape).encode() + frame.tobytes())
    return digest.hexdigest()


def _label(episode: TableEpisode) -> str:
    outcome = f"success in {episode.length / POLICY_HZ:.1f} s" if episode.success else "fails"
    return f"{episode.method}: {outcome}"


def make_video(table: Path, value: float, episode: int, methods: list[str], out: Path) -> dict:
    """Rerun, check against the table, compose, write ``out``.mp4 and ``out``.json."""
    from impact_control.runinfo import cpu_info
    from impact_eval.video import EpisodeVideo, require_video

    require_video()
    shown = [table_episode(table, m, value, episode) for m in methods]
    clips = []
    for row in shown:
        frames, columns = rerun(row)
        if bool(columns["success"]) != row.success or int(columns["length"]) != row.length:
            raise ImpactError(
                f"{row.method}'s rerun ended success={columns['success']} after "
                f"{columns['length']} steps, the table's row success={int(row.success)} after "
                f"{row.length}: not the table's episode on this CPU (it records its CPU in "
                "results/manifest.json)")
        clips.append(frames)
    frames = compose(clips, [_label(r) for r in shown])
    out.parent.mkdir(parents=True, exist_ok=True)
    video = EpisodeVideo(out.with_suffix(".mp4"))
    for frame in frames:
        video.add(frame)
    video.close()
    record = {"command": ["python", "-m", "impact_experiments.side_by_side", "--table",
                          str(table), "--value", str(value), "--episode", str(episode),
                          "--methods", ",".join(methods), "--out", str(out)],
              "rows": [vars(r) for r in shown], "n_frames": len(frames), "fps": POLICY_HZ,
              "frames_sha256": frames_sha256(frames), "cpu": cpu_info()}
    out.with_suffix(".json").write_text(json.dumps(record, indent=1) + "\n")
    return record


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--table", required=True, help="a results folder with episodes.csv")
    parser.add_argument("--value", type=float, required=True, help="the parameter value")
    parser.add_argument("--episode", type=int, required=True, help="the episode index")
    parser.add_argument("--methods", required=True, help="comma-separated, left to right")
    parser.add_argument("--out", required=True, help="output path without suffix")
    args = parser.parse_args(argv)
    try:
        record = make_video(Path(args.table), args.value, args.episode,
                            [m.strip() for m in args.methods.split(",") if m.strip()],
                            Path(args.out))
    except ImpactError as exc:
        parser.exit(2, f"side_by_side: error: {exc}\n")
    print(f"{args.out}.mp4: {record['n_frames']} frames, sha256 {record['frames_sha256']}")


if __name__ == "__main__":
    main()
