"""Internal model: MLP over a short state history predicting the slow external wrench.

Per tick the features z = [q (7), dq (7), gripper width (1), p_ee (3), w_ext (6)] are normalized
with fixed constants, (z - FEATURE_OFFSET) / FEATURE_SCALE (no data-dependent normalizer since
the model learns online), and appended to a history of L ticks. The input is the history
flattened oldest-to-newest, row-major: x[t * 24 + i] = z_norm[t][i]. Output = network
output * OUTPUT_SCALE (10 N, 1 Nm). The torch module is the trained source of truth; per-tick
inference runs on a NumPy float32 copy of its weights that is refreshed after every SGD step,
``load`` and ``reinitialize``.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path

import numpy as np
import torch
from safetensors.torch import load_file, save_file

from impact_envs.control.config import InternalModelConfig
from impact_envs.control.internal_model_net import (
    FEATURE_DIM,
    FEATURE_NAMES,
    FEATURE_OFFSET,
    FEATURE_SCALE,
    FORMAT_VERSION,
    OUTPUT_SCALE,
    build_network,
)
from impact_envs.control.replay import ReplayBuffer
from impact_envs.control.surprise_gate import SurpriseGate
from impact_envs.errors import CheckpointError

__all__ = [
    "FEATURE_DIM",
    "FEATURE_NAMES",
    "FEATURE_OFFSET",
    "FEATURE_SCALE",
    "OUTPUT_SCALE",
    "InternalModel",
    "build_network",
]


class InternalModel:
    """Network + history + numpy fast path + surprise gate + replay + online SGD.

    Attributes:
        wrench_pred_world: Last prediction (6,) [N, Nm] (robot-on-environment sign).
        surprise_n: |w_pred - w_slow| over unmasked force axes of the last tick [N].
        gate: The hysteresis gate (``gate.is_open``).
        learning_active: Whether the last tick was a learning tick (gate open and quasi-steady).
        learning_enabled: Set False to freeze the weights (prediction and gate keep running).
        n_updates: SGD steps taken since construction / ``reinitialize``.
    """

    def __init__(self, config: InternalModelConfig | None = None) -> None:
        """Build the network (seeded) and all per-tick buffers."""
        self.config = config or InternalModelConfig()
        cfg = self.config
        self.input_dim = cfg.history_length * FEATURE_DIM
        self.net = build_network(cfg)
        self.optimizer = torch.optim.SGD(self.net.parameters(), lr=cfg.learning_rate)
        self.gate = SurpriseGate(cfg.surprise_open_n, cfg.surprise_release_n, cfg.slow_rate_max)
        self.replay = ReplayBuffer(cfg.replay_capacity, self.input_dim, 6, seed=cfg.seed)
        self.wrench_pred_world = np.zeros(6)
        self.surprise_n = 0.0
        self.learning_active = False
        self.learning_enabled = True
        self.n_updates = 0
        self._inv_feature_scale = (1.0 / FEATURE_SCALE).astype(np.float32)
        self._inv_output_scale = (1.0 / OUTPUT_SCALE).astype(np.float32)
        L = cfg.history_length
        # History stored twice (rows h and h + L) so the window oldest..newest is contiguous.
        self._hist = np.zeros((2 * L, FEATURE_DIM), dtype=np.float32)
        self._rows = list(self._hist)
        self._windows = [self._hist[h + 1 : h + 1 + L].reshape(-1) for h in range(L)]
        self._window = self._windows[0]
        self._head = 0
        self._filled = False
        self._tick = 0
        self._target = np.zeros(6, dtype=np.float32)
        self._mask = np.ones(6, dtype=np.float32)
        self._ones = np.ones(6, dtype=np.float32)
        self._batch_x = np.zeros((cfg.batch_size, self.input_dim), dtype=np.float32)
        self._batch_y = np.zeros((cfg.batch_size, 6), dtype=np.float32)
        self._batch_m = np.zeros((cfg.batch_size, 6), dtype=np.float32)
        self.refresh_fast_path()

    # ----------------------------------------------------------------- state management
    def refresh_fast_path(self) -> None:
        """Copy the torch weights into the NumPy fast path (call after editing ``net`` by hand).

        Layer 0 keeps (W, b); later layers store [W | b] and act on activations that carry a
        trailing constant 1, which saves one add per layer; OUTPUT_SCALE is folded into the last.
        """
        linears = [m for m in self.net if isinstance(m, torch.nn.Linear)]
        ws = [m.weight.detach().numpy() for m in linears]
        bs = [m.bias.detach().numpy() for m in linears]
        self._w0, self._b0 = ws[0].copy(), bs[0].copy()
        pairs = zip(ws[1:], bs[1:], strict=True)
        self._w_aug = [np.concatenate([w, b[:, None]], axis=1) for w, b in pairs]
        self._w_aug[-1] *= OUTPUT_SCALE[:, None]
        if not hasattr(self, "_acts"):
            self._acts = [np.ones(w.shape[0] + 1, dtype=np.float32) for w in ws[:-1]]
            self._act_views = [a[:-1] for a in self._acts]
            self._pred32 = np.zeros(6, dtype=np.float32)

    def reset_history(self) -> None:
        """Clear the history, gate and prediction; keep weights and replay samples."""
        self._filled = False
        self._head = 0
        self._tick = 0
        self.gate.reset()
        self.wrench_pred_world.fill(0.0)
        self.surprise_n = 0.0
        self.learning_active = False

    def reinitialize(self) -> None:
        """Restore the seeded initial weights, clear the replay buffer and the history."""
        fresh = build_network(self.config)
        self.net.load_state_dict(fresh.state_dict())
        self.optimizer = torch.optim.SGD(self.net.parameters(), lr=self.config.learning_rate)
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
        L = self.config.history_length
        h = self._head
        row = self._rows[h]
        np.concatenate((q, dq, (gripper_width_m,), pos_ee_world, wrench_ext_world), out=row)
        row -= FEATURE_OFFSET
        row *= self._inv_feature_scale
        if not self._filled:
            self._hist[:] = row
            self._filled = True
        else:
            self._rows[h + L][:] = row
        self._window = self._windows[h]
        self._head = (h + 1) % L

    def history_input(self) -> np.ndarray:
        """The current flattened normalized history (L * 24,) float32 (a view)."""
        if not self._filled:
            return np.zeros(self.input_dim, dtype=np.float32)
        return self._window

    def predict(self) -> np.ndarray:
        """NumPy forward pass on the current history -> ``wrench_pred_world`` (6,) [N, Nm]."""
        a0 = self._act_views[0]
        np.dot(self._w0, self.history_input(), out=a0)
        a0 += self._b0
        np.tanh(a0, out=a0)
        for i in range(1, len(self._acts)):
            a = self._act_views[i]
            np.dot(self._w_aug[i - 1], self._acts[i - 1], out=a)
            np.tanh(a, out=a)
        np.dot(self._w_aug[-1], self._acts[-1], out=self._pred32)
        self.wrench_pred_world[:] = self._pred32
        return self.wrench_pred_world

    def predict_torch(self, x: np.ndarray | None = None) -> np.ndarray:
        """Reference torch forward pass on ``x`` (default: current history) -> (6,) [N, Nm]."""
        x = self.history_input() if x is None else x
        with torch.no_grad():
            y = self.net(torch.from_numpy(np.ascontiguousarray(x, dtype=np.float32))[None])
        return y[0].numpy().astype(np.float64) * OUTPUT_SCALE

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
        if learn_mask is None:
            mask = self._ones
            px, py, pz = (pred[:3] - wrench_slow_world[:3]).tolist()
        else:
            mask = self._mask
            mask[:] = learn_mask
            px, py, pz = ((pred[:3] - wrench_slow_world[:3]) * mask[:3]).tolist()
        self.surprise_n = math.sqrt(px * px + py * py + pz * pz)
        learn = self.learning_enabled and self.gate.update(self.surprise_n, slow_rate)
        self.learning_active = learn
        if not self.learning_enabled:
            return pred
        tick = self._tick
        self._tick += 1
        store = tick % self.config.replay_period == 0 and slow_rate <= self.config.slow_rate_max
        train = learn and self._tick % self.config.update_every == 0
        if store or train:
            np.multiply(wrench_slow_world, self._inv_output_scale, out=self._target)
            if store:
                self.replay.add(self.history_input(), self._target, mask)
            if train:
                self.train_step(self.history_input(), self._target, mask)
        return pred

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
        pred = self.net(torch.from_numpy(bx))
        err = (pred - torch.from_numpy(by)) * torch.from_numpy(bm)
        loss = err.square().mean()
        self.optimizer.zero_grad(set_to_none=False)
        loss.backward()
        self.optimizer.step()
        self.n_updates += 1
        self.refresh_fast_path()
        return float(loss.detach())

    # ----------------------------------------------------------------- persistence
    def save(self, path: str | Path) -> Path:
        """Write weights to ``path`` (.safetensors) and the config to the same stem + .json."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tensors = {k: v.detach().contiguous() for k, v in self.net.state_dict().items()}
        save_file(tensors, str(path))
        meta = {"format_version": FORMAT_VERSION, "feature_names": list(FEATURE_NAMES)}
        meta["config"] = asdict(self.config)
        path.with_suffix(".json").write_text(json.dumps(meta, indent=2))
        return path

    def load(self, path: str | Path) -> None:
        """Load weights saved by ``save``; the network shape must match this model's config.

        Raises:
            CheckpointError: Missing files, other feature layout or network shape.
        """
        path = Path(path)
        meta_path = path.with_suffix(".json")
        if not path.is_file() or not meta_path.is_file():
            raise CheckpointError(f"missing internal model files {path} / {meta_path}")
        meta = json.loads(meta_path.read_text())
        saved = meta.get("config", {})
        same_shape = saved.get("history_length") == self.config.history_length and tuple(
            saved.get("hidden_sizes", ())
        ) == tuple(self.config.hidden_sizes)
        if meta.get("feature_names") != list(FEATURE_NAMES) or not same_shape:
            raise CheckpointError(f"internal model checkpoint {path} does not match the config")
        try:
            self.net.load_state_dict(load_file(str(path)))
        except (RuntimeError, OSError) as exc:
            raise CheckpointError(f"cannot load internal model weights {path}: {exc}") from exc
        self.refresh_fast_path()

    @classmethod
    def from_file(cls, path: str | Path) -> InternalModel:
        """Build a model with the saved config and load its weights."""
        meta_path = Path(path).with_suffix(".json")
        if not meta_path.is_file():
            raise CheckpointError(f"missing internal model config {meta_path}")
        saved = json.loads(meta_path.read_text()).get("config", {})
        try:
            config = InternalModelConfig(**saved)
        except TypeError as exc:
            raise CheckpointError(f"invalid internal model config in {meta_path}: {exc}") from exc
        model = cls(config)
        model.load(path)
        return model
