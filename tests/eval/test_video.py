"""impact-eval --video K: playable MP4s of the first K episodes of every cell, same CSV."""

from __future__ import annotations

import pytest

from impact_eval.cli import main

imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")


def _sweep(out, *extra):
    return main(["--env", "fixtures.reach_task:IMPACT-Test/Reach-v0", "--method",
                 "scripted_impact", "--param", "target_height", "--param-values", "0.2,0.4",
                 "--episodes", "2", "--workers", "1", "--out", str(out), *extra])


def test_video_writes_playable_mp4s_and_changes_no_row(tmp_path):
    assert _sweep(tmp_path / "plain") == 0
    assert _sweep(tmp_path / "video", "--video", "1") == 0
    plain = (tmp_path / "plain" / "episodes.csv").read_text()
    assert (tmp_path / "video" / "episodes.csv").read_text() == plain
    videos = sorted((tmp_path / "video" / "videos" / "scripted_impact").glob("*.mp4"))
    assert [v.name for v in videos] == ["target_height=0.2_ep000.mp4",
                                        "target_height=0.4_ep000.mp4"]
    import pandas as pd

    episodes = pd.read_csv(tmp_path / "plain" / "episodes.csv")
    for value, video in zip((0.2, 0.4), videos, strict=True):
        reader = imageio_ffmpeg.read_frames(str(video))
        meta = next(reader)
        frames = sum(1 for _ in reader)
        assert meta["size"] == (320, 240) and meta["fps"] == 30
        row = episodes[(episodes["param_value"] == value) & (episodes["episode"] == 0)]
        assert frames == int(row["length"].iloc[0]) + 1  # the reset frame + one per step


def test_negative_video_is_one_line(tmp_path, capsys):
    assert _sweep(tmp_path / "bad", "--video", "-1") == 2
    assert "--video must be >= 0" in capsys.readouterr().err
