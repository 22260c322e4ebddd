"""Fixed-size FIFO replay buffer of (history, target, mask) samples for online learning."""

from __future__ import annotations

import numpy as np


class ReplayBuffer:
    """Preallocated ring buffer; the oldest sample is overwritten when full.

    Attributes:
        inputs: (capacity, input_dim) float32 normalized histories.
        targets: (capacity, output_dim) float32 normalized targets.
        masks: (capacity, output_dim) float32, 1 where the axis is learned, 0 where frozen.
        count: Number of valid samples.
    """

    def __init__(self, capacity: int, input_dim: int, output_dim: int, seed: int = 0) -> None:
        """Allocate storage for ``capacity`` samples; ``seed`` drives ``sample``."""
        self.capacity = capacity
        self.inputs = np.zeros((capacity, input_dim), dtype=np.float32)
        self.targets = np.zeros((capacity, output_dim), dtype=np.float32)
        self.masks = np.zeros((capacity, output_dim), dtype=np.float32)
        self.count = 0
        self._head = 0
        self._seed = seed
        self._rng = np.random.default_rng(seed)

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
