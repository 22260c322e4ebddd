"""Internal model: MLP over a short state history predicting the slow external wrench.

Per tick the features z = [q (7), dq (7), gripper width (1), p_ee (3), w_ext (6)] are normalized
with fixed constants, (z - FEATURE_OFFSET) / FEATURE_SCALE (no data-dependent normalizer since
the model learns online), and appended to a history of L ticks. The input is the history
flattened oldest-to-newest, row-major: x[t * 24 + i] = z_norm[t][i]. Output = network
output * OUTPUT_SCALE (10 N, 1 Nm). The network's float32 arrays (``net.MLP``) are the trained
source of truth; per-tick inference runs in numba (``kernels.mlp_forward``) on those same
arrays, and SGD steps, ``load`` and ``reinitialize`` change them in place, so they are seen
without copying.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.internal_model import kernels
from impact_control.internal_model.checkpoint import read_config, read_weights, write_checkpoint
from impact_control.internal_model.config import InternalModelConfig
from impact_control.internal_model.gate import SurpriseGate
from impact_control.internal_model.learner import (
    LearnerArrays,
    make_learner,
    unpack_counters,
)
from impact_control.internal_model.net import (
    FEATURE_DIM,
    FEATURE_NAMES,
    FEATURE_OFFSET,
    FEATURE_SCALE,
    MLP,
    OUTPUT_SCALE,
    build_network,
    sgd_step,
)
from impact_control.internal_model.replay import ReplayBuffer
from impact_control.kernel_layout import STORE, TRAIN

__all__ = ["InternalModel", "ModelSnapshot"]


@dataclass(frozen=True)
class ModelSnapshot:
    """What an ``InternalModel`` has learned: network weights and the replay buffer."""

    weights: dict[str, np.ndarray]
    replay: ReplayBuffer


class InternalModel:
    """Network + history + numba fast path + surprise gate + replay + online SGD.

    Per-tick work (feature push, forward pass, surprise, gate, replay/SGD schedule) is
    ``kernels.push_features`` / ``model_predict`` / ``model_gate_step`` on ``kernel_args()``
    (layouts: ``kernels.unpack_model``, ``unpack_model32``); only the replay insert and the SGD
    step (``learn``) run in Python.

    Attributes:
        wrench_pred_world: Last prediction (6,) [N, Nm] (robot-on-environment sign).
        surprise_n: |w_pred - w_slow| over unmasked force axes of the last tick [N].
        gate: The hysteresis gate (``gate.is_open``).
        learning_active: Whether the last tick was a learning tick (gate open and quasi-steady).
        learning_enabled: Set False to freeze the weights (prediction and surprise keep
            running; the gate holds its state).
        n_updates: SGD steps taken since construction / ``reinitialize``.
        n_divergences: SGD steps whose loss or resulting weights were not finite; each one
            re-initialises the model (seeded weights, empty replay), so a diverging learner
            can never feed a non-finite prediction forward.
    """

    STATELESS: tuple[str, ...] = ("_inv_output_scale", "_ones", "_target", "_mask",
                                  "_batch_x", "_batch_y", "_batch_m")
    """Array attributes that carry nothing from one tick to the next: constants, and the
    NumPy learner's per-call scratch (filled before every use)."""

    def __init__(self, config: InternalModelConfig | None = None) -> None:
        """Build the network (seeded) and all per-tick buffers."""
        self.config = config or InternalModelConfig()
        cfg = self.config
        self.input_dim = cfg.history_length * FEATURE_DIM
        self.net: MLP = build_network(cfg)
        weights = self.net.weights
        self.learner: LearnerArrays = make_learner(
            cfg.replay_capacity, cfg.batch_size, self.input_dim, weights, cfg.learning_rate,
            cfg.samples_per_tick, cfg.learner == "numba")
        lrn = self.learner
        self._counters = unpack_counters(lrn.scal)[0]  # named views, made once
        self.replay = ReplayBuffer(cfg.replay_capacity, self.input_dim, 6, seed=cfg.seed,
                                   storage=(lrn.inputs, lrn.targets, lrn.masks, lrn.scal))
        self._reseed_learner()
        self.n_divergences = 0
        self._init_kernel_buffers()
        self.gate = SurpriseGate(cfg.surprise_open_n, cfg.surprise_release_n, cfg.slow_rate_max,
                                 state=self.state.gate_open)
        self._inv_output_scale = (1.0 / OUTPUT_SCALE).astype(np.float32)
        self._target = np.zeros(6, dtype=np.float32)
        self._mask = np.ones(6, dtype=np.float32)
        self._ones = np.ones(6, dtype=np.float32)
        self._batch_x = np.zeros((cfg.batch_size, self.input_dim), dtype=np.float32)
        self._batch_y = np.zeros((cfg.batch_size, 6), dtype=np.float32)
        self._batch_m = np.zeros((cfg.batch_size, 6), dtype=np.float32)
        self.refresh_fast_path()

    def _init_kernel_buffers(self) -> None:
        """Allocate the float32 (features, history) and float64 (parameters, state) buffers."""
        cfg = self.config
        L, F = cfg.history_length, FEATURE_DIM
        self._buf32 = np.zeros(kernels.model32_size(L, F), dtype=np.float32)
        self.inputs = m32 = kernels.unpack_model32(self._buf32, F)
        offset, inv_scale, hist = m32.offset, m32.inv_scale, m32.hist
        offset[:] = FEATURE_OFFSET
        inv_scale[:] = 1.0 / FEATURE_SCALE
        if not cfg.wrench_feature:  # the estimated-wrench inputs then read 0 on every tick
            inv_scale[np.asarray(FEATURE_NAMES) == "w_ext"] = 0.0
        # History stored twice (rows h and h + L) so the window oldest..newest is contiguous.
        self._hist = hist.reshape(2 * L, F)
        self._windows = [self._hist[h + 1 : h + 1 + L].reshape(-1) for h in range(L)]
        width = max(cfg.hidden_sizes)
        self.buffer = np.zeros(kernels.model_size(width))
        self.buffer[kernels.MODEL_LAYOUT.offset("params__max_hidden")] = width  # sizes acts
        self.state = m = kernels.unpack_model(self.buffer)[0]
        p = m.params
        p.open_n[0], p.release_n[0] = cfg.surprise_open_n, cfg.surprise_release_n
        p.slow_rate_max[0], p.replay_period[0] = cfg.slow_rate_max, cfg.replay_period
        p.update_every[0], m.learning_enabled[0] = cfg.update_every, 1.0
        p.history_length[0], p.n_features[0] = L, F
        p.out_scale[:] = OUTPUT_SCALE
        self.wrench_pred_world = m.pred

    # ----------------------------------------------------------------- state management
    @property
    def n_updates(self) -> int:
        """SGD steps taken since construction / ``reinitialize``."""
        return int(self._counters.n_updates[0])

    @n_updates.setter
    def n_updates(self, value: int) -> None:
        self._counters.n_updates[0] = value

    def _reseed_learner(self) -> None:
        """Drop a pending in-kernel SGD step and reseed its replay sampler."""
        self._counters.pending[0] = 0.0
        self.learner.rng[0] = np.uint64(self.config.seed)

    @property
    def surprise_n(self) -> float:
        """Force surprise of the last tick [N]."""
        return float(self.state.surprise[0])

    @property
    def learning_active(self) -> bool:
        """Whether the last tick was a learning tick."""
        return bool(self.state.learning_active[0])

    @property
    def learning_enabled(self) -> bool:
        """False freezes the weights (prediction and surprise keep running, the gate stops)."""
        return bool(self.state.learning_enabled[0])

    @learning_enabled.setter
    def learning_enabled(self, value: bool) -> None:
        self.state.learning_enabled[0] = float(value)

    def refresh_fast_path(self) -> None:
        """Re-bind the fast path to the network's arrays (call after replacing ``net``).

        The forward kernel reads the network's own arrays, so in-place changes (SGD steps,
        ``load_state_dict``, editing them) are seen without copying; OUTPUT_SCALE is applied
        after the last layer.
        """
        self._weights = self.net.weights
        self._biases = self.net.biases

    def kernel_args(self) -> tuple:
        """(float32 buffer, weights, biases, float64 buffer, learner) of the model kernels."""
        return self._buf32, self._weights, self._biases, self.buffer, self.learner

    def reset_history(self) -> None:
        """Clear the history, gate and prediction; keep weights and replay samples."""
        self._hist.fill(0.0)
        m = self.state
        for per_tick in (m.head, m.filled, m.tick, m.gate_open, m.surprise, m.learning_active):
            per_tick.fill(0.0)
        self.wrench_pred_world.fill(0.0)
        self._reseed_learner()

    def reinitialize(self) -> None:
        """Restore the seeded initial weights, clear the replay buffer and the history."""
        fresh = build_network(self.config)
        self.net.load_state_dict(fresh.state_dict())
        self.replay.clear()
        self.n_updates = 0
        self.refresh_fast_path()
        self.reset_history()

    # ----------------------------------------------------------------- inference
    def push(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        gripper_width_m: float,
        pos_ee_world: np.ndarray,
        wrench_ext_world: np.ndarray,
    ) -> None:
        """Append one tick of features (the first push after a reset fills the whole history)."""
        f64 = np.float64
        kernels.push_features(
            np.asarray(q, f64), np.asarray(dq, f64), float(gripper_width_m),
            np.asarray(pos_ee_world, f64), np.asarray(wrench_ext_world, f64),
            self.inputs, self.state,
        )  # fmt: skip

    def history_input(self) -> np.ndarray:
        """The current flattened normalized history (L * 24,) float32 (a view)."""
        head, filled = self.state.head[0], self.state.filled[0]
        if not filled:
            return np.zeros(self.input_dim, dtype=np.float32)
        return self._windows[(int(head) - 1) % self.config.history_length]

    def predict(self) -> np.ndarray:
        """Forward pass on the current history -> ``wrench_pred_world`` (6,) [N, Nm]."""
        kernels.model_predict(self.inputs, self._weights, self._biases, self.state)
        return self.wrench_pred_world

    def predict_reference(self, x: np.ndarray | None = None) -> np.ndarray:
        """Reference NumPy forward pass on ``x`` (default: current history) -> (6,) [N, Nm]."""
        x = self.history_input() if x is None else x
        y = self.net.forward(np.ascontiguousarray(x, dtype=np.float32)[None])
        return y[0].astype(np.float64) * OUTPUT_SCALE

    # ----------------------------------------------------------------- learning
    def step(
        self,
        wrench_slow_world: np.ndarray,
        slow_rate: float,
        learn_mask: np.ndarray | None = None,
    ) -> np.ndarray:
        """Predict, update the gate, store replay samples and learn; call after ``push``.

        Args:
            wrench_slow_world: Training target w_slow (6,) [N, Nm].
            slow_rate: Dimensionless slow-wrench rate (``SlowWrenchFilter.slow_rate``).
            learn_mask: 6 bools; False freezes that axis (zero loss, excluded from surprise).

        Returns:
            The prediction made *before* any update on this tick (6,) [N, Nm].
        """
        pred = self.predict()
        mask = self.mask_array(learn_mask)
        w_slow = np.asarray(wrench_slow_world, dtype=np.float64)
        flags = kernels.model_gate_step(w_slow, float(slow_rate), mask, self.state)
        if flags:
            self.learn(flags, w_slow, mask)
        return pred

    def mask_array(self, learn_mask: np.ndarray | None) -> np.ndarray:
        """float32 (6,) learning mask: ones for None, else a copy of ``learn_mask``."""
        if learn_mask is None:
            return self._ones
        mask = np.asarray(learn_mask, dtype=np.float64)
        if mask.shape != (6,) or not np.all((mask >= 0.0) & (mask <= 1.0)):
            raise InvalidArgumentError(f"invalid learn_mask {learn_mask!r}; valid: None or 6 "
                                       "bools / weights in [0, 1], one per wrench axis")
        self._mask[:] = mask
        return self._mask

    def learn(self, flags: int, wrench_slow_world: np.ndarray, mask: np.ndarray) -> None:
        """Store a replay sample (``flags & STORE``) and/or take an SGD step (``& TRAIN``)."""
        np.multiply(wrench_slow_world, self._inv_output_scale, out=self._target)
        if flags & STORE:
            self.replay.add(self.history_input(), self._target, mask)
        if flags & TRAIN:
            self.train_step(self.history_input(), self._target, mask)

    def train_step(self, x: np.ndarray, target: np.ndarray, mask: np.ndarray) -> float:
        """One SGD step on [current sample] + replayed samples; returns the loss.

        Args:
            x: Normalized history (L * 24,).
            target: Normalized target (6,) (wrench / OUTPUT_SCALE).
            mask: (6,) 1 = learn this axis, 0 = frozen (target := current prediction).
        """
        idx = self.replay.sample_indices(self.config.batch_size - 1)
        n = 1 + len(idx)
        bx, by, bm = self._batch_x[:n], self._batch_y[:n], self._batch_m[:n]
        bx[0], by[0], bm[0] = x, target, mask
        if len(idx):
            np.take(self.replay.inputs, idx, axis=0, out=bx[1:])
            np.take(self.replay.targets, idx, axis=0, out=by[1:])
            np.take(self.replay.masks, idx, axis=0, out=bm[1:])
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is handled below
            loss = sgd_step(self._weights, self._biases, bx, by, bm, self.config.learning_rate)
        self.n_updates += 1  # the fast path shares the weights' memory: no refresh
        if not (math.isfinite(loss) and self._parameters_finite()):
            self.diverged()
        return loss

    def diverged(self) -> None:
        """After an SGD step left a non-finite loss or weight (inputs far outside any
        payload): re-initialise (seeded weights, empty replay) and count it."""
        self.reinitialize()
        self.n_divergences += 1

    def _parameters_finite(self) -> bool:
        """Whether every weight and bias is finite (~6 us, once per SGD step)."""
        return all(np.isfinite(a).all() for a in (*self._weights, *self._biases))

    # ----------------------------------------------------------------- persistence
    def python_state(self) -> dict[str, Any]:
        """What is not an array (copies): the replay sampler's generator and the divergence
        count (the arrays are ``kernel_args()``, walked by ``ImpactController.state_arrays``)."""
        return {"replay_rng": copy.deepcopy(self.replay.rng),
                "n_divergences": self.n_divergences}

    def load_python_state(self, state: dict[str, Any]) -> None:
        """Set what ``python_state`` returned."""
        self.replay.rng = copy.deepcopy(state["replay_rng"])
        self.n_divergences = int(state["n_divergences"])

    def snapshot(self) -> ModelSnapshot:
        """A copy of what the model has learned: weights and replay samples."""
        replay = ReplayBuffer(self.replay.capacity, self.input_dim, 6, seed=self.config.seed)
        replay.copy_from(self.replay)
        weights = {k: v.copy() for k, v in self.net.state_dict().items()}
        return ModelSnapshot(weights, replay)

    def restore(self, snapshot: ModelSnapshot) -> None:
        """Set weights and replay samples to (copies of) ``snapshot``'s; clear the history.

        Raises:
            CheckpointError: The snapshot comes from a model of another shape.
        """
        try:
            self.net.load_state_dict(snapshot.weights)
            self.replay.copy_from(snapshot.replay)
        except (RuntimeError, ValueError) as exc:
            raise CheckpointError(f"internal model snapshot does not fit: {exc}") from None
        self.refresh_fast_path()
        self.reset_history()

    def save(self, path: str | Path) -> Path:
        """Write weights to ``path`` (.safetensors) and the config to the same stem + .json
        (``checkpoint.write_checkpoint``)."""
        return write_checkpoint(path, self.net.state_dict(), self.config)

    def load(self, path: str | Path) -> None:
        """Load weights saved by ``save``; the network shape must match this model's config.

        Raises:
            CheckpointError: Missing files, other feature layout or network shape.
        """
        weights = read_weights(path, self.config)
        try:
            self.net.load_state_dict(weights)
        except (RuntimeError, ValueError) as exc:
            raise CheckpointError(f"cannot load internal model weights {path}: {exc}") from exc
        self.refresh_fast_path()

    @classmethod
    def from_file(cls, path: str | Path) -> InternalModel:
        """Build a model with the saved config and load its weights."""
        model = cls(read_config(path))
        model.load(path)
        return model
