"""The checksum record of a demonstration store (``store_check.py`` reads it, ``ReplayWriter``
writes it): per array its rows, rows per chunk and a digest of each chunk's decoded values."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_learn.store_format import CHECKSUM_ATTR

ALGORITHM = "sha256-128"
"""SHA-256 truncated to 128 bits (32 hex digits); with the SHA instructions of current x86 CPUs
it hashes faster than BLAKE2b (docs/diffusion_policy.md, "Checks of a store")."""


class DamagedStoreError(InvalidArgumentError):
    """A store whose arrays are missing, short, non-finite or differ from their checksums."""

    def __init__(self, path: str | Path, detail: str) -> None:
        self.path, self.detail = str(path), detail
        super().__init__(f"{path}: the store is damaged: {detail}; collect it again")


def digest(values: np.ndarray) -> str:
    """The first 32 hex digits of the SHA-256 of the C-ordered bytes of ``values``."""
    return hashlib.sha256(np.ascontiguousarray(values).data).hexdigest()[:32]


def chunk_digests(values: np.ndarray, chunk_rows: int) -> list[str]:
    """One ``digest`` per block of ``chunk_rows`` rows of ``values`` (the last may be short)."""
    return [digest(values[i:i + chunk_rows]) for i in range(0, len(values), chunk_rows)]


@dataclass
class ArraySums:
    """Checksums of one array: rows covered, rows per chunk, one digest per chunk."""

    rows: int
    chunk_rows: int
    chunks: list[str] = field(default_factory=list)


class Checksums:
    """A store's checksum record, extended as episodes are appended.

    Args:
        arrays: ``{"data/<key>" | "meta/<key>": ArraySums}``.
    """

    def __init__(self, arrays: dict[str, ArraySums]) -> None:
        self.arrays = arrays
        self.tails: dict[str, np.ndarray] = {}
        """Rows of each array's last, partial chunk (what the next append's digest needs)."""

    @classmethod
    def empty(cls, chunk_rows: Mapping[str, int]) -> Checksums:
        """The record of a new store whose arrays hold no rows."""
        return cls({name: ArraySums(0, rows) for name, rows in chunk_rows.items()})

    def set_tail(self, name: str, tail: np.ndarray) -> None:
        """The rows of ``name``'s last partial chunk, as stored."""
        self.tails[name] = np.array(tail)

    def extend(self, name: str, rows: np.ndarray) -> None:
        """Account for ``rows`` appended to array ``name`` (as stored: dtype and shape)."""
        sums, tail = self.arrays[name], self.tails.get(name)
        block = rows if tail is None or not len(tail) else np.concatenate([tail, rows])
        first = (sums.rows + len(rows) - len(block)) // sums.chunk_rows
        sums.chunks[first:] = chunk_digests(block, sums.chunk_rows)
        sums.rows += len(rows)
        keep = sums.rows % sums.chunk_rows
        self.set_tail(name, block[len(block) - keep:])

    def to_attr(self) -> dict[str, Any]:
        """The JSON value of the store attribute ``checksums``."""
        return {"algorithm": ALGORITHM,
                "arrays": {name: {"rows": s.rows, "chunk_rows": s.chunk_rows, "chunks": s.chunks}
                           for name, s in sorted(self.arrays.items())}}

    @classmethod
    def from_attr(cls, value: object, path: str | Path) -> Checksums:
        """Parse the attribute (a malformed one is a ``DamagedStoreError``)."""
        algorithm = value.get("algorithm") if isinstance(value, dict) else None
        if algorithm is not None and algorithm != ALGORITHM:
            raise DamagedStoreError(path, f"its checksums use {algorithm!r}; valid: {ALGORITHM!r}")
        try:
            assert isinstance(value, dict) and algorithm == ALGORITHM
            arrays = {str(name): ArraySums(int(s["rows"]), int(s["chunk_rows"]),
                                           [str(c) for c in s["chunks"]])
                      for name, s in value["arrays"].items()}
        except (AssertionError, KeyError, TypeError, ValueError, AttributeError):
            raise DamagedStoreError(path, f"its {CHECKSUM_ATTR!r} attribute is malformed") from None
        return cls(arrays)
