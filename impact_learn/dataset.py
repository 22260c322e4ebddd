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
a store holding them has ``format_version`` 2, a state-only store 1. The attribute
``checksums`` holds a digest of every chunk of every array, updated with each append
(``store_check.py``): ``load_replay`` and ``--resume`` read every chunk and compare.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import zarr
from zarr.codecs import ZstdCodec

from impact_control.errors import InvalidArgumentError
from impact_learn.replay_data import ReplayData, checked_layout, load_replay  # noqa: F401
from impact_learn.store_check import ScanResult, StoreLayout, scan_store, store_layout
from impact_learn.store_checksums import Checksums, DamagedStoreError
from impact_learn.store_format import (  # noqa: F401 - the layout's names, importable from here
    ACTION_DIM,
    ACTION_KEY,
    CHECKSUM_ATTR,
    CHUNK_ROWS,
    FORMAT_VERSION,
    IMAGE_CHUNK_FRAMES,
    IMAGE_FORMAT_VERSION,
    IMAGE_ZSTD_LEVEL,
    META_DTYPES,
    UNCHECKED_ATTRS,
)


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
        verify: bool = True,
    ) -> None:
        self.path = Path(path)
        self.obs_keys = tuple(obs_dims)
        self.images = {k: v for k, v in obs_dims.items() if isinstance(v, ImageSpec)}
        if append and self.path.exists():
            self._open_for_append(attrs, verify)
            return
        if self.path.exists():
            raise InvalidArgumentError(f"{self.path} exists; pass --resume to append or remove it")
        self.root = zarr.open_group(str(self.path), mode="w")
        chunk_rows = {f"data/{k}": IMAGE_CHUNK_FRAMES if k in self.images else CHUNK_ROWS
                      for k in (*obs_dims, ACTION_KEY)}
        chunk_rows |= {f"meta/{k}": CHUNK_ROWS for k in (*META_DTYPES, "episode_ends")}
        self.sums = Checksums.empty(chunk_rows)
        version = IMAGE_FORMAT_VERSION if self.images else FORMAT_VERSION
        self.root.attrs.update({**attrs, "format_version": version,
                                CHECKSUM_ATTR: self.sums.to_attr()})
        data, meta = self.root.require_group("data"), self.root.require_group("meta")
        for key, dim in {**obs_dims, ACTION_KEY: ACTION_DIM}.items():
            if isinstance(dim, ImageSpec):
                _create_image_array(data, key, dim)
            else:
                data.zeros(name=key, shape=(0, dim), chunks=(CHUNK_ROWS, dim), dtype="float32")
        for key, dtype in {**META_DTYPES, "episode_ends": "int64"}.items():
            meta.zeros(name=key, shape=(0,), chunks=(CHUNK_ROWS,), dtype=dtype)

    def _open_for_append(self, attrs: Mapping[str, Any], verify: bool) -> None:
        """Open and check an existing store (every chunk against its checksum with
        ``verify``), then trim an interrupted append; a damaged store is a one-line error and
        is left as it was."""
        try:
            self.root = zarr.open_group(str(self.path), mode="r+")
            layout = store_layout(self.root, self.path)
            self._check_attrs(attrs)
            scan = scan_store(layout, self.path, load=False, allow_unrecorded=True) if verify \
                else None
        except DamagedStoreError as exc:
            raise InvalidArgumentError(f"cannot resume {exc.path}: the store is damaged: "
                                       f"{exc.detail}; delete it and collect again") from None
        except InvalidArgumentError:
            raise
        except Exception as exc:  # noqa: BLE001 - zarr/numcodecs raise many types here
            msg = " ".join(str(exc).split())[:160]
            raise InvalidArgumentError(
                f"cannot resume {self.path}: the store is damaged ({type(exc).__name__}: "
                f"{msg}); delete it and collect again") from None
        try:
            self._truncate_partial()
            self._resume_checksums(layout, scan)
        except OSError as exc:
            raise InvalidArgumentError(
                f"cannot resume {self.path}: cannot write to it ({exc.strerror or exc}); "
                "valid: a writable store") from None

    def _resume_checksums(self, layout: StoreLayout, scan: ScanResult | None) -> None:
        """The checksum record to extend: the scan's (rows written after the record was last
        saved are added), or the stored one when the store was just verified."""
        if scan is None:
            self.sums = Checksums.from_attr(self.root.attrs.get(CHECKSUM_ATTR), self.path)
            checked = {name: s.rows for name, s in self.sums.arrays.items()}
        else:
            self.sums = scan.checksums(layout)
            checked = scan.checked_rows
        for name, sums in self.sums.arrays.items():
            arr, upto, rows = layout.arrays[name], checked[name], layout.rows[name]
            self.sums.set_tail(name, arr[upto - upto % sums.chunk_rows:upto])
            if rows > upto:
                self.sums.extend(name, np.asarray(arr[upto:rows]))
        if scan is None or scan.checked_rows != layout.rows or not scan.recorded:
            self.root.attrs[CHECKSUM_ATTR] = self.sums.to_attr()

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
            if arr.shape[0] != n_steps:
                arr.resize((n_steps, *arr.shape[1:]))
        for key in META_DTYPES:
            if self.root[f"meta/{key}"].shape[0] != len(ends):
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
        key), ``actions`` ``(T, 10)``; the checksum record is saved after ``episode_ends``."""
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
        rows = {f"data/{k}": np.asarray(obs[k], dtype=self.images[k].dtype if k in self.images
                                        else np.float32) for k in self.obs_keys}
        rows[f"data/{ACTION_KEY}"] = np.asarray(actions, dtype=np.float32)
        values = (meta.param, meta.seed, meta.success, meta.attempt)
        for key, value in zip(META_DTYPES, values, strict=True):
            rows[f"meta/{key}"] = np.asarray([value], dtype=META_DTYPES[key])
        rows["meta/episode_ends"] = np.asarray([start + length], dtype=np.int64)
        for name, block in rows.items():  # episode_ends last: it commits the episode
            self.root[name].append(block, axis=0)
            self.sums.extend(name, block)
        self.root.attrs[CHECKSUM_ATTR] = self.sums.to_attr()


def _create_image_array(group: zarr.Group, key: str, spec: ImageSpec) -> None:
    """An empty ``(0, H, W, C)`` image array, ``IMAGE_CHUNK_FRAMES`` frames a chunk, zstd."""
    group.create_array(name=key, shape=(0, *spec.shape),
                       chunks=(IMAGE_CHUNK_FRAMES, *spec.shape), dtype=spec.dtype,
                       compressors=ZstdCodec(level=IMAGE_ZSTD_LEVEL), fill_value=0)
