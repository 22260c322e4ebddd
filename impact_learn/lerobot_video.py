"""H.264 MP4 files of camera frames for the LeRobot export (``lerobot_export``).

Frames go to an ``ffmpeg`` process through a pipe as raw RGB; the binary is the one
``imageio-ffmpeg`` ships (``pip install impact-robotics[lerobot]``), so no system FFmpeg is
needed to export. Encoding: libx264, yuv420p (what LeRobot's decoders read), constant frame rate,
one thread and bit-exact flags (the same frames give the same file), a keyframe every
``gop_frames`` frames (random access for training loaders).
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.rates import POLICY_HZ


@dataclass(frozen=True)
class VideoOptions:
    """How camera frames are encoded.

    Attributes:
        fps: Frame rate [Hz] (the env's policy rate: timestamps are ``frame_index / fps``).
        crf: x264 constant rate factor, 0 (lossless luma) to 51; 18 is visually lossless.
        gop_frames: Frames between keyframes [frames].
    """

    fps: int = POLICY_HZ
    crf: int = 18
    gop_frames: int = 2

    def __post_init__(self) -> None:
        if not 0 <= self.crf <= 51:
            raise InvalidArgumentError(f"invalid crf {self.crf}; valid: 0 to 51")
        if self.gop_frames < 1 or self.fps < 1:
            raise InvalidArgumentError(
                f"invalid gop_frames {self.gop_frames} or fps {self.fps}; valid: >= 1")


def ffmpeg_exe() -> str:
    """Path of imageio-ffmpeg's ffmpeg binary (one-line error without the package)."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise InvalidArgumentError(
            "exporting images needs imageio-ffmpeg; valid: pip install "
            "'impact-robotics[lerobot]'") from None
    return str(imageio_ffmpeg.get_ffmpeg_exe())


class Mp4Writer:
    """One MP4 file, fed frame blocks ``(T, H, W, 3)`` uint8 in order; ``close`` finishes it.

    Args:
        path: Output file (its folder is created).
        width, height: Frame size [px]; both even (yuv420p halves the chroma planes).
        opts: Encoding options.
    """

    def __init__(self, path: Path, width: int, height: int, opts: VideoOptions) -> None:
        if width % 2 or height % 2:
            raise InvalidArgumentError(
                f"cannot encode {width}x{height} frames as yuv420p video; valid: even sizes")
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path, self.size, self.frames = path, (height, width), 0
        cmd = [ffmpeg_exe(), "-nostdin", "-loglevel", "error", "-y",
               "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{width}x{height}",
               "-r", str(opts.fps), "-i", "-",
               "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", str(opts.crf),
               "-g", str(opts.gop_frames), "-bf", "0", "-threads", "1",
               "-map_metadata", "-1", "-fflags", "+bitexact", "-flags:v", "+bitexact",
               "-movflags", "+faststart", str(path)]
        self._proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)

    def write(self, frames: np.ndarray) -> None:
        """Append ``frames`` ``(T, H, W, 3)`` uint8."""
        if frames.dtype != np.uint8 or frames.shape[1:] != (*self.size, 3):
            raise InvalidArgumentError(
                f"frames of shape {frames.shape} {frames.dtype}; valid: (T, {self.size[0]}, "
                f"{self.size[1]}, 3) uint8")
        assert self._proc.stdin is not None
        self._proc.stdin.write(np.ascontiguousarray(frames).tobytes())
        self.frames += int(frames.shape[0])

    def close(self) -> None:
        """Finish the file; a failed encoder is an ``ImpactError`` with its first line."""
        _, err = self._proc.communicate()
        if self._proc.returncode != 0:
            first = (err or b"").decode(errors="replace").strip().splitlines()[:1]
            raise ImpactError(f"ffmpeg failed on {self.path}: {' '.join(first) or 'no message'}")
