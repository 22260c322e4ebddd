"""Feature layout, fixed normalisation constants, network and SGD step of the internal model."""

from __future__ import annotations

import numpy as np
import torch

from impact_envs.control.internal_model.config import InternalModelConfig

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


def build_network(config: InternalModelConfig) -> torch.nn.Sequential:
    """tanh MLP, input L * 24, output 6; last layer zero-initialised (initial prediction 0)."""
    gen_state = torch.random.get_rng_state()
    torch.manual_seed(config.seed)
    layers: list[torch.nn.Module] = []
    width = config.history_length * FEATURE_DIM
    for hidden in config.hidden_sizes:
        layers += [torch.nn.Linear(width, hidden), torch.nn.Tanh()]
        width = hidden
    last = torch.nn.Linear(width, 6)
    torch.nn.init.zeros_(last.weight)
    torch.nn.init.zeros_(last.bias)
    layers.append(last)
    torch.random.set_rng_state(gen_state)
    return torch.nn.Sequential(*layers)


def sgd_step(
    weights: tuple[np.ndarray, ...],
    biases: tuple[np.ndarray, ...],
    x: np.ndarray,
    target: np.ndarray,
    mask: np.ndarray,
    learning_rate: float,
) -> float:
    """One plain-SGD step on mean(((net(x) - target) * mask)^2) of ``build_network``'s MLP.

    ``weights`` / ``biases`` are float32 NumPy views that share memory with the torch
    ``Linear`` parameters (``InternalModel.kernel_args``), so the torch network is updated in
    place. The gradients are written out by hand (tanh MLP, masked MSE) in NumPy: the same
    update as autograd + ``torch.optim.SGD`` to float32 round-off
    (``test_sgd_step_matches_autograd``) at about 135 us instead of 300 us (torch's per-op
    overhead) for these batch-16 steps, which run every 5th tick while the model learns.
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
