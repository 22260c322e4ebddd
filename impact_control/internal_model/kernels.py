"""Numba kernels of the internal model: named layouts, feature push, the MLP forward pass,
the surprise gate and the replay/SGD schedule (``controller_tick`` runs them every tick)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.kernel_layout import STORE, TRAIN
from impact_control.stage_layout import Dim, Layout, slots


class ModelParams(NamedTuple):
    """The internal model's configuration, (1,) views (written once from its config).

    Attributes:
        max_hidden: Widest hidden layer (sizes ``ModelState.acts``; the buffer's first slot).
        open_n, release_n: The surprise gate's thresholds [N].
        slow_rate_max: Largest slow-wrench rate at which the gate may open or a sample be
            stored (dimensionless).
        replay_period: Ticks between replay inserts.
        update_every: Ticks between SGD steps while learning.
        history_length: L, ticks of history in the input.
        n_features: F, features per tick.
        out_scale: (6,) output scale of the network [N, Nm].
    """

    max_hidden: np.ndarray
    open_n: np.ndarray
    release_n: np.ndarray
    slow_rate_max: np.ndarray
    replay_period: np.ndarray
    update_every: np.ndarray
    history_length: np.ndarray
    n_features: np.ndarray
    out_scale: np.ndarray


class ModelState(NamedTuple):
    """The internal model's float64 buffer as named views (``unpack_model``): its
    configuration (``params``) and its runtime state, (1,) views for scalars (written by
    name from Python; the kernels read ``[0]``).

    Attributes:
        params: ``ModelParams``.
        learning_enabled: 0 freezes learning (and the gate); a switch, not configuration.
        head, filled: History ring position and whether it has been filled once.
        tick: Ticks since the reset (schedules inserts and steps).
        gate_open, surprise, learning_active: The gate, the last surprise [N], whether the
            last tick learned.
        pred: (6,) the prediction w_pred [N, Nm], world frame.
        acts: (2 x max hidden,) hidden activations (ping-pong).
    """

    params: ModelParams
    learning_enabled: np.ndarray
    head: np.ndarray
    filled: np.ndarray
    tick: np.ndarray
    gate_open: np.ndarray
    surprise: np.ndarray
    learning_active: np.ndarray
    pred: np.ndarray
    acts: np.ndarray


_HIDDEN = Dim.named("hidden")
MODEL_LAYOUT = Layout.of(ModelState, dict(
    params=Layout.of(ModelParams, dict(
        **slots("max_hidden open_n release_n slow_rate_max replay_period update_every "
                "history_length n_features"), out_scale=6)),
    **slots("learning_enabled head filled tick gate_open surprise learning_active"),
    pred=6, acts=2 * _HIDDEN), dims={"hidden": "int(buf[0])"}, args=("buf",))
"""The internal model's float64 buffer; ``max_hidden`` (slot 0) sizes ``acts``."""
unpack_model = MODEL_LAYOUT.unpacker("unpack_model", __name__)


def model_size(max_hidden: int) -> int:
    """Length of the internal model's float64 buffer (``MODEL_LAYOUT``)."""
    return MODEL_LAYOUT.size(hidden=max_hidden)


class Model32State(NamedTuple):
    """The internal model's float32 buffer as named views (``unpack_model32``).

    Attributes:
        offset, inv_scale: (F,) feature normalization: (x - offset) * inv_scale.
        hist: (2 L F,) the feature history, each row stored twice (see ``push_features``).
    """

    offset: np.ndarray
    inv_scale: np.ndarray
    hist: np.ndarray


_FEATURES, _HISTORY = Dim.named("f"), Dim.named("hist")
MODEL32_LAYOUT = Layout.of(Model32State, dict(
    offset=_FEATURES, inv_scale=_FEATURES, hist=_HISTORY),
    dims={"f": "n_features", "hist": "buf32.shape[0] - 2 * n_features"},
    args=("buf32", "n_features"))
"""The internal model's float32 buffer (the history fills what the normalization leaves)."""
unpack_model32 = MODEL32_LAYOUT.unpacker("unpack_model32", __name__, returns_length=False)


def model32_size(history_length: int, n_features: int) -> int:
    """Length of the internal model's float32 buffer: 2 L rows of F in the history."""
    return MODEL32_LAYOUT.size(f=n_features, hist=2 * history_length * n_features)


@njit(cache=True)
def _put_features(row, k, values, offset, inv_scale) -> int:
    """row[k:k+n] = (float32(values) - offset) * inv_scale in float32; returns k + n."""
    for v in values:
        row[k] = (np.float32(v) - offset[k]) * inv_scale[k]
        k += 1
    return k


@njit(cache=True, inline="always")
def push_features(q, dq, gripper_width, pos_ee, wrench_ext, m32, m) -> None:
    """Append one normalized float32 feature row [q, dq, width, p_ee, w_ext].

    The history (2L rows of F) stores row h twice (h and h + L), so the window oldest..newest
    is the contiguous block of rows head+1 .. head+L; the first push after a reset fills every
    row.
    """
    n_rows, n_feat = int(m.params.history_length[0]), int(m.params.n_features[0])
    offset, inv_scale, hist = m32.offset, m32.inv_scale, m32.hist
    h = int(m.head[0])
    row = hist[h * n_feat:(h + 1) * n_feat]
    k = _put_features(row, 0, q, offset, inv_scale)
    k = _put_features(row, k, dq, offset, inv_scale)
    row[k] = (np.float32(gripper_width) - offset[k]) * inv_scale[k]
    k = _put_features(row, k + 1, pos_ee, offset, inv_scale)
    _put_features(row, k, wrench_ext, offset, inv_scale)
    first = m.filled[0] == 0.0
    for r in range(2 * n_rows):
        if first or r == h + n_rows:
            for i in range(n_feat):
                hist[r * n_feat + i] = row[i]
    m.filled[0] = 1.0
    m.head[0] = (h + 1) % n_rows


@njit(cache=True, fastmath={"reassoc", "contract"})
def dense(weight, bias, x, out, zero) -> None:
    """out = weight @ x + bias, accumulated in the type of ``zero``.

    float32 for the history input (768 wide, vectorized like the float32 BLAS it replaces),
    float64 for the hidden activations; reassociation lets LLVM vectorize the sums.
    """
    for i in range(weight.shape[0]):
        s = zero
        for j in range(weight.shape[1]):
            s += weight[i, j] * x[j]
        out[i] = np.float64(s) + np.float64(bias[i])


@njit(cache=True)
def tanh_inplace(a) -> None:
    """a = tanh(a) as sign(a) (1 - e) / (1 + e), e = exp(-2|a|) (absolute error ~1e-16)."""
    for i in range(a.shape[0]):
        e = math.exp(-2.0 * abs(a[i]))
        t = (1.0 - e) / (1.0 + e)
        a[i] = t if a[i] >= 0.0 else -t


@njit(cache=True)
def mlp_forward(x, weights, biases, acts, out) -> None:
    """tanh MLP, out = W_n tanh(... tanh(W_0 x + b_0) ...) + b_n; acts: 2 x max hidden width."""
    half = acts.shape[0] // 2
    width = weights[0].shape[0]
    dense(weights[0], biases[0], x, acts[:width], np.float32(0.0))
    src = 0
    for k in range(1, len(weights)):
        a = acts[src:src + width]
        tanh_inplace(a)
        width_out = weights[k].shape[0]
        dst = out if k == len(weights) - 1 else acts[half - src:half - src + width_out]
        dense(weights[k], biases[k], a, dst, 0.0)
        src, width = half - src, width_out


@njit(cache=True, inline="always")
def model_predict(m32, weights, biases, m) -> None:
    """Forward pass on the current history window (all zeros before the first push)."""
    n_rows, n_feat = int(m.params.history_length[0]), int(m.params.n_features[0])
    hist = m32.hist
    start = ((int(m.head[0]) + n_rows - 1) % n_rows + 1) * n_feat
    pred = m.pred
    mlp_forward(hist[start:start + n_rows * n_feat], weights, biases, m.acts, pred)
    for i in range(pred.shape[0]):
        pred[i] *= m.params.out_scale[i]


@njit(cache=True)
def gate_update(is_open, surprise, slow_rate, open_n, release_n, slow_rate_max):
    """Schmitt trigger (gate.py); returns (new is_open, learn on this tick)."""
    quasi_steady = slow_rate <= slow_rate_max
    if is_open:
        if surprise < release_n:
            is_open = False
    elif surprise >= open_n and quasi_steady:
        is_open = True
    return is_open, is_open and quasi_steady


@njit(cache=True, inline="always")
def model_gate_step(wrench_slow, slow_rate, mask, m) -> int:
    """Surprise over unmasked force axes, gate, replay/SGD schedule; returns STORE | TRAIN.

    Call after this tick's prediction; ``m`` is the ``ModelState``.
    """
    pred = m.pred
    px = (pred[0] - wrench_slow[0]) * mask[0]
    py = (pred[1] - wrench_slow[1]) * mask[1]
    pz = (pred[2] - wrench_slow[2]) * mask[2]
    m.surprise[0] = math.sqrt(px * px + py * py + pz * pz)
    m.learning_active[0] = 0.0
    if m.learning_enabled[0] == 0.0:  # learning disabled: the gate is frozen too
        return 0
    par = m.params
    is_open, learn = gate_update(m.gate_open[0] != 0.0, m.surprise[0], slow_rate, par.open_n[0],
                                 par.release_n[0], par.slow_rate_max[0])
    m.gate_open[0] = 1.0 if is_open else 0.0
    m.learning_active[0] = 1.0 if learn else 0.0
    tick = int(m.tick[0])
    m.tick[0] = tick + 1
    flags = 0
    if tick % int(par.replay_period[0]) == 0 and slow_rate <= par.slow_rate_max[0]:
        flags |= STORE
    if learn and (tick + 1) % int(par.update_every[0]) == 0:
        flags |= TRAIN
    return flags
