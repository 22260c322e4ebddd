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
