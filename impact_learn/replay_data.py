"""Loading a demonstration store (``dataset.py``'s layout) into memory, every chunk checked."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_learn.store_check import StoreLayout, open_store, scan_store, store_layout
from impact_learn.store_checksums import DamagedStoreError
from impact_learn.store_format import ACTION_DIM, ACTION_KEY, CHECKSUM_ATTR, META_DTYPES


@dataclass(frozen=True)
class ReplayData:
    """A whole demonstration store loaded into memory.

    Attributes:
        data: ``{key: (N, d)}`` float32 arrays, including ``"action"`` ``(N, 10)``.
        episode_ends: ``(E,)`` exclusive end indices.
        meta: ``{name: (E,)}`` per-episode metadata (``episode_param``, ``episode_seed``, ...).
        attrs: Store attributes (without the checksum record).
        fingerprints: ``{"data/<key>" | "meta/<key>": digest}`` of each array's content (a
            training run records those it uses, so ``--resume`` can refuse other data).
    """

    data: dict[str, np.ndarray]
    episode_ends: np.ndarray
    meta: dict[str, np.ndarray]
    attrs: dict[str, Any]
    fingerprints: dict[str, str] = field(default_factory=dict)

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
    """Load a store written by ``ReplayWriter`` (complete episodes only), every chunk checked
    against its checksum (``store_check.scan_store``); bad input is a one-line error."""
    layout = checked_layout(path)
    scan = scan_store(layout, path, load=True)
    data = {k[5:]: v for k, v in scan.values.items() if k.startswith("data/")}
    meta = {k: scan.values[f"meta/{k}"] for k in META_DTYPES}
    attrs = {k: v for k, v in layout.root.attrs.items() if k != CHECKSUM_ATTR}
    return ReplayData(data, layout.ends, meta, attrs, scan.fingerprints())


def checked_layout(path: str | Path) -> StoreLayout:
    """Open a store for reading and check its layout (``store_check.store_layout``); a store
    without episodes is refused."""
    layout = store_layout(open_store(path), path)
    if len(layout.ends) == 0:
        raise InvalidArgumentError(
            f"{path} holds no episodes with actions (data/{ACTION_KEY}, meta/episode_ends)")
    if layout.arrays[f"data/{ACTION_KEY}"].shape[1:] != (ACTION_DIM,):
        raise DamagedStoreError(path, f"data/{ACTION_KEY} has shape "
                                f"{layout.arrays[f'data/{ACTION_KEY}'].shape}; valid: (N, 10)")
    return layout
