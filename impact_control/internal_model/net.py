"""Feature layout, fixed normalisation constants, network and SGD step of the internal model."""

from __future__ import annotations

import math

import numpy as np

from impact_control.internal_model.config import InternalModelConfig

FEATURE_NAMES = ("q",) * 7 + ("dq",) * 7 + ("gripper_width",) + ("pos_ee",) * 3 + ("w_ext",) * 6
FEATURE_DIM = len(FEATURE_NAMES)
FEATURE_OFFSET = np.array(
    [0.0, 0.0, 0.0, -1.59695, 0.0, 2.5307, 0.0]  # FR3 joint-range midpoints [rad]
    + [0.0] * 7  # [rad/s]
    + [0.04]  # half of the 0.08 m stroke [m]
    + [0.5, 0.0, 0.3]  # workspace centre [m]
    + [0.0] * 6,  # [N, Nm]
    dtype=np.float32,
)
FEATURE_SCALE = np.array(
    [2.7437, 1.7837, 2.9007, 1.44515, 2.8065, 1.9862, 3.0159]  # FR3 half ranges [rad]
    + [1.0] * 7  # [rad/s]
    + [0.04]  # [m]
    + [0.3] * 3  # [m]
    + [10.0] * 3
    + [1.0] * 3,  # [N, Nm]
    dtype=np.float32,
)
OUTPUT_SCALE = np.array([10.0, 10.0, 10.0, 1.0, 1.0, 1.0], dtype=np.float32)
"""Network output units: 1 = 10 N on force axes, 1 Nm on torque axes."""
FORMAT_VERSION = 1
"""Version of the saved checkpoint layout (safetensors weights + JSON config)."""


class MLP:
    """The internal model's network as NumPy arrays: a tanh MLP with a linear last layer.

    ``weights[k]`` is layer k's (out, in) float32 matrix and ``biases[k]`` its (out,) vector,
    as torch's ``Linear`` stores them. The arrays are allocated once and only ever changed in
    place (``load_state_dict``, ``sgd_step``, the numba learner), so the fast path's views of
    them stay bound. ``state_dict`` names them as a ``torch.nn.Sequential`` of Linear / Tanh
    layers would ("0.weight", "0.bias", "2.weight", ...), the names of the saved files.
    """

    def __init__(self, weights: tuple[np.ndarray, ...], biases: tuple[np.ndarray, ...]) -> None:
        self.weights = tuple(np.ascontiguousarray(w, dtype=np.float32) for w in weights)
        self.biases = tuple(np.ascontiguousarray(b, dtype=np.float32) for b in biases)

    def state_dict(self) -> dict[str, np.ndarray]:
        """The live arrays by their saved names (not copies)."""
        out: dict[str, np.ndarray] = {}
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            out[f"{2 * k}.weight"], out[f"{2 * k}.bias"] = w, b
        return out

    def load_state_dict(self, arrays: dict[str, np.ndarray]) -> None:
        """Copy ``arrays`` into the live arrays (same names and shapes).

        Raises:
            ValueError: A name is missing or extra, or a shape differs.
        """
        mine = self.state_dict()
        if set(arrays) != set(mine):
            raise ValueError(f"weights named {sorted(arrays)}, expected {sorted(mine)}")
        for name, live in mine.items():
            if np.shape(arrays[name]) != live.shape:
                raise ValueError(f"{name} has shape {np.shape(arrays[name])}, expected "
                                 f"{live.shape}")
        for name, live in mine.items():
            np.copyto(live, arrays[name], casting="same_kind")

    def parameters(self) -> list[np.ndarray]:
        """The live arrays in torch's order: weight, bias of each layer."""
        return list(self.state_dict().values())

    def forward(self, x: np.ndarray) -> np.ndarray:
        """Reference forward pass in float32 NumPy: ``x`` (B, in) -> (B, 6), network units."""
        h = np.asarray(x, dtype=np.float32)
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            h = h @ w.T + b
            if k < len(self.weights) - 1:
                h = np.tanh(h)
        return h


def torch_uniform(raw: np.ndarray, low: float, high: float) -> np.ndarray:
    """torch's CPU ``uniform_(low, high)`` of float32 from its generator's 32-bit draws ``raw``:
    the low 24 bits scaled to [0, 1), then ``x * (high - low) + low`` fused in one rounding,
    as torch's vectorised CPU kernel computes it (an FMA; emulated exactly in float64, where
    the float32 product is exact)."""
    x = (raw & np.uint32(0xFFFFFF)).astype(np.float32) * np.float32(2.0**-24)
    lo, hi = np.float32(low), np.float32(high)
    return (x.astype(np.float64) * np.float64(hi - lo) + np.float64(lo)).astype(np.float32)


def build_network(config: InternalModelConfig) -> MLP:
    """tanh MLP, input L * 24, output 6; last layer zero-initialised (initial prediction 0).

    The hidden layers start as ``torch.manual_seed(config.seed)`` and ``torch.nn.Linear``'s
    default initialisation would start them (Kaiming-uniform weights, a = sqrt(5), uniform
    biases of bound 1/sqrt(fan_in), drawn layer by layer from one MT19937 stream; the last
    layer's draws are made and then zeroed), bit for bit on a CPU with FMA, without importing
    torch: MT19937 seeded as torch seeds it is NumPy's legacy ``RandomState(seed)``
    (tests/control/test_internal_model.py compares with torch)."""
    stream = np.random.RandomState(config.seed)._bit_generator  # noqa: SLF001 - raw draws
    weights, biases = [], []
    width = config.history_length * FEATURE_DIM
    for out in (*config.hidden_sizes, 6):
        bound_w = math.sqrt(3.0) * (math.sqrt(2.0 / (1 + 5)) / math.sqrt(width))
        bound_b = 1.0 / math.sqrt(width)
        raw_w = stream.random_raw(out * width).astype(np.uint32)
        weights.append(torch_uniform(raw_w, -bound_w, bound_w).reshape(out, width))
        biases.append(torch_uniform(stream.random_raw(out).astype(np.uint32), -bound_b, bound_b))
        width = out
    weights[-1][:] = 0.0
    biases[-1][:] = 0.0
    return MLP(tuple(weights), tuple(biases))


def sgd_step(
    weights: tuple[np.ndarray, ...],
    biases: tuple[np.ndarray, ...],
    x: np.ndarray,
    target: np.ndarray,
    mask: np.ndarray,
    learning_rate: float,
) -> float:
    """One plain-SGD step on mean(((net(x) - target) * mask)^2) of ``build_network``'s MLP.

    ``weights`` / ``biases`` are the network's float32 arrays (``MLP``,
    ``InternalModel.kernel_args``), updated in place. The gradients are written out by hand
    (tanh MLP, masked MSE) in NumPy: the same update as autograd + ``torch.optim.SGD`` to
    float32 round-off (``test_sgd_step_matches_autograd``) at about 135 us instead of 300 us
    (torch's per-op overhead) for these batch-16 steps, which run every 5th tick while the
    model learns.
    Returns the loss before the step.
    """
    lr = np.float32(learning_rate)
    last = len(weights) - 1
    acts = [x]
    for k, (w, b) in enumerate(zip(weights, biases, strict=True)):
        h = acts[-1] @ w.T
        h += b
        if k < last:
            np.tanh(h, out=h)
        acts.append(h)
    err = acts[-1] - target
    err *= mask
    loss = float(np.vdot(err, err)) / err.size
    grad = err * (mask * np.float32(2.0 / err.size))  # d loss / d output
    for k in range(last, -1, -1):
        w, b, a_in = weights[k], biases[k], acts[k]
        grad_in = None
        if k:  # through W_k (before its update) and the tanh that produced a_in
            grad_in = grad @ w
            grad_in *= 1.0 - a_in * a_in
        b -= lr * grad.sum(0)
        w -= lr * (grad.T @ a_in)
        grad = grad_in
    return loss
