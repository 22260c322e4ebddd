"""MP4 videos of sweep episodes (``impact-eval --video K``): the first K episodes of every cell.

Frames are the env's ``rgb_array`` render after reset and after every policy step (30 fps,
real time), encoded with the ffmpeg that ``imageio-ffmpeg`` ships. Rendering reads MuJoCo's
state only, so episodes with and without video give the same CSV rows.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_control.rates import POLICY_HZ

VIDEO_FPS = POLICY_HZ
"""One frame per policy step."""


def require_encoder() -> None:
    """One-line error when no MP4 encoder is installed."""
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        raise InvalidArgumentError(
            "--video needs imageio-ffmpeg (it ships its own ffmpeg); valid: pip install "
            "imageio-ffmpeg, or --video 0") from None


def require_video() -> None:
    """Before a sweep writes anything: an MP4 encoder is installed and this machine can render
    (``impact_envs._gl.check_rendering``: a tiny offscreen render), else one line saying what
    to install or set. A ``--video`` run used to write its results folder and then fail in
    every episode on a machine without a GL context."""
    from impact_envs._gl import check_rendering

    require_encoder()
    check_rendering()


def video_path(root: Path, method: str, param: str, value: str, episode: int) -> Path:
    """``root/<method>/<param>=<value>_ep<episode>.mp4`` (method made file-name safe)."""
    safe = re.sub(r"[^A-Za-z0-9_.=+@-]+", "_", method).strip("_")  # keeps a composition
    return root / safe / f"{param}={value}_ep{episode:03d}.mp4"


class EpisodeVideo:
    """Frames of one episode streamed to an MP4 file (opened on the first frame)."""

    def __init__(self, path: Path) -> None:
        self.path, self._writer = path, None

    def add(self, frame: np.ndarray | None) -> None:
        """Append an (H, W, 3) uint8 frame (None: the env did not render, nothing added)."""
        if frame is None:
            return
        frame = np.ascontiguousarray(frame, dtype=np.uint8)
        if self._writer is None:
            import imageio_ffmpeg

            self.path.parent.mkdir(parents=True, exist_ok=True)
            h, w = frame.shape[:2]
            self._writer = imageio_ffmpeg.write_frames(
                str(self.path), (w, h), fps=VIDEO_FPS, macro_block_size=1, quality=7)
            self._writer.send(None)  # start the encoder
        self._writer.send(frame)

    def close(self) -> None:
        """Finish the file."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None
