"""``impact_experiments.side_by_side``: a table's episode rerun under two methods, composed
side by side; the frames are a function of the episode (the same sha256 on a rerun)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_experiments.side_by_side import compose, frames_sha256, rerun, table_episode

REPO = Path(__file__).resolve().parents[2]
TABLE = REPO / "results" / "hammer_presets"
VIDEO = REPO / "docs" / "img" / "hammer_5kg.json"


def test_compose_puts_clips_side_by_side_and_holds_the_shorter_one() -> None:
    short = [np.full((8, 6, 3), 10, np.uint8)]
    long = [np.full((8, 6, 3), 200, np.uint8), np.full((8, 6, 3), 100, np.uint8)]
    frames = compose([short, long], ["", ""])
    assert len(frames) == 2 and frames[0].shape == (8, 12, 3)
    assert (frames[1][:, :6] == 10).all() and (frames[1][:, 6:] == 100).all()
    assert frames_sha256(frames) != frames_sha256(frames[::-1])


def test_the_row_is_looked_up_and_a_missing_one_is_one_line() -> None:
    row = table_episode(TABLE, "impact", 5.0, 19)
    assert (row.env_id, row.param_name, row.success) == ("IMPACT/Hammer-v1", "object_mass", True)
    with pytest.raises(InvalidArgumentError, match="no row for method 'impact' at 5.0 episode 99"):
        table_episode(TABLE, "impact", 5.0, 99)


def test_a_rerun_gives_the_same_frames() -> None:
    row = table_episode(TABLE, "vanilla_dp", 5.0, 19)
    first, _ = rerun(row, max_steps=4)
    again, _ = rerun(row, max_steps=4)
    assert len(first) == 5 and first[0].shape == (240, 320, 3)
    assert frames_sha256(first) == frames_sha256(again)


@pytest.mark.slow
def test_the_committed_video_is_regenerated_frame_for_frame(tmp_path: Path) -> None:
    from impact_control.runinfo import cpu_info
    from impact_experiments.side_by_side import make_video

    record = json.loads(VIDEO.read_text())
    if record["cpu"] != cpu_info():
        pytest.skip(f"recorded on {record['cpu']}, this is {cpu_info()}")
    again = make_video(TABLE, 5.0, 19, ["impact", "vanilla_dp"], tmp_path / "v")
    assert again["frames_sha256"] == record["frames_sha256"]
