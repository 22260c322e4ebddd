"""impact-eval --video K: playable MP4s of the first K episodes of every cell, same CSV."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from impact_eval.cli import main

ROOT = Path(__file__).resolve().parents[2]

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


@pytest.fixture
def no_gl_context(monkeypatch: pytest.MonkeyPatch) -> None:
    """This process cannot make a GL context (as glfw without a display): mujoco.Renderer
    raises MuJoCo's own FatalError; the cached probe is forgotten."""
    import mujoco

    from impact_envs import _gl

    def fail(*args: object, **kwargs: object) -> None:
        raise mujoco.FatalError("an OpenGL platform library has not been loaded into this "
                                "process")

    monkeypatch.setattr(mujoco, "Renderer", fail)
    monkeypatch.setattr(_gl, "_probed", None)


def test_video_without_rendering_is_one_line_before_any_file(tmp_path, capsys,
                                                             no_gl_context) -> None:
    """It used to write the results folder, then fail in every episode (FatalError rows)."""
    out = tmp_path / "new" / "run"
    assert _sweep(out, "--video", "1") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot render with MuJoCo" in err[0]
    assert "set MUJOCO_GL=egl" in err[0] and "FatalError" in err[0]
    assert not (tmp_path / "new").exists()


def test_video_on_resume_without_rendering_leaves_the_run_unchanged(tmp_path, capsys,
                                                                    monkeypatch) -> None:
    """Held-out variant: an existing, finished run and --resume --video 2."""
    out = tmp_path / "run"
    assert _sweep(out) == 0
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    import mujoco

    from impact_envs import _gl

    monkeypatch.setattr(mujoco, "Renderer", lambda *a, **k: (_ for _ in ()).throw(
        AttributeError("'NoneType' object has no attribute 'glGetError'")))
    monkeypatch.setattr(_gl, "_probed", None)
    capsys.readouterr()
    assert _sweep(out, "--resume", "--video", "2") == 2
    assert "cannot render with MuJoCo" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_video_without_mujoco_gl_or_display_in_a_fresh_process(tmp_path) -> None:
    """The README's --video on a machine without a display and nothing set: the package
    picks EGL itself (impact_envs/_gl.py) and the MP4 is written."""
    environ = {k: v for k, v in os.environ.items()
               if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL", "PYOPENGL_PLATFORM")}
    environ["PYTHONPATH"] = os.pathsep.join([str(ROOT / "tests"), str(ROOT)])
    out = tmp_path / "run"
    done = subprocess.run(
        [sys.executable, "-m", "impact_eval", "--env",
         "fixtures.reach_task:IMPACT-Test/Reach-v0", "--method", "scripted_impact",
         "--param-values", "0.3", "--episodes", "1", "--workers", "1", "--out", str(out),
         "--video", "1"], capture_output=True, text=True, env=environ, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    video = out / "videos" / "scripted_impact" / "target_height=0.3_ep000.mp4"
    meta = next(imageio_ffmpeg.read_frames(str(video)))
    assert meta["size"] == (320, 240)
    assert "exception" not in (out / "episodes.csv").read_text()
