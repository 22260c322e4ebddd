"""Numba kernels: the per-tick math of every controller stage, in one place.

Each stage class (``impedance.py``, ``estimators.py``, ``slow_filter.py``, ``limits.py``,
``jacobian.py``, ``internal_model.py``) keeps its parameters and state in one preallocated
float64 buffer and calls the kernel of its own stage; ``ImpactController.compute`` calls
:func:`controller_tick`, which runs all stages after the dynamics update in one call through the
same functions. There is no second (NumPy) copy of this math.

Buffers: the ``*_views`` functions below are the only definition of each buffer's layout; the
classes call them once to get named NumPy views, the kernels call them every tick (slicing is
free in compiled code). One array per stage keeps the call cheap: numba's dispatcher costs
~0.06 us per array argument. Matrix products are explicit loops (numba's ``@`` needs SciPy's
BLAS, and for 6x7 operands loops are faster anyway). Everything is float64 except the internal
model's history and weights (float32, the weights shared with torch); its first dense layer
accumulates in float32 (like the float32 BLAS path it replaced), the later ones in float64.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact_envs.control.chain_dynamics import chain_terms

EPS_SMALL_ANGLE = 1e-8
"""Below this |vector part| the quaternion log uses its series expansion."""

# Bits of the status returned by model_gate_step / controller_tick.
STORE = 1
"""Store the current sample in the replay buffer (Python side, ``InternalModel.learn``)."""
TRAIN = 2
"""Take one SGD step on the current sample (Python side, torch)."""
BAD_QUAT = 4
"""The target quaternion is zero or not finite; nothing was updated."""
NON_FINITE = 8
"""The torque command is not finite."""


# --------------------------------------------------------------------------- buffer layouts
@njit(cache=True)
def _next(buf, start, size):
    """(buf[start:start + size], start + size)."""
    return buf[start:start + size], start + size


def impedance_size(n: int) -> int:
    """Length of an impedance buffer for ``n`` joints (see ``impedance_views``)."""
    return 46 + 5 * n


@njit(cache=True)
def impedance_views(buf):
    """(par, k_q_null, e, twist, w_imp, tau0, w_null, w, tau_coriolis, tau_gravity, out).

    par = [K (6), D (6), k_n, d_n, gravity on, Coriolis on]; e = pose error; out = torque
    without gravity.
    """
    n = (buf.shape[0] - 46) // 5
    par, o = _next(buf, 0, 16)
    k_q_null, o = _next(buf, o, n)
    e, o = _next(buf, o, 6)
    twist, o = _next(buf, o, 6)
    w_imp, o = _next(buf, o, 6)
    tau0, o = _next(buf, o, n)
    w_null, o = _next(buf, o, 6)
    w, o = _next(buf, o, 6)
    tau_cor, o = _next(buf, o, n)
    tau_grav, o = _next(buf, o, n)
    out, o = _next(buf, o, n)
    return par, k_q_null, e, twist, w_imp, tau0, w_null, w, tau_cor, tau_grav, out


def residual_size(n: int) -> int:
    """Length of a residual-estimator buffer for ``n`` joints."""
    return 8 + 8 * n


@njit(cache=True)
def residual_views(buf):
    """(par [a, started], lp [ddq_hat; tau_lp], raw, gain, dq_prev, tau_res, wrench)."""
    n = (buf.shape[0] - 8) // 8
    par, o = _next(buf, 0, 2)
    lp, o = _next(buf, o, 2 * n)
    raw, o = _next(buf, o, 2 * n)
    gain, o = _next(buf, o, 2 * n)
    dq_prev, o = _next(buf, o, n)
    tau_res, o = _next(buf, o, n)
    wrench, o = _next(buf, o, 6)
    return par, lp, raw, gain, dq_prev, tau_res, wrench


def momentum_size(n: int) -> int:
    """Length of a momentum-observer buffer for ``n`` joints."""
    return 9 + 5 * n


@njit(cache=True)
def momentum_views(buf):
    """(par [K_O, dt, started], r, p0, integral, p, tau_res, wrench)."""
    n = (buf.shape[0] - 9) // 5
    par, o = _next(buf, 0, 3)
    r, o = _next(buf, o, n)
    p0, o = _next(buf, o, n)
    integral, o = _next(buf, o, n)
    p, o = _next(buf, o, n)
    tau_res, o = _next(buf, o, n)
    wrench, o = _next(buf, o, 6)
    return par, r, p0, integral, p, tau_res, wrench


SLOW_FILTER_SIZE = 32
"""Length of a slow-filter buffer."""


@njit(cache=True)
def slow_filter_views(buf):
    """(par [1 / (eta_f c_f), slow_rate], eta, gain, clip, w_slow, rate)."""
    par, o = _next(buf, 0, 2)
    eta, o = _next(buf, o, 6)
    gain, o = _next(buf, o, 6)
    clip, o = _next(buf, o, 6)
    w_slow, o = _next(buf, o, 6)
    rate, o = _next(buf, o, 6)
    return par, eta, gain, clip, w_slow, rate


def limiter_size(n: int) -> int:
    """Length of a torque-limiter buffer for ``n`` joints."""
    return 1 + 3 * n


@njit(cache=True)
def limiter_views(buf):
    """(par [max change per tick], tau_max, previous output without gravity, output)."""
    n = (buf.shape[0] - 1) // 3
    par, o = _next(buf, 0, 1)
    tau_max, o = _next(buf, o, n)
    last, o = _next(buf, o, n)
    out, o = _next(buf, o, n)
    return par, tau_max, last, out


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


CONTROLLER_SIZE = 30
"""Length of ImpactController's own buffer."""


@njit(cache=True)
def controller_views(buf):
    """(par, wrench_cmd signal, w_ff + w_cmd, scalars, applied w_ff) of the controller buffer.

    par = [lambda^2, lambda_n^2, maps shared, estimator kind (0 residual, 1 momentum),
    run internal model, apply feedforward]; scalars = [|e_p|, |e_R|, slow rate, surprise,
    gate open, learning active]; w_ff = the feedforward applied this tick (the prediction on
    unmasked axes, the last unmasked tick's value on masked ones).
    """
    par, o = _next(buf, 0, 6)
    w_cmd, o = _next(buf, o, 6)
    w_extra, o = _next(buf, o, 6)
    scalars, o = _next(buf, o, 6)
    w_ff, o = _next(buf, o, 6)
    return par, w_cmd, w_extra, scalars, w_ff


# ------------------------------------------------------------------------------ linear algebra
@njit(cache=True)
def mat_vec(a, x, out) -> None:
    """out = a @ x for a (m, n)."""
    for i in range(a.shape[0]):
        s = 0.0
        for j in range(a.shape[1]):
            s += a[i, j] * x[j]
        out[i] = s


@njit(cache=True)
def mat_t_vec(a, x, out) -> None:
    """out = a.T @ x for a (m, n)."""
    for j in range(a.shape[1]):
        out[j] = 0.0
    for i in range(a.shape[0]):
        xi = x[i]
        for j in range(a.shape[1]):
            out[j] += a[i, j] * xi


@njit(cache=True)
def regularized_wrench_map(jac, damping_sq, gram, out) -> None:
    """out = (J J^T + damping_sq I)^-1 J by Cholesky (J J^T + lambda^2 I is SPD for lambda > 0).

    ``gram`` (m, m) is scratch (holds the Cholesky factor afterwards). A non-finite Jacobian
    gives NaN, which the controller's finite check reports.
    """
    m, n = jac.shape
    for i in range(m):
        for k in range(i + 1):
            s = 0.0
            for j in range(n):
                s += jac[i, j] * jac[k, j]
            gram[i, k] = s
        gram[i, i] += damping_sq
    for j in range(m):  # in-place lower Cholesky factor
        s = gram[j, j]
        for k in range(j):
            s -= gram[j, k] * gram[j, k]
        d = math.sqrt(s) if s > 0.0 else math.nan
        gram[j, j] = d
        for i in range(j + 1, m):
            s = gram[i, j]
            for k in range(j):
                s -= gram[i, k] * gram[j, k]
            gram[i, j] = s / d
    for c in range(n):  # L L^T x = J[:, c]
        for i in range(m):
            s = jac[i, c]
            for k in range(i):
                s -= gram[i, k] * out[k, c]
            out[i, c] = s / gram[i, i]
        for i in range(m - 1, -1, -1):
            s = out[i, c]
            for k in range(i + 1, m):
                s -= gram[k, i] * out[k, c]
            out[i, c] = s / gram[i, i]


# ----------------------------------------------------------------------------------- SO(3)
@njit(cache=True)
def quat_normalized(quat):
    """(valid, w, x, y, z) of quat / |quat|; invalid when the norm is ~0 or not finite."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if not (n > 1e-12 and math.isfinite(n)):
        return False, 1.0, 0.0, 0.0, 0.0
    return True, w / n, x / n, y / n, z / n


@njit(cache=True)
def matrix_to_quat(rot):
    """Shepperd's method: unit (w, x, y, z) of a rotation matrix with w >= 0."""
    m00, m01, m02 = rot[0, 0], rot[0, 1], rot[0, 2]
    m10, m11, m12 = rot[1, 0], rot[1, 1], rot[1, 2]
    m20, m21, m22 = rot[2, 0], rot[2, 1], rot[2, 2]
    trace = m00 + m11 + m22
    if trace >= max(m00, max(m11, m22)):
        s = 2.0 * math.sqrt(max(1.0 + trace, 0.0))
        w, x, y, z = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 >= m11 and m00 >= m22:
        s = 2.0 * math.sqrt(max(1.0 + m00 - m11 - m22, 0.0))
        w, x, y, z = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 >= m22:
        s = 2.0 * math.sqrt(max(1.0 + m11 - m00 - m22, 0.0))
        w, x, y, z = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = 2.0 * math.sqrt(max(1.0 + m22 - m00 - m11, 0.0))
        w, x, y, z = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if w < 0.0:
        n = -n
    return w / n, x / n, y / n, z / n


@njit(cache=True)
def quat_log(w, x, y, z):
    """Rotation vector of a unit quaternion with w >= 0 (angle in [0, pi])."""
    s = math.sqrt(x * x + y * y + z * z)
    if s < EPS_SMALL_ANGLE:
        # theta / s = 2 atan2(s, w) / s ~ (2 / w) (1 - s^2 / (3 w^2)); here w ~ 1.
        k = 2.0 / w * (1.0 - s * s / (3.0 * w * w))
    else:
        k = 2.0 * math.atan2(s, w) / s
    return k * x, k * y, k * z


@njit(cache=True)
def orientation_error(quat_target, rot, out) -> bool:
    """out = Log(R_d R^T) via q_d * conj(q(R)) (shortest arc); False if q_d is invalid."""
    valid, dw, dx, dy, dz = quat_normalized(quat_target)
    if not valid:
        return False
    w, x, y, z = matrix_to_quat(rot)
    ew = dw * w + dx * x + dy * y + dz * z
    ex = -dw * x + dx * w - dy * z + dz * y
    ey = -dw * y + dx * z + dy * w - dz * x
    ez = -dw * z - dx * y + dy * x + dz * w
    if ew < 0.0:
        ew, ex, ey, ez = -ew, -ex, -ey, -ez
    out[0], out[1], out[2] = quat_log(ew, ex, ey, ez)
    return True


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


# ------------------------------------------------------------------------------ controller
@njit(cache=True)
def controller_tick(
    q, dq, tau_meas, pos_target, quat_target, wrench_cmd, mask, gripper_width, fric, dyn,
    ctl, grams, wrench_maps, est, sf, model32, weights, biases, model, imp, lim,
) -> int:  # fmt: skip
    """Everything of ImpactController.compute after ``dynamics.update``; returns status bits.

    ``ctl`` is the controller buffer (``controller_views``); grams / wrench_maps (2, 6, 6) /
    (2, 6, 7) hold the estimator's and the null-space projector's solves (one when shared).
    Without "run internal model" (mode "impedance") the model is skipped entirely.
    """
    par, sig_cmd, w_extra, scalars, w_ff = controller_views(ctl)
    if not quat_normalized(quat_target)[0]:
        return BAD_QUAT
    regularized_wrench_map(dyn[0], par[0], grams[0], wrench_maps[0])
    if par[2] == 0.0:
        regularized_wrench_map(dyn[0], par[1], grams[1], wrench_maps[1])
    if par[3] == 0.0:
        residual_update(dq, tau_meas, fric, dyn, wrench_maps[0], est)
    else:
        momentum_update(dq, tau_meas, fric, dyn, wrench_maps[0], est)
    wrench_ext = est[est.shape[0] - 6:]  # both estimator layouts end with the wrench
    slow_rate = slow_filter_update(wrench_ext, sf)
    flags = 0
    pred = model_views(model)[3]
    if par[4] != 0.0:
        push_features(q, dq, gripper_width, dyn[4], wrench_ext, model32, model)
        model_predict(model32, weights, biases, model)
        flags = model_gate_step(slow_filter_views(sf)[4], slow_rate, mask, model)
    for i in range(6):
        sig_cmd[i] = wrench_cmd[i]
        if par[5] == 0.0:
            w_ff[i] = 0.0
        elif mask[i] != 0.0:
            w_ff[i] = pred[i]
        # else: a masked axis keeps the feedforward of its last unmasked tick (its prediction
        # follows input features that the commanded contact changes: positive feedback)
        w_extra[i] = w_ff[i] + wrench_cmd[i]
    wrench_map_null = wrench_maps[0] if par[2] != 0.0 else wrench_maps[1]
    impedance_law(dyn, q, dq, pos_target, quat_target, wrench_map_null, w_extra, imp)
    views = impedance_views(imp)
    torque_limiter(views[10], views[9], lim)
    _fill_scalars(views[2], slow_rate, model, par[4] != 0.0, scalars)
    for v in limiter_views(lim)[3]:
        if not math.isfinite(v):
            flags |= NON_FINITE
    return flags


@njit(cache=True)
def controller_tick_chain(
    chain, chain_work, need_coriolis, q_model, dq_model,
    q, dq, tau_meas, pos_target, quat_target, wrench_cmd, mask, gripper_width, fric, dyn,
    ctl, grams, wrench_maps, est, sf, model32, weights, biases, model, imp, lim,
) -> int:  # fmt: skip
    """``chain_terms`` (the model update, into ``dyn``) then ``controller_tick``: one call.

    ``chain`` is ``ChainParams.arrays()``; ``q_model`` / ``dq_model`` receive copies of q, dq
    (the state the model was evaluated at).
    """
    for i in range(q.shape[0]):
        q_model[i] = q[i]
        dq_model[i] = dq[i]
    chain_terms(chain[0], chain[1], chain[2], chain[3], chain[4], chain[5], chain[6], chain[7],
                chain[8], q_model, dq_model, need_coriolis, chain_work, dyn[4], dyn[5], dyn[0],
                dyn[1], dyn[3], dyn[2])
    return controller_tick(
        q, dq, tau_meas, pos_target, quat_target, wrench_cmd, mask, gripper_width, fric, dyn,
        ctl, grams, wrench_maps, est, sf, model32, weights, biases, model, imp, lim,
    )  # fmt: skip


@njit(cache=True)
def _fill_scalars(pose_error, slow_rate, model, run_model, scalars) -> None:
    """scalars = [|e_p|, |e_R|, slow rate, surprise, gate open, learning active]."""
    e = pose_error
    scalars[0] = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    scalars[1] = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
    scalars[2] = slow_rate
    state = model_views(model)[1]
    scalars[3] = state[4] if run_model else 0.0
    scalars[4] = state[3] if run_model else 0.0
    scalars[5] = state[5] if run_model else 0.0
