"""What the numba kernels share: the status bits they return, the input bounds, and the
packing of a stage's state.

A stage's state crosses from Python into numba *packed*: its scalar parameters (a small
NamedTuple) and one float64 buffer holding all its arrays (``Packed``). Each stage declares
that buffer once, as a ``stage_layout.Layout``; its ``unpack_*`` (``@njit``), its length and
its flag slots come from the declaration. Passing one buffer per stage keeps the cost of
every Python -> numba call low (each array crossing costs its unboxing), while the kernels
and the stage classes read every field by name.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
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


# ----------------------------------------------------------------------------- input check
@njit(cache=True)
def _over(values, bound) -> bool:
    """Whether some element is not finite or |element| > bound (NaN fails every comparison)."""
    for v in values:  # noqa: SIM110 (numba compiles no generator expression in any())
        if not abs(v) <= bound:
            return True
    return False


@njit(cache=True)
def first_bad_input(q, dq, tau_meas, pos_target, quat_target, wrench_cmd, gripper_width) -> int:
    """Index into ``INPUT_ABS_MAX`` of the first input out of its bound, or -1 if all pass."""
    if _over(q, Q_ABS_MAX):
        return 0
    if _over(dq, DQ_ABS_MAX):
        return 1
    if _over(tau_meas, TAU_ABS_MAX):
        return 2
    if _over(pos_target, POS_ABS_MAX):
        return 3
    if _over(quat_target, QUAT_ABS_MAX):
        return 4
    if _over(wrench_cmd, WRENCH_ABS_MAX):
        return 5
    if not abs(gripper_width) <= WIDTH_ABS_MAX:
        return 6
    return -1


# --------------------------------------------------------------------------- buffer layouts
class Packed(NamedTuple):
    """A stage's state as it crosses into numba: ``scalars`` (its NamedTuple of scalar
    parameters) and ``buffer`` (every array of it, float64, laid out by its ``Layout``)."""

    scalars: Any
    buffer: np.ndarray
