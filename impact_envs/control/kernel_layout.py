"""Buffer layouts of the numba kernels (``kernels.py``) and the status bits they return.

The ``*_views`` functions are the only definition of each stage's float64 buffer layout: the
stage classes call them once to get named NumPy views, the kernels call them every tick
(slicing is free in compiled code).
"""

from __future__ import annotations

from numba import njit

# Bits of the status returned by model_gate_step / controller_tick.
STORE = 1
"""Store the current sample in the replay buffer (Python side, ``InternalModel.learn``)."""
TRAIN = 2
"""Take one SGD step on the current sample (Python side, torch)."""
BAD_QUAT = 4
"""The target quaternion is zero or not finite; nothing was updated."""
NON_FINITE = 8
"""The torque command is not finite."""
BAD_INPUT = 16
"""An input is not finite or outside ``INPUT_ABS_MAX``; nothing was updated."""

# Largest magnitude accepted per input element. Generous physical bounds (the FR3 reaches
# |q| < 4.6 rad, |dq| < 2.7 rad/s, |tau| < 87 Nm): beyond them the readings are not a robot's,
# and the float arithmetic of the stages could overflow into non-finite state.
INPUT_ABS_MAX = (
    ("q", 10.0, "rad"),
    ("dq", 100.0, "rad/s"),
    ("tau_measured", 1000.0, "Nm"),
    ("pos_target_world", 10.0, "m"),
    ("quat_target_world", 1000.0, ""),
    ("wrench_cmd_world", 10000.0, "N, Nm"),
    ("gripper_width_m", 1.0, "m"),
)
"""(argument, bound, unit) in the order ``kernels.first_bad_input`` checks them."""
Q_ABS_MAX, DQ_ABS_MAX, TAU_ABS_MAX, POS_ABS_MAX, QUAT_ABS_MAX, WRENCH_ABS_MAX, WIDTH_ABS_MAX = (
    bound for _, bound, _ in INPUT_ABS_MAX
)


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
# Slots of the controller buffer's ``par`` (``controller_views``), by name.
LAMBDA_SQ = 0
"""Estimator regularization lambda^2 [m^2]."""
LAMBDA_NULL_SQ = 1
"""Null-space projector regularization lambda_n^2 [m^2]."""
MAPS_SHARED = 2
"""1 when both use the same lambda (one solve serves both), else 0."""
ESTIMATOR_KIND = 3
"""0 residual estimator, 1 momentum observer."""
RUN_MODEL = 4
"""1 runs the internal model (mode "impact"), 0 skips it (mode "impedance")."""
APPLY_FEEDFORWARD = 5
"""1 applies the prediction as feedforward, 0 does not."""


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
