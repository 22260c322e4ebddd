"""The online learner inside the 1 kHz tick: replay ring, seeded sampler and SGD in numba.

With ``InternalModelConfig.learner == "numba"`` the replay insert and the SGD step run inside
``controller_tick``: no Python, no BLAS and no allocation per tick, so the tick has a bounded
cost that no thread pool can stall. One SGD step (batch ``batch_size``: the current sample and
replayed ones, drawn when the step starts) is spread over ticks, ``samples_per_tick`` samples
per tick, against the weights of the tick it started on; the update is applied on the tick
that processes the last sample. The result is the whole-batch step of ``net.sgd_step`` (masked
MSE, plain SGD), computed sample by sample (tests/control/test_learner.py: equal to autograd within
float32 round-off), and applied ``ceil(batch_size / samples_per_tick) - 1`` ticks later.

Replay indices come from splitmix64 (seeded with ``InternalModelConfig.seed``, reseeded by
``clear``), so a run is reproducible and the sampler state is one uint64.
``learner == "numpy"`` keeps the learner the published tables were computed with (Python
after the tick, NumPy BLAS, ``numpy.random.Generator``); docs/controller.md, "A bounded tick".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.internal_model.kernels import (
    dense,
    tanh_inplace,
)
from impact_control.kernel_layout import STORE, TRAIN
from impact_control.stage_layout import Layout, slots

DIVERGED = 32
"""Status bit: the SGD step just applied left a non-finite loss or weight (Python then
re-initialises the model, ``InternalModel.n_divergences``)."""



class LearnerParams(NamedTuple):
    """The learner's configuration, (1,) float64 views of ``LearnerArrays.scal``.

    Attributes:
        learning_rate: SGD learning rate.
        batch_size: Rows of an SGD step (the current sample and replayed ones).
        samples_per_tick: Rows processed per tick.
        in_kernel: 1 when the learner runs in the kernel, 0 when in Python (``"numpy"``).
    """

    learning_rate: np.ndarray
    batch_size: np.ndarray
    samples_per_tick: np.ndarray
    in_kernel: np.ndarray


class LearnerCounters(NamedTuple):
    """The learner's scalars, as named (1,) float64 views of ``LearnerArrays.scal``
    (``COUNTERS_LAYOUT``): its configuration (``params``) and its runtime counters.

    Attributes:
        params: ``LearnerParams``.
        count: Samples in the replay ring.
        head: Ring slot the next sample goes to.
        pending: Samples in the SGD step in progress (0: none).
        next_row: Next batch row to process.
        n_updates: SGD steps applied.
        loss: Sum of squared masked errors of the step in progress.
    """

    params: LearnerParams
    count: np.ndarray
    head: np.ndarray
    pending: np.ndarray
    next_row: np.ndarray
    n_updates: np.ndarray
    loss: np.ndarray


COUNTERS_LAYOUT = Layout.of(LearnerCounters, dict(
    params=Layout.of(LearnerParams,
                     slots("learning_rate batch_size samples_per_tick in_kernel")),
    **slots("count head pending next_row n_updates loss")), args=("scal",))
"""The learner's ``scal`` buffer."""
unpack_counters = COUNTERS_LAYOUT.unpacker("unpack_counters", __name__)


def make_counters() -> np.ndarray:
    """A zeroed ``scal`` buffer (``COUNTERS_LAYOUT``)."""
    return np.zeros(COUNTERS_LAYOUT.size())


class LearnerArrays(NamedTuple):
    """The learner's state, by name (``InternalModel.learner``).

    ``inputs`` / ``targets`` / ``masks``: the replay ring (capacity, L*24 / 6 / 6) float32;
    ``batch_x`` / ``batch_y`` / ``batch_m``: the batch of the step in progress; ``grad_w`` /
    ``grad_b``: its gradient so far (float32, shaped like the weights); ``acts`` (layers,
    max width) float64 activations of one sample; ``grad_out`` (2, max width) float64;
    ``target`` (6,) float32 scratch (this tick's normalized target); ``scal`` float64
    configuration and counters (``LearnerCounters``, ``COUNTERS_LAYOUT``); ``rng`` (1,)
    uint64 splitmix64 state.
    """

    inputs: np.ndarray
    targets: np.ndarray
    masks: np.ndarray
    batch_x: np.ndarray
    batch_y: np.ndarray
    batch_m: np.ndarray
    grad_w: tuple
    grad_b: tuple
    acts: np.ndarray
    grad_out: np.ndarray
    target: np.ndarray
    scal: np.ndarray
    rng: np.ndarray


def make_learner(capacity: int, batch_size: int, input_dim: int, weights: tuple,
                 learning_rate: float, samples_per_tick: int, in_kernel: bool) -> LearnerArrays:
    """Zeroed learner arrays for a network with ``weights`` (float32 (out, in) matrices)."""
    widest = max(w.shape[0] for w in weights)
    scal = make_counters()
    c = unpack_counters(scal)[0]
    c.params.learning_rate[0], c.params.batch_size[0] = learning_rate, batch_size
    c.params.samples_per_tick[0], c.params.in_kernel[0] = samples_per_tick, float(in_kernel)
    f32 = np.float32
    return LearnerArrays(
        np.zeros((capacity, input_dim), f32), np.zeros((capacity, 6), f32),
        np.zeros((capacity, 6), f32), np.zeros((batch_size, input_dim), f32),
        np.zeros((batch_size, 6), f32), np.zeros((batch_size, 6), f32),
        tuple(np.zeros_like(w) for w in weights),
        tuple(np.zeros(w.shape[0], f32) for w in weights),
        np.zeros((len(weights), widest)), np.zeros((2, widest)), np.zeros(6, f32), scal,
        np.zeros(1, np.uint64))


@njit(cache=True)
def splitmix64_below(rng, n) -> int:
    """Advance the splitmix64 state ``rng[0]``; an integer uniform in [0, n) (53-bit draw)."""
    rng[0] += np.uint64(0x9E3779B97F4A7C15)
    z = rng[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return min(int(np.float64(z >> np.uint64(11)) * (1.0 / 9007199254740992.0) * n), n - 1)


@njit(cache=True)
def replay_store(x, target, mask, lrn) -> None:
    """Copy one sample into the ring at ``head`` (the oldest is overwritten when full)."""
    c = unpack_counters(lrn.scal)[0]
    cap = lrn.inputs.shape[0]
    h = int(c.head[0])
    lrn.inputs[h, :] = x
    lrn.targets[h, :] = target
    lrn.masks[h, :] = mask
    c.head[0] = (h + 1) % cap
    c.count[0] = min(c.count[0] + 1.0, cap)


@njit(cache=True)
def start_step(x, target, mask, lrn) -> None:
    """Begin an SGD step: row 0 = the current sample, then replayed rows; zero the gradient."""
    c = unpack_counters(lrn.scal)[0]
    count = int(c.count[0])
    n = 1 + (int(c.params.batch_size[0]) - 1 if count > 0 else 0)
    lrn.batch_x[0, :] = x
    lrn.batch_y[0, :] = target
    lrn.batch_m[0, :] = mask
    for r in range(1, n):
        i = splitmix64_below(lrn.rng, count)
        lrn.batch_x[r, :] = lrn.inputs[i]
        lrn.batch_y[r, :] = lrn.targets[i]
        lrn.batch_m[r, :] = lrn.masks[i]
    for k in range(len(lrn.grad_w)):
        lrn.grad_w[k][:] = 0.0
        lrn.grad_b[k][:] = 0.0
    c.pending[0], c.next_row[0], c.loss[0] = n, 0.0, 0.0


@njit(cache=True, fastmath={"reassoc", "contract"})
def _outer_add(grad_w, g, a_in) -> None:
    """grad_w += outer(g, a_in) in float32 (row by row, vectorized)."""
    for i in range(grad_w.shape[0]):
        gi = np.float32(g[i])
        row = grad_w[i]
        for j in range(row.shape[0]):
            row[j] += gi * np.float32(a_in[j])


@njit(cache=True)
def accumulate_sample(r, weights, biases, lrn) -> None:
    """Add row ``r``'s gradient of mean(((net(x) - y) * m)^2) (over the pending batch)."""
    x, acts, n_layers = lrn.batch_x[r], lrn.acts, len(weights)
    for k in range(n_layers):
        width = weights[k].shape[0]
        out = acts[k, :width]
        if k == 0:
            dense(weights[0], biases[0], x, out, np.float32(0.0))
        else:
            dense(weights[k], biases[k], acts[k - 1, :weights[k].shape[1]], out, 0.0)
        if k < n_layers - 1:
            tanh_inplace(out)  # the forward pass's own tanh
    y, m = lrn.batch_y[r], lrn.batch_m[r]
    c = unpack_counters(lrn.scal)[0]
    scale = np.float32(2.0 / (c.pending[0] * 6.0))
    g = lrn.grad_out[0]
    for i in range(6):
        err = (acts[n_layers - 1, i] - np.float64(y[i])) * np.float64(m[i])
        c.loss[0] += err * err
        g[i] = err * np.float64(m[i]) * np.float64(scale)
    src = 0
    for k in range(n_layers - 1, -1, -1):
        w = weights[k]
        g_k = lrn.grad_out[src, :w.shape[0]]
        for i in range(w.shape[0]):
            lrn.grad_b[k][i] += np.float32(g_k[i])
        if k == 0:
            _outer_add(lrn.grad_w[0], g_k, x)
            break
        a_in = acts[k - 1, :w.shape[1]]
        _outer_add(lrn.grad_w[k], g_k, a_in)
        g_in = lrn.grad_out[1 - src, :w.shape[1]]
        for j in range(w.shape[1]):
            s = 0.0
            for i in range(w.shape[0]):
                s += np.float64(w[i, j]) * g_k[i]
            g_in[j] = s * (1.0 - a_in[j] * a_in[j])
        src = 1 - src


@njit(cache=True)
def _apply(weights, biases, lrn) -> int:
    """W -= lr * grad for every layer; DIVERGED when the loss or a weight is not finite."""
    c = unpack_counters(lrn.scal)[0]
    lr = np.float32(c.params.learning_rate[0])
    finite = math.isfinite(c.loss[0])
    for k in range(len(weights)):
        w, b, gw, gb = weights[k], biases[k], lrn.grad_w[k], lrn.grad_b[k]
        for i in range(w.shape[0]):
            b[i] -= lr * gb[i]
            finite = finite and math.isfinite(b[i])
            row, grow = w[i], gw[i]
            for j in range(row.shape[0]):
                row[j] -= lr * grow[j]
            for j in range(row.shape[0]):
                if not math.isfinite(row[j]):
                    finite = False
                    break
    c.pending[0] = 0.0
    c.n_updates[0] += 1.0
    return 0 if finite else DIVERGED


@njit(cache=True)
def continue_step(weights, biases, lrn) -> int:
    """Process this tick's share of the pending step; apply it after its last sample."""
    c = unpack_counters(lrn.scal)[0]
    n = int(c.pending[0])
    if n == 0:
        return 0
    r0 = int(c.next_row[0])
    r1 = min(n, r0 + int(c.params.samples_per_tick[0]))
    for r in range(r0, r1):
        accumulate_sample(r, weights, biases, lrn)
    c.next_row[0] = r1
    return _apply(weights, biases, lrn) if r1 == n else 0


@njit(cache=True, inline="always")
def learner_tick(flags, wrench_slow, mask, m32, m, weights, biases, lrn) -> int:
    """The replay insert / SGD schedule of ``flags`` (``model_gate_step``), in the kernel.

    Returns ``flags`` without STORE / TRAIN (done here), plus DIVERGED when a step applied on
    this tick diverged. A no-op returning ``flags`` unchanged when the learner runs in Python.
    """
    c = unpack_counters(lrn.scal)[0]
    if c.params.in_kernel[0] == 0.0:
        return flags
    if flags & (STORE | TRAIN):
        out_scale = m.params.out_scale
        n_rows, n_feat = int(m.params.history_length[0]), int(m.params.n_features[0])
        hist = m32.hist
        start = ((int(m.head[0]) + n_rows - 1) % n_rows + 1) * n_feat
        x = hist[start:start + n_rows * n_feat]
        target = lrn.target
        for i in range(6):
            inv_scale = np.float64(np.float32(1.0) / np.float32(out_scale[i]))
            target[i] = np.float32(wrench_slow[i] * inv_scale)
        if flags & STORE:
            replay_store(x, target, mask, lrn)
        if flags & TRAIN and c.pending[0] == 0.0:
            start_step(x, target, mask, lrn)
    return (flags & ~(STORE | TRAIN)) | continue_step(weights, biases, lrn)
