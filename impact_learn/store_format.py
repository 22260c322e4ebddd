"""Constants of the demonstration store layout (``dataset.py`` writes it, ``store_check.py``
checks it); importable from ``impact_learn.dataset`` as before."""

from __future__ import annotations

FORMAT_VERSION = 1
"""Version of the zarr layout (stored in attrs['format_version']) for state-only stores."""
IMAGE_FORMAT_VERSION = 2
"""``format_version`` of a store holding image arrays ``(N, H, W, C)``."""
IMAGE_CHUNK_FRAMES = 64
"""Frames per chunk of an image array (64 frames of 96x96 RGB: 1.8 MB before compression)."""
IMAGE_ZSTD_LEVEL = 9
ACTION_KEY = "action"
ACTION_DIM = 10
META_DTYPES = {
    "episode_param": "float64",
    "episode_seed": "int64",
    "episode_success": "bool",
    "episode_attempt": "int64",
}
CHUNK_ROWS = 4096
UNCHECKED_ATTRS = frozenset({"package_version", "n_attempts", "checksums"})
"""Attributes that may differ when a store is reopened for appending."""
CHECKSUM_ATTR = "checksums"
"""Store attribute holding every array's chunk checksums (``store_check.Checksums``)."""
REQUIRED_ARRAYS = (f"data/{ACTION_KEY}", "meta/episode_ends",
                   *(f"meta/{key}" for key in META_DTYPES))
"""Arrays every store holds (``impact-collect`` writes them all)."""
