"""Demonstration storage (Diffusion Policy's zarr replay layout); training windows: windows.py.

Layout of ``DATA.zarr``::

    data/<obs_key>          (N, d_key) float32   one array per env observation key
    data/<camera>_rgb       (N, H, W, 3) uint8   image stores only (impact-collect --obs-mode)
    data/<camera>_depth     (N, H, W, 1) float32 --obs-mode rgbd only [m]
    data/action             (N, 10)    float32   expert action at the same step
    meta/episode_ends       (E,) int64           exclusive end index of each episode in N
    meta/episode_param      (E,) float64         randomized parameter (e.g. object mass [kg])
    meta/episode_seed       (E,) int64           env reset seed
    meta/episode_success    (E,) bool            expert succeeded
    meta/episode_attempt    (E,) int64           collection attempt index (for --resume)
    attrs                   env_id, param_name, controller, expert options, versions, ...

Episodes are appended one at a time; ``meta/episode_ends`` is written last, so an interrupted
append is discarded (truncated) when the store is reopened. Image arrays are chunked by
``IMAGE_CHUNK_FRAMES`` frames and compressed losslessly with zstd (level ``IMAGE_ZSTD_LEVEL``);
a store holding them has ``format_version`` 2, a state-only store 1 (its bytes are as before).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import zarr
from zarr.codecs import ZstdCodec

from impact_envs.errors import InvalidArgumentError

FORMAT_VERSION = 1
"""Version of the zarr layout above (stored in attrs['format_version']) for state-only stores."""
IMAGE_FORMAT_VERSION = 2
"""``format_version`` of a store holding image arrays ``(N, H, W, C)``."""
IMAGE_CHUNK_FRAMES = 64
"""Frames per chunk of an image array (64 frames of 96x96 RGB: 1.8 MB before compression)."""
IMAGE_ZSTD_LEVEL = 9
ACTION_KEY = "action"
META_DTYPES = {
    "episode_param": "float64",
    "episode_seed": "int64",
    "episode_success": "bool",
    "episode_attempt": "int64",
}
CHUNK_ROWS = 4096
UNCHECKED_ATTRS = frozenset({"package_version", "n_attempts"})
"""Attributes that may differ when a store is reopened for appending."""


@dataclass(frozen=True)
class ImageSpec:
    """An image observation stored per step.

    Attributes:
        shape: ``(H, W, C)`` of one image [px, px, channels].
        dtype: ``"uint8"`` (RGB) or ``"float32"`` (depth [m]).
    """

    shape: tuple[int, int, int]
    dtype: str


FieldDims = Mapping[str, int | ImageSpec]
"""``{obs_key: d_key}`` of flat float32 arrays, or an ``ImageSpec`` for an image key."""


@dataclass(frozen=True)
class EpisodeMeta:
    """Per-episode metadata.

    Attributes:
        param: Randomized parameter value (object mass [kg] for Hammer/Dumbbell).
        seed: Env reset seed.
        success: Whether the expert succeeded.
        attempt: Collection attempt index.
    """

    param: float
    seed: int
    success: bool
    attempt: int


class ReplayWriter:
    """Append-only writer of the zarr layout (used by ``impact-collect``).

    Args:
        path: Store path (a directory ``*.zarr``).
        obs_dims: ``{obs_key: d_key}`` of the env's flat observation arrays, or an
            ``ImageSpec`` for each image key.
        attrs: JSON-serialisable store attributes (env_id, param_name, ...).
        append: Reopen an existing store (its attrs must match ``attrs`` on the keys given)
            instead of creating a new one; an existing store without ``append`` is an error.
    """

    def __init__(
        self,
        path: str | Path,
        obs_dims: FieldDims,
        attrs: Mapping[str, Any],
        *,
        append: bool = False,
    ) -> None:
        self.path = Path(path)
        self.obs_keys = tuple(obs_dims)
        self.images = {k: v for k, v in obs_dims.items() if isinstance(v, ImageSpec)}
        if append and self.path.exists():
            self._open_for_append(attrs)
            return
        if self.path.exists():
            raise InvalidArgumentError(f"{self.path} exists; pass --resume to append or remove it")
        self.root = zarr.open_group(str(self.path), mode="w")
        version = IMAGE_FORMAT_VERSION if self.images else FORMAT_VERSION
        self.root.attrs.update({**attrs, "format_version": version})
        data, meta = self.root.require_group("data"), self.root.require_group("meta")
        for key, dim in {**obs_dims, ACTION_KEY: 10}.items():
            if isinstance(dim, ImageSpec):
                _create_image_array(data, key, dim)
            else:
                data.zeros(name=key, shape=(0, dim), chunks=(CHUNK_ROWS, dim), dtype="float32")
        for key, dtype in {**META_DTYPES, "episode_ends": "int64"}.items():
            meta.zeros(name=key, shape=(0,), chunks=(CHUNK_ROWS,), dtype=dtype)

    def _open_for_append(self, attrs: Mapping[str, Any]) -> None:
        """Open, check and trim an existing store; a damaged one is a one-line error."""
        try:
            self.root = zarr.open_group(str(self.path), mode="r+")
            self._check_attrs(attrs)
            self._truncate_partial()
            for key in (*self.obs_keys, ACTION_KEY, *META_DTYPES, "episode_ends"):
                group = "meta" if key in META_DTYPES or key == "episode_ends" else "data"
                arr = self.root[f"{group}/{key}"]
                # every chunk decodes (a torn write does not); of an image array the last
                # chunk, the only one an interrupted append rewrites
                first = arr.shape[0] - 1 - (arr.shape[0] - 1) % arr.chunks[0]
                arr[max(first, 0) if key in self.images else 0:]
        except InvalidArgumentError:
            raise
        except Exception as exc:  # noqa: BLE001 - zarr/numcodecs raise many types here
            msg = " ".join(str(exc).split())[:160]
            raise InvalidArgumentError(
                f"cannot resume {self.path}: the store is damaged ({type(exc).__name__}: "
                f"{msg}); delete it and collect again") from None

    def _check_attrs(self, attrs: Mapping[str, Any]) -> None:
        stored = dict(self.root.attrs)
        for key, value in attrs.items():
            if key in stored and key not in UNCHECKED_ATTRS and stored[key] != value:
                raise InvalidArgumentError(
                    f"cannot resume {self.path}: attr {key!r} is {stored[key]!r}, not {value!r}"
                )
        if stored.get("observation") != attrs.get("observation"):
            raise InvalidArgumentError(
                f"cannot resume {self.path}: it was collected with observation "
                f"{stored.get('observation', 'state')!r}, not "
                f"{attrs.get('observation', 'state')!r}")
        missing = [k for k in self.obs_keys if k not in self.root["data"]]
        if missing:
            raise InvalidArgumentError(f"cannot resume {self.path}: missing data arrays {missing}")

    def _truncate_partial(self) -> None:
        ends = self.root["meta/episode_ends"][:]
        n_steps = int(ends[-1]) if len(ends) else 0
        for key in (*self.obs_keys, ACTION_KEY):
            arr = self.root[f"data/{key}"]
            arr.resize((n_steps, *arr.shape[1:]))
        for key in META_DTYPES:
            self.root[f"meta/{key}"].resize((len(ends),))

    @property
    def n_episodes(self) -> int:
        """Number of complete episodes stored."""
        return int(self.root["meta/episode_ends"].shape[0])

    def attempts(self) -> np.ndarray:
        """Attempt index of each stored episode ``(E,)``."""
        return np.asarray(self.root["meta/episode_attempt"][:], dtype=np.int64)

    def set_attrs(self, **attrs: Any) -> None:
        """Update store attributes (e.g. the number of attempts made so far)."""
        self.root.attrs.update(attrs)

    def append_episode(
        self, obs: Mapping[str, np.ndarray], actions: np.ndarray, meta: EpisodeMeta
    ) -> None:
        """Append one episode: ``obs[key]`` ``(T, d_key)`` (``(T, H, W, C)`` for an image
        key), ``actions`` ``(T, 10)``."""
        length = int(actions.shape[0])
        if length == 0 or any(np.shape(obs[k])[0] != length for k in self.obs_keys):
            raise InvalidArgumentError(
                "episode observations and actions must have equal length > 0"
            )
        for key, spec in self.images.items():
            if tuple(np.shape(obs[key])[1:]) != spec.shape:
                raise InvalidArgumentError(
                    f"images {key!r} have shape {np.shape(obs[key])[1:]}; valid: {spec.shape}")
        ends = self.root["meta/episode_ends"]
        start = int(ends[-1]) if ends.shape[0] else 0
        for key in self.obs_keys:
            dtype = self.images[key].dtype if key in self.images else np.float32
            self.root[f"data/{key}"].append(np.asarray(obs[key], dtype=dtype), axis=0)
        self.root[f"data/{ACTION_KEY}"].append(np.asarray(actions, dtype=np.float32), axis=0)
        values = (meta.param, meta.seed, meta.success, meta.attempt)
        for key, value in zip(META_DTYPES, values, strict=True):
            self.root[f"meta/{key}"].append(np.asarray([value], dtype=META_DTYPES[key]))
        ends.append(np.asarray([start + length], dtype=np.int64))


def _create_image_array(group: zarr.Group, key: str, spec: ImageSpec) -> None:
    """An empty ``(0, H, W, C)`` image array, ``IMAGE_CHUNK_FRAMES`` frames a chunk, zstd."""
    group.create_array(name=key, shape=(0, *spec.shape),
                       chunks=(IMAGE_CHUNK_FRAMES, *spec.shape), dtype=spec.dtype,
                       compressors=ZstdCodec(level=IMAGE_ZSTD_LEVEL), fill_value=0)


@dataclass(frozen=True)
class ReplayData:
    """A whole demonstration store loaded into memory.

    Attributes:
        data: ``{key: (N, d)}`` float32 arrays, including ``"action"`` ``(N, 10)``.
        episode_ends: ``(E,)`` exclusive end indices.
        meta: ``{name: (E,)}`` per-episode metadata (``episode_param``, ``episode_seed``, ...).
        attrs: Store attributes.
    """

    data: dict[str, np.ndarray]
    episode_ends: np.ndarray
    meta: dict[str, np.ndarray]
    attrs: dict[str, Any]

    @property
    def n_episodes(self) -> int:
        """Number of episodes E."""
        return int(self.episode_ends.shape[0])

    def obs_matrix(self, keys: Sequence[str]) -> np.ndarray:
        """Concatenate observation arrays ``keys`` into ``(N, D_obs)``."""
        missing = [k for k in keys if k not in self.data]
        if missing:
            raise InvalidArgumentError(
                f"observation keys {missing} not in dataset; valid keys: {', '.join(self.data)}"
            )
        return np.concatenate([self.data[k] for k in keys], axis=1).astype(np.float32)


def load_replay(path: str | Path) -> ReplayData:
    """Load a store written by ``ReplayWriter`` (complete episodes only)."""
    if not Path(path).exists():
        raise InvalidArgumentError(f"dataset {path} does not exist")
    try:
        root = zarr.open_group(str(path), mode="r")
        ends = np.asarray(root["meta/episode_ends"][:], dtype=np.int64)
        n_steps = int(ends[-1]) if len(ends) else 0
        data = {k: np.asarray(a[:n_steps]) for k, a in root["data"].arrays()}
        meta = {k: np.asarray(root[f"meta/{k}"][: len(ends)]) for k in META_DTYPES}
    except Exception as exc:  # noqa: BLE001 - zarr raises many types for foreign/corrupt stores
        msg = " ".join(str(exc).split())[:120]
        raise InvalidArgumentError(
            f"{path} is not a readable demonstration store (impact-collect's zarr layout): "
            f"{type(exc).__name__}: {msg}") from None
    if ACTION_KEY not in data or len(ends) == 0:
        raise InvalidArgumentError(
            f"{path} holds no episodes with actions (data/{ACTION_KEY}, meta/episode_ends)")
    if any(len(a) < n_steps for a in data.values()):
        raise InvalidArgumentError(f"{path} is truncated: arrays shorter than episode_ends says")
    return ReplayData(data, ends, meta, dict(root.attrs))
