"""Numba kernels of the controller stages: impedance, estimators, slow filter, torque limits and
the internal model's features, forward pass and surprise gate (``kernels.py`` chains them)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact_envs.control.kernel_layout import (
    STORE,
    TRAIN,
    impedance_views,
    limiter_views,
    model32_views,
    model_views,
    momentum_views,
    residual_views,
    slow_filter_views,
)
from impact_envs.control.kernel_math import (
    mat_t_vec,
    mat_vec,
    orientation_error,
)


# ------------------------------------------------------------------------------- impedance
@njit(cache=True)
def impedance_law(dyn, q, dq, pos_target, quat_target, wrench_map, wrench_ff, buf) -> bool:
    """tau_no_gravity = J^T (K e - D J dq - W_n tau_0 + w_ff) + tau_0 + C dq (impedance.py).

    dyn = (J, M, C, g, p_ee, R_ee); buf = impedance buffer. Returns False (nothing written) when
    the target quaternion is invalid.
    """
    jac, _, cor, grav, pos_ee, rot_ee = dyn
    par, k_q_null, e, twist, w_imp, tau0, w_null, w, tau_cor, tau_grav, out = (
        impedance_views(buf)
    )
    if not orientation_error(quat_target, rot_ee, e[3:]):
        return False
    for i in range(3):
        e[i] = pos_target[i] - pos_ee[i]
    mat_vec(jac, dq, twist)
    for i in range(6):
        w_imp[i] = par[i] * e[i] - par[6 + i] * twist[i]
    k_null, d_null = par[12], par[13]
    for j in range(tau0.shape[0]):
        tau0[j] = q[j] * -k_null + k_q_null[j] - dq[j] * d_null
    mat_vec(wrench_map, tau0, w_null)
    for i in range(6):
        w[i] = w_imp[i] - w_null[i] + wrench_ff[i]
    mat_t_vec(jac, w, out)
    if par[15] != 0.0:
        mat_vec(cor, dq, tau_cor)
    for j in range(out.shape[0]):
        out[j] += tau0[j]
        if par[15] != 0.0:
            out[j] += tau_cor[j]
        if par[14] != 0.0:
            tau_grav[j] = grav[j]
    return True


# ------------------------------------------------------------------------------ estimators
@njit(cache=True)
def residual_update(dq, tau_meas, fric, dyn, wrench_map, buf) -> None:
    """Residual estimator tick (estimators.py::ResidualEstimator); fric = 0 when not modelled."""
    _, mass, cor, grav, _, _ = dyn
    par, lp, raw, gain, dq_prev, tau_res, wrench = residual_views(buf)
    n = dq.shape[0]
    alpha = par[0]
    for j in range(n):
        raw[j] = dq[j] - dq_prev[j] if par[1] != 0.0 else 0.0
        dq_prev[j] = dq[j]
    par[1] = 1.0
    mat_vec(cor, dq, tau_res)  # scratch: C dq
    for j in range(n):
        raw[n + j] = tau_meas[j] - grav[j] - tau_res[j] - fric[j]
    for j in range(2 * n):  # lp <- (1 - a) lp + a raw, the 1/dt of the difference in the gain
        lp[j] = lp[j] * (1.0 - alpha) + raw[j] * gain[j]
    mat_vec(mass, lp[:n], tau_res)
    for j in range(n):
        tau_res[j] = lp[n + j] - tau_res[j]
    mat_vec(wrench_map, tau_res, wrench)


@njit(cache=True)
def momentum_update(dq, tau_meas, fric, dyn, wrench_map, buf) -> None:
    """Momentum observer tick (estimators.py::MomentumObserver); fric = 0 when not modelled."""
    _, mass, cor, grav, _, _ = dyn
    par, r, p0, integral, p, tau_res, wrench = momentum_views(buf)
    gain, dt = par[0], par[1]
    n = dq.shape[0]
    mat_vec(mass, dq, p)
    if par[2] == 0.0:
        for j in range(n):
            p0[j] = p[j]
        par[2] = 1.0
    else:
        mat_t_vec(cor, dq, tau_res)  # scratch: C^T dq
        for j in range(n):
            beta = (tau_res[j] - grav[j] - fric[j] + tau_meas[j] + r[j]) * dt
            integral[j] += beta
            r[j] = (p[j] - p0[j] - integral[j]) * gain
    for j in range(n):
        tau_res[j] = -r[j]
    mat_vec(wrench_map, tau_res, wrench)


# ----------------------------------------------------------------------- slow filter, limits
@njit(cache=True)
def slow_filter_update(wrench_ext, buf) -> float:
    """w_slow += eta dt clip(w_ext - w_slow, -c, c); returns (and stores) the slow rate."""
    par, eta, gain, clip, w_slow, rate = slow_filter_views(buf)
    for i in range(6):
        d = wrench_ext[i] - w_slow[i]
        if d > clip[i]:
            d = clip[i]
        if d < -clip[i]:
            d = -clip[i]
        rate[i] = eta[i] * d
        w_slow[i] += d * gain[i]
    fx, fy, fz = rate[0], rate[1], rate[2]
    par[1] = math.sqrt(fx * fx + fy * fy + fz * fz) * par[0]
    return par[1]


@njit(cache=True)
def limit_rate(tau_desired, tau_last, max_delta, out) -> None:
    """out = tau_last + clip(tau_desired - tau_last, -max_delta, max_delta) (NaN propagates)."""
    for j in range(out.shape[0]):
        d = tau_desired[j] - tau_last[j]
        if d > max_delta:
            d = max_delta
        if d < -max_delta:
            d = -max_delta
        out[j] = d + tau_last[j]


@njit(cache=True)
def saturate(tau, tau_max, out) -> None:
    """out = clip(tau, -tau_max, tau_max) per joint (NaN propagates)."""
    for j in range(out.shape[0]):
        v = tau[j]
        if v > tau_max[j]:
            v = tau_max[j]
        if v < -tau_max[j]:
            v = -tau_max[j]
        out[j] = v


@njit(cache=True)
def torque_limiter(tau_no_gravity, tau_gravity, buf) -> None:
    """Rate-limit without gravity, add gravity, saturate; remember output - gravity."""
    par, tau_max, last, out = limiter_views(buf)
    limit_rate(tau_no_gravity, last, par[0], out)
    for j in range(out.shape[0]):
        out[j] += tau_gravity[j]
    saturate(out, tau_max, out)
    for j in range(out.shape[0]):
        last[j] = out[j] - tau_gravity[j]


# -------------------------------------------------------------------------- internal model
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
    """Schmitt trigger (surprise_gate.py); returns (new is_open, learn on this tick)."""
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
