"""Fixed-size FIFO replay buffer of (history, target, mask) samples for online learning."""

from __future__ import annotations

import numpy as np

from impact_control.internal_model.learner import make_counters, unpack_counters


class ReplayBuffer:
    """Preallocated ring buffer; the oldest sample is overwritten when full.

    The arrays may be views of an ``InternalModel``'s learner (``learner.LearnerArrays``): the
    in-kernel learner and this class then read and write the same ring.

    Attributes:
        inputs: (capacity, input_dim) float32 normalized histories.
        targets: (capacity, output_dim) float32 normalized targets.
        masks: (capacity, output_dim) float32, 1 where the axis is learned, 0 where frozen.
        count: Number of valid samples.
    """

    def __init__(self, capacity: int, input_dim: int, output_dim: int, seed: int = 0,
                 storage: tuple[np.ndarray, ...] | None = None) -> None:
        """Allocate storage for ``capacity`` samples, or use ``storage`` = (inputs, targets,
        masks, scal) of a learner (``scal`` holds count and head); ``seed`` drives
        ``sample_indices``."""
        self.capacity = capacity
        if storage is None:
            storage = (np.zeros((capacity, input_dim), dtype=np.float32),
                       np.zeros((capacity, output_dim), dtype=np.float32),
                       np.zeros((capacity, output_dim), dtype=np.float32), make_counters())
        self.inputs, self.targets, self.masks, self._scal = storage
        self._counters = unpack_counters(self._scal)[0]
        self._seed = seed
        self._rng = np.random.default_rng(seed)

    @property
    def rng(self) -> np.random.Generator:
        """The generator of ``sample_indices`` (part of a snapshot's state)."""
        return self._rng

    @rng.setter
    def rng(self, value: np.random.Generator) -> None:
        self._rng = value

    @property
    def count(self) -> int:
        """Number of valid samples."""
        return int(self._counters.count[0])

    @count.setter
    def count(self, value: int) -> None:
        self._counters.count[0] = value

    @property
    def _head(self) -> int:
        return int(self._counters.head[0])

    @_head.setter
    def _head(self, value: int) -> None:
        self._counters.head[0] = value

    def clear(self) -> None:
        """Drop all samples and reseed the sampler."""
        self.count = 0
        self._head = 0
        self._rng = np.random.default_rng(self._seed)

    def copy_from(self, other: ReplayBuffer) -> None:
        """Hold a copy of ``other``'s samples (same shapes); the sampler is reseeded."""
        self.clear()
        self.inputs[:] = other.inputs
        self.targets[:] = other.targets
        self.masks[:] = other.masks
        self.count, self._head = other.count, other._head

    def add(self, x: np.ndarray, target: np.ndarray, mask: np.ndarray) -> None:
        """Store one sample (copied)."""
        i = self._head
        self.inputs[i] = x
        self.targets[i] = target
        self.masks[i] = mask
        self._head = (i + 1) % self.capacity
        self.count = min(self.count + 1, self.capacity)

    def sample_indices(self, n: int) -> np.ndarray:
        """Up to ``n`` indices drawn uniformly with replacement (empty if the buffer is empty)."""
        if self.count == 0 or n <= 0:
            return np.zeros(0, dtype=np.int64)
        return self._rng.integers(0, self.count, size=n)
