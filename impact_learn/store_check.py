"""Checks of a demonstration store before a run reads or resumes it.

``ReplayWriter`` records a checksum (SHA-256, 128 bits kept) of every chunk of every array as it
appends, in the store attribute ``checksums``: per array its rows, rows per chunk and one digest
per chunk of the decoded values. A chunk file that is deleted (zarr then reads the fill value:
black frames, zero states), truncated, corrupted or moved to another array no longer matches.

``store_layout`` checks what can be checked without reading the data (``episode_ends``
increasing, every required array present, no array shorter than the rows it must hold);
``scan_store`` reads every chunk once, refuses non-finite state and action values and compares
every chunk with its checksum. Stores written before checksums existed have no record: their
chunks must decode, and an image array must have every chunk file (a missing one reads as
black frames).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import zarr

from impact_control.errors import InvalidArgumentError
from impact_learn.store_checksums import ArraySums, Checksums, DamagedStoreError, digest
from impact_learn.store_format import CHECKSUM_ATTR, REQUIRED_ARRAYS


def open_store(path: str | Path, mode: str = "r") -> zarr.Group:
    """Open an ``impact-collect`` store (one-line error for a missing or foreign path)."""
    if not Path(path).exists():
        raise InvalidArgumentError(f"dataset {path} does not exist")
    try:
        root = zarr.open_group(str(path), mode=mode)
        root["meta/episode_ends"]
        root["data"]
    except Exception as exc:  # noqa: BLE001 - zarr raises many types for foreign stores
        msg = " ".join(str(exc).split())[:120]
        raise InvalidArgumentError(
            f"{path} is not a readable demonstration store (impact-collect's zarr layout): "
            f"{type(exc).__name__}: {msg}") from None
    return root


@dataclass(frozen=True)
class StoreLayout:
    """A store's arrays and the rows each must hold.

    Attributes:
        root: The open store.
        ends: ``meta/episode_ends`` (strictly increasing, first > 0).
        arrays: ``{"data/<key>" | "meta/<key>": array}``.
        rows: Rows in use per array: ``ends[-1]`` for data arrays, ``len(ends)`` for meta.
    """

    root: zarr.Group
    ends: np.ndarray
    arrays: dict[str, zarr.Array]
    rows: dict[str, int]


def store_layout(root: zarr.Group, path: str | Path) -> StoreLayout:
    """Check the store's shape without reading its data (one line naming what is wrong)."""
    arrays = _arrays(root, path)
    try:
        ends_arr = arrays.get("meta/episode_ends")
        ends = np.asarray(ends_arr[:]) if ends_arr is not None else np.zeros(0, np.int64)
    except Exception as exc:  # noqa: BLE001 - zarr/numcodecs raise many types
        raise DamagedStoreError(path, f"meta/episode_ends cannot be read ({type(exc).__name__})"
                                ) from None
    missing = [name for name in REQUIRED_ARRAYS if name not in arrays]
    if missing:
        raise DamagedStoreError(path, f"{', '.join(missing)} missing")
    _check_ends(ends, path)
    n_steps, n_eps = (int(ends[-1]) if len(ends) else 0), len(ends)
    rows = {name: n_steps if name.startswith("data/") else n_eps for name in arrays}
    for name, arr in arrays.items():
        ndims = (2, 4) if name.startswith("data/") else (1,)
        if arr.ndim not in ndims:
            raise DamagedStoreError(path, f"{name} has {arr.ndim} dimensions; valid: {ndims}")
        if arr.shape[0] < rows[name]:
            raise DamagedStoreError(
                path, f"{name} holds {arr.shape[0]} rows but meta/episode_ends needs "
                f"{rows[name]} (the array is truncated)")
    return StoreLayout(root, ends.astype(np.int64), arrays, rows)


def _arrays(root: zarr.Group, path: str | Path) -> dict[str, zarr.Array]:
    """``{"data/<key>" | "meta/<key>": array}``: every folder of the two groups, each of which
    must read as an array (a missing or unreadable ``zarr.json`` is damage, named)."""
    names = sorted(f"{group}/{p.name}" for group in ("data", "meta")
                   if (Path(path) / group).is_dir() for p in (Path(path) / group).iterdir()
                   if p.is_dir())
    arrays = {}
    for name in names:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # zarr warns of folders it does not recognize
                arr = root[name]
        except Exception as exc:  # noqa: BLE001 - zarr raises many types on bad metadata
            msg = " ".join(str(exc).split())[:80]
            raise DamagedStoreError(path, f"{name} is not a readable array "
                                    f"({type(exc).__name__}: {msg})") from None
        if not isinstance(arr, zarr.Array):
            raise DamagedStoreError(path, f"{name} is not an array")
        arrays[name] = arr
    return arrays


def _check_ends(ends: np.ndarray, path: str | Path) -> None:
    if ends.ndim != 1 or not np.issubdtype(ends.dtype, np.integer):
        raise DamagedStoreError(path, f"meta/episode_ends is {ends.dtype} {ends.shape}; "
                                "valid: 1-D integers")
    steps = np.diff(np.concatenate([[0], ends]))
    if len(steps) and steps.min() <= 0:
        ep = int(np.argmax(steps <= 0))
        raise DamagedStoreError(
            path, f"meta/episode_ends does not increase at episode {ep} "
            f"({int(ends[ep - 1]) if ep else 0} -> {int(ends[ep])})")


@dataclass
class ScanResult:
    """What ``scan_store`` read.

    Attributes:
        values: ``{name: rows in use}`` (only with ``load=True``).
        digests: ``{name: chunk digests}`` of the rows checked.
        checked_rows: ``{name: rows checked}`` (fewer than in use only with
            ``allow_unrecorded``: rows appended after the record was last written).
        recorded: Whether the store had a checksum record.
    """

    values: dict[str, np.ndarray]
    digests: dict[str, list[str]]
    checked_rows: dict[str, int]
    recorded: bool

    def checksums(self, layout: StoreLayout) -> Checksums:
        """The record of the rows checked (a writer extends it with later rows)."""
        return Checksums({name: ArraySums(self.checked_rows[name],
                                          layout.arrays[name].chunks[0], list(digests))
                          for name, digests in self.digests.items()})

    def fingerprints(self) -> dict[str, str]:
        """One digest per array over its chunk digests (what a training run records)."""
        return {name: digest(np.frombuffer("".join(d).encode(), np.uint8))
                for name, d in self.digests.items()}


def scan_store(layout: StoreLayout, path: str | Path, *, load: bool,
               allow_unrecorded: bool = False) -> ScanResult:
    """Read every chunk of every array once; refuse non-finite state/action values and any
    chunk that differs from its checksum (``DamagedStoreError``, one line)."""
    value = layout.root.attrs.get(CHECKSUM_ATTR)
    record = None if value is None else Checksums.from_attr(value, path).arrays
    if record is not None:
        extra = sorted(set(layout.arrays) - set(record))
        lost = sorted(set(record) - set(layout.arrays))
        if extra or lost:
            what = f"{', '.join(lost)} missing" if lost else f"{', '.join(extra)} not recorded"
            raise DamagedStoreError(path, f"{what} (its checksum record lists other arrays)")
    result = ScanResult({}, {}, {}, record is not None)
    for name, arr in layout.arrays.items():
        upto = layout.rows[name]
        sums = None if record is None else record[name]
        if sums is not None:
            _check_record(name, sums, upto, arr, path, allow_unrecorded)
            upto = sums.rows
        elif arr.ndim == 4:
            _check_chunk_files(name, arr, path)
        values, digests = _scan_array(arr, name, upto, layout.ends, path, load)
        if sums is not None:
            _compare(name, digests, sums, path)
        result.digests[name], result.checked_rows[name] = digests, upto
        if load:
            result.values[name] = values
    return result


def _check_record(name: str, sums: ArraySums, rows: int, arr: zarr.Array, path: str | Path,
                  allow_unrecorded: bool) -> None:
    if sums.chunk_rows != arr.chunks[0]:
        raise DamagedStoreError(path, f"{name} has chunks of {arr.chunks[0]} rows, its "
                                f"checksums {sums.chunk_rows}")
    if sums.rows > rows or (sums.rows < rows and not allow_unrecorded):
        reason = ("an interrupted impact-collect: --resume finishes it" if sums.rows < rows
                  else "meta/episode_ends was shortened")
        raise DamagedStoreError(path, f"{name} has checksums for {sums.rows} rows but holds "
                                f"{rows} ({reason})")


def _check_chunk_files(name: str, arr: zarr.Array, path: str | Path) -> None:
    expected = arr.nchunks
    if arr.nchunks_initialized < expected:
        raise DamagedStoreError(
            path, f"{expected - arr.nchunks_initialized} of {expected} chunk files of {name} "
            "are missing (this store predates checksums; a missing chunk reads as black frames)")


def _scan_array(arr: zarr.Array, name: str, rows: int, ends: np.ndarray, path: str | Path,
                load: bool) -> tuple[np.ndarray, list[str]]:
    """``(values or an empty array, chunk digests)`` of ``arr[:rows]``; non-finite values of
    a float state or action array are refused."""
    step = arr.chunks[0]
    values = np.empty((rows, *arr.shape[1:]), arr.dtype) if load else np.zeros(0)
    digests, bad_rows, bad = [], [], 0
    for start in range(0, rows, step):
        block = _read(arr, name, start, min(start + step, rows), path)
        if load:
            values[start:start + step] = block
        digests.append(digest(block))
        if arr.ndim == 2 and name.startswith("data/") and block.dtype.kind == "f":
            finite = np.isfinite(block)
            if not finite.all():
                bad += int((~finite).sum())
                bad_rows.append(start + np.flatnonzero(~finite.all(axis=1)))
    if bad:
        episodes = np.unique(np.searchsorted(ends, np.concatenate(bad_rows), side="right"))
        more = " ..." if len(episodes) > 5 else ""
        raise DamagedStoreError(path, f"{name} holds {bad} non-finite values (NaN/inf) in "
                                f"episodes {episodes[:5].tolist()}{more}")
    return values, digests


def _read(arr: zarr.Array, name: str, start: int, stop: int, path: str | Path) -> np.ndarray:
    try:
        return np.asarray(arr[start:stop])
    except Exception as exc:  # noqa: BLE001 - zarr/numcodecs raise many types on a torn chunk
        msg = " ".join(str(exc).split())[:100]
        raise DamagedStoreError(
            path, f"{name} chunk {start // arr.chunks[0]} (rows {start}-{stop - 1}) cannot be "
            f"decoded ({type(exc).__name__}: {msg})") from None


def _compare(name: str, digests: list[str], sums: ArraySums, path: str | Path) -> None:
    for i, (got, want) in enumerate(zip(digests, sums.chunks, strict=False)):
        if got != want:
            last = min((i + 1) * sums.chunk_rows, sums.rows) - 1
            raise DamagedStoreError(
                path, f"{name} chunk {i} (rows {i * sums.chunk_rows}-{last}) differs from the "
                "checksum written with it (deleted, corrupted or edited)")
    if len(digests) != len(sums.chunks):
        raise DamagedStoreError(path, f"{name} has {len(sums.chunks)} chunk checksums for "
                                f"{len(digests)} chunks")
