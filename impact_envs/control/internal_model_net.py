"""Feature layout, fixed normalisation constants, network and SGD step of the internal model."""

from __future__ import annotations

import numpy as np
import torch

from impact_envs.control.config import InternalModelConfig

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
    net: torch.nn.Sequential,
    x: torch.Tensor,
    target: torch.Tensor,
    mask: torch.Tensor,
    learning_rate: float,
) -> float:
    """One plain-SGD step on mean(((net(x) - target) * mask)^2) of ``build_network``'s MLP.

    The gradients are written out by hand (tanh MLP, masked MSE) instead of autograd +
    ``torch.optim.SGD``: the same update to float32 round-off (``test_sgd_step_matches_autograd``)
    at about a third of the cost for these batch-16 steps, which run every 5th tick while the
    model learns. Weights are updated in place. Returns the loss before the step.
    """
    linears = [m for m in net if isinstance(m, torch.nn.Linear)]
    with torch.no_grad():
        acts = [x]
        for k, layer in enumerate(linears):
            h = torch.addmm(layer.bias, acts[-1], layer.weight.t())
            acts.append(h.tanh_() if k < len(linears) - 1 else h)
        err = (acts[-1] - target).mul_(mask)
        flat = err.view(-1)
        loss = float(torch.dot(flat, flat)) / flat.numel()
        grad = err.mul_(mask).mul_(2.0 / flat.numel())  # d loss / d output
        for k in range(len(linears) - 1, -1, -1):
            layer, a_in = linears[k], acts[k]
            # through W_k (before its update) and the tanh that produced a_in
            grad_in = torch.ops.aten.tanh_backward(grad.mm(layer.weight), a_in) if k else None
            layer.bias.sub_(grad.sum(0), alpha=learning_rate)
            layer.weight.addmm_(grad.t(), a_in, alpha=-learning_rate)
            grad = grad_in
    return loss
