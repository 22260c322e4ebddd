"""``meta/stats.json`` of the LeRobot export: per-feature statistics over every frame.

Each feature gets ``min``, ``max``, ``mean``, ``std`` (population), ``count`` and the quantiles
``q01``, ``q10``, ``q50``, ``q90``, ``q99`` that LeRobot's normalizers read. Vectors: per
dimension over all frames (``np.quantile``, linear interpolation). Camera features: per colour
channel over all pixels of all frames, in [0, 1] (frames as LeRobot's loader returns them),
shaped ``(3, 1, 1)``; computed exactly from 256-bin histograms of the stored uint8 frames (the
quantile is the smallest level whose cumulative share reaches q), so no frame is sampled out.
"""

from __future__ import annotations

import numpy as np

QUANTILES = {"q01": 0.01, "q10": 0.10, "q50": 0.50, "q90": 0.90, "q99": 0.99}


def vector_stats(values: np.ndarray) -> dict[str, list]:
    """Statistics of ``values`` ``(N, d)`` along the frame axis."""
    x = np.asarray(values, dtype=np.float64).reshape(len(values), -1)
    stats = {"min": x.min(0), "max": x.max(0), "mean": x.mean(0), "std": x.std(0),
             "count": np.array([len(x)])}
    stats.update({name: np.quantile(x, q, axis=0) for name, q in QUANTILES.items()})
    return {k: v.tolist() for k, v in stats.items()}


class ImageHistogram:
    """Per-channel 256-bin histograms of uint8 RGB frames, accumulated episode by episode."""

    def __init__(self) -> None:
        self.counts = np.zeros((3, 256), dtype=np.int64)
        self.frames = 0

    def add(self, frames: np.ndarray) -> None:
        """Count the pixels of ``frames`` ``(T, H, W, 3)`` uint8."""
        for c in range(3):
            self.counts[c] += np.bincount(frames[..., c].ravel(), minlength=256)
        self.frames += int(frames.shape[0])

    def stats(self) -> dict[str, list]:
        """Statistics in [0, 1], each ``(3, 1, 1)`` (``count``: the number of frames)."""
        levels = np.arange(256) / 255.0
        n = self.counts.sum(1)
        mean = (self.counts * levels).sum(1) / n
        var = (self.counts * (levels[None] - mean[:, None]) ** 2).sum(1) / n
        present = self.counts > 0
        cdf = np.cumsum(self.counts, 1) / n[:, None]
        stats = {"min": levels[present.argmax(1)],
                 "max": levels[255 - present[:, ::-1].argmax(1)],
                 "mean": mean, "std": np.sqrt(var)}
        for name, q in QUANTILES.items():
            stats[name] = levels[(cdf >= q - 1e-12).argmax(1)]
        out = {k: v.reshape(3, 1, 1).tolist() for k, v in stats.items()}
        out["count"] = [self.frames]
        return out
