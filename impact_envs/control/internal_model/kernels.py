"""Numba kernels of the internal model: buffer layouts, feature push, the MLP forward pass,
the surprise gate and the replay/SGD schedule (``controller_tick`` runs them every tick)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact_envs.control.kernel_layout import STORE, TRAIN, _next


def model_size(max_hidden: int) -> int:
    """Length of the internal model's float64 buffer."""
    return 26 + 2 * max_hidden


@njit(cache=True)
def model_views(buf):
    """(par, state, out_scale, pred, acts) of the internal model's float64 buffer.

    par = [open N, release N, max slow rate, replay period, update_every, learning enabled,
    history length L, features per tick F]; state = [head, filled, tick, gate open, surprise,
    learning active]; acts (2 x max hidden width) holds hidden activations (ping-pong).
    """
    par, o = _next(buf, 0, 8)
    state, o = _next(buf, o, 6)
    out_scale, o = _next(buf, o, 6)
    pred, o = _next(buf, o, 6)
    acts, o = _next(buf, o, buf.shape[0] - o)
    return par, state, out_scale, pred, acts


def model32_size(history_length: int, n_features: int) -> int:
    """Length of the internal model's float32 buffer."""
    return (2 + 2 * history_length) * n_features


@njit(cache=True)
def model32_views(buf32, n_features):
    """(feature offset, 1 / feature scale, history (2L * F flat)) of the float32 buffer."""
    offset, o = _next(buf32, 0, n_features)
    inv_scale, o = _next(buf32, o, n_features)
    hist, o = _next(buf32, o, buf32.shape[0] - o)
    return offset, inv_scale, hist


@njit(cache=True)
def _put_features(row, k, values, offset, inv_scale) -> int:
    """row[k:k+n] = (float32(values) - offset) * inv_scale in float32; returns k + n."""
    for v in values:
        row[k] = (np.float32(v) - offset[k]) * inv_scale[k]
        k += 1
    return k


@njit(cache=True)
def push_features(q, dq, gripper_width, pos_ee, wrench_ext, buf32, buf) -> None:
    """Append one normalized float32 feature row [q, dq, width, p_ee, w_ext].

    The history (2L rows of F) stores row h twice (h and h + L), so the window oldest..newest
    is the contiguous block of rows head+1 .. head+L; the first push after a reset fills every
    row.
    """
    par, state, _, _, _ = model_views(buf)
    n_rows, n_feat = int(par[6]), int(par[7])
    offset, inv_scale, hist = model32_views(buf32, n_feat)
    h = int(state[0])
    row = hist[h * n_feat:(h + 1) * n_feat]
    k = _put_features(row, 0, q, offset, inv_scale)
    k = _put_features(row, k, dq, offset, inv_scale)
    row[k] = (np.float32(gripper_width) - offset[k]) * inv_scale[k]
    k = _put_features(row, k + 1, pos_ee, offset, inv_scale)
    _put_features(row, k, wrench_ext, offset, inv_scale)
    first = state[1] == 0.0
    for r in range(2 * n_rows):
        if first or r == h + n_rows:
            for i in range(n_feat):
                hist[r * n_feat + i] = row[i]
    state[1] = 1.0
    state[0] = (h + 1) % n_rows


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


@njit(cache=True)
def model_predict(buf32, weights, biases, buf) -> None:
    """Forward pass on the current history window (all zeros before the first push)."""
    par, state, out_scale, pred, acts = model_views(buf)
    n_rows, n_feat = int(par[6]), int(par[7])
    hist = model32_views(buf32, n_feat)[2]
    start = ((int(state[0]) + n_rows - 1) % n_rows + 1) * n_feat
    mlp_forward(hist[start:start + n_rows * n_feat], weights, biases, acts, pred)
    for i in range(pred.shape[0]):
        pred[i] *= out_scale[i]


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


@njit(cache=True)
def model_gate_step(wrench_slow, slow_rate, mask, buf) -> int:
    """Surprise over unmasked force axes, gate, replay/SGD schedule; returns STORE | TRAIN.

    Call after this tick's prediction (see ``model_views`` for the buffer).
    """
    par, state, _, pred, _ = model_views(buf)
    px = (pred[0] - wrench_slow[0]) * mask[0]
    py = (pred[1] - wrench_slow[1]) * mask[1]
    pz = (pred[2] - wrench_slow[2]) * mask[2]
    state[4] = math.sqrt(px * px + py * py + pz * pz)
    state[5] = 0.0
    if par[5] == 0.0:  # learning disabled: the gate is frozen too
        return 0
    is_open, learn = gate_update(state[3] != 0.0, state[4], slow_rate, par[0], par[1], par[2])
    state[3] = 1.0 if is_open else 0.0
    state[5] = 1.0 if learn else 0.0
    tick = int(state[2])
    state[2] = tick + 1
    flags = 0
    if tick % int(par[3]) == 0 and slow_rate <= par[2]:
        flags |= STORE
    if learn and (tick + 1) % int(par[4]) == 0:
        flags |= TRAIN
    return flags
