"""The controller's per-tick kernel: every stage chained in one numba call.

Each stage module (``impedance.py``, ``estimators.py``, ``slow_filter.py``, ``limits.py``,
``internal_model/``) holds its config, the layout of its float64 state buffer (its
``*_views`` function: the only definition of that layout, giving named views) and its
``@njit`` step; its class keeps the buffer and calls that step. ``controller_tick`` runs the
steps of all stages on a ``ControllerState`` (the stages' buffers, by name);
``ImpactController.compute`` and the closed loop (``impact_envs/loop``) call it. There is no
second (NumPy) copy of this math. Shared pieces: ``kernel_layout.py`` (status bits, input
bounds, the controller's own buffer), ``kernel_math.py`` (linear algebra, SO(3)).

Everything is float64 except the internal model's history and weights (float32, the weights
shared with torch); its first dense layer accumulates in float32 (like the float32 BLAS path
it replaced), the later ones in float64.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.contact_guard import (
    contact_guard_step,
    guard_feedforward,
    unpack_guard,
)
from impact_control.estimators import momentum_update, residual_update, unpack_estimator
from impact_control.impedance import impedance_law, unpack_impedance
from impact_control.internal_model.kernels import (
    model_gate_step,
    model_predict,
    push_features,
    unpack_model,
    unpack_model32,
)
from impact_control.internal_model.learner import DIVERGED, learner_tick
from impact_control.joint_limits import joint_limit_torque
from impact_control.kernel_layout import (
    BAD_INPUT,
    BAD_QUAT,
    NON_FINITE,
    STORE,
    TRAIN,
    Packed,
    first_bad_input,
)
from impact_control.kernel_math import quat_normalized, regularized_wrench_map
from impact_control.limits import torque_limiter, unpack_limiter
from impact_control.optional_stages import (
    joint_limits_on,
    observer_on,
    optional_joint_limits,
    optional_observer,
    optional_payload,
    optional_saturation_release,
    optional_target_filter,
    saturation_release_on,
    target_filter_on,
)
from impact_control.payload_model import payload_step
from impact_control.saturation_release import (
    saturation_release_restore,
    saturation_release_step,
)
from impact_control.slow_filter import slow_filter_tick, unpack_slow_filter
from impact_control.stage_layout import N_JOINTS, Layout, slots
from impact_control.target_filter import target_filter_step
from impact_control.wrench_observer import observer_update

__all__ = [
    "BAD_INPUT", "BAD_QUAT", "DIVERGED", "NON_FINITE", "STORE", "TRAIN", "ControllerState",
    "TickState", "make_tick_state", "unpack_limiter", "unpack_tick",
    "controller_tick", "first_bad_input",
]


# ------------------------------------------------------------------------------ controller
class TickParams(NamedTuple):
    """The controller's own constants (``make_tick_state``).

    Attributes:
        lambda_sq: Estimator regularization lambda^2 [units of J squared].
        lambda_null_sq: Null-space projector regularization lambda_n^2.
        maps_shared: Whether both use the same lambda (one solve serves both).
        run_model: Whether the internal model runs (mode "impact" without the payload model).
        apply_feedforward: Whether its prediction is applied as feedforward.
        n_joints: The arm's joint count (the maps' columns).
    """

    lambda_sq: float
    lambda_null_sq: float
    maps_shared: bool
    run_model: bool
    apply_feedforward: bool
    n_joints: int


class TickState(NamedTuple):
    """What ``controller_tick`` itself writes (world frame).

    Attributes:
        params: ``TickParams``.
        estimator_gram: (6, 6) the wrench estimator's J J^T + lambda^2 I.
        projector_gram: (6, 6) the null-space projector's J J^T + lambda_n^2 I.
        estimator_map: (6, n) the estimator's (J J^T + lambda^2 I)^-1 J: joint torques to a
            world wrench.
        projector_map: (6, n) the projector's (J J^T + lambda_n^2 I)^-1 J (not computed when
            ``maps_shared``: the estimator's serves).
        wrench_cmd: (6,) the commanded wrench of the tick [N, Nm].
        wrench_ff: (6,) the feedforward applied (the prediction on unmasked axes, the last
            unmasked tick's value on masked ones) [N, Nm].
        wrench_extra: (6,) w_ff + w_cmd, mapped by J^T [N, Nm].
        pos_error_norm, rot_error_norm: (1,) |e_p| [m], |e_R| [rad].
        slow_rate: (1,) the slow filter's dimensionless rate.
        surprise, gate_open, learning_active: (1,) the internal model's (0 in "impedance").
        payload_feedforward: (1,) 1 when the payload model runs and its output is the
            feedforward (mode "impact" with ``PayloadModelConfig.enabled``; the internal model
            is then skipped). A constant in the buffer, not a scalar: no crossing cost.
    """

    params: TickParams
    estimator_gram: np.ndarray
    projector_gram: np.ndarray
    estimator_map: np.ndarray
    projector_map: np.ndarray
    wrench_cmd: np.ndarray
    wrench_ff: np.ndarray
    wrench_extra: np.ndarray
    pos_error_norm: np.ndarray
    rot_error_norm: np.ndarray
    slow_rate: np.ndarray
    surprise: np.ndarray
    gate_open: np.ndarray
    learning_active: np.ndarray
    payload_feedforward: np.ndarray


TICK_LAYOUT = Layout.of(TickState, dict(
    estimator_gram=(6, 6), projector_gram=(6, 6), estimator_map=(6, N_JOINTS),
    projector_map=(6, N_JOINTS), wrench_cmd=6, wrench_ff=6, wrench_extra=6,
    **slots("pos_error_norm rot_error_norm slow_rate surprise gate_open learning_active "
            "payload_feedforward")), dims={"n": "params.n_joints"}, args=("buf", "params"))
"""The controller's own buffer (``params`` are all scalars)."""
unpack_tick = TICK_LAYOUT.unpacker("unpack_tick", __name__)


def make_tick_state(lambda_m: float, lambda_null_m: float, run_model: bool,
                    payload_feedforward: bool = False, n_joints: int = 7) -> Packed:
    """Estimator and projector regularizations, the model on/off, the payload model's
    feedforward on/off (which skips the model), for ``n_joints`` joints; packed
    (``unpack_tick``)."""
    run_model = run_model and not payload_feedforward
    params = TickParams(lambda_m * lambda_m, lambda_null_m * lambda_null_m,
                        lambda_null_m == lambda_m, run_model, run_model, n_joints)
    packed = Packed(params, np.zeros(TICK_LAYOUT.size_for(params)))
    unpack_tick(packed.buffer, params)[0].payload_feedforward[0] = float(payload_feedforward)
    return packed


class ControllerState(NamedTuple):
    """Every state ``controller_tick`` reads and writes, one named field per stage
    (``ImpactController.kernel_state`` builds it; numba takes it as one argument).

    ``tick``: the controller's own (``TickState``); ``est``, ``sf``, ``guard``, ``imp``,
    ``lim``: the estimator's, slow filter's, contact guard's, impedance law's and limiter's
    states, each ``Packed`` (``unpack_*`` names them inside the kernel); ``model32``,
    ``weights``, ``biases``, ``model``, ``learner``: the internal model's; ``opt``: the
    optional stages' (target filter, observer, payload model, joint limits, saturation
    release: one buffer, ``optional_stages.py``).
    """

    tick: Packed
    est: Packed
    sf: Packed
    model32: np.ndarray
    weights: tuple
    biases: tuple
    model: np.ndarray
    learner: tuple
    guard: Packed
    imp: Packed
    lim: Packed
    opt: Packed


@njit(cache=True)
def controller_tick(
    q, dq, tau_meas, pos_target, quat_target, wrench_cmd, mask, gripper_width, fric, dyn, state,
) -> int:  # fmt: skip
    """Everything of ImpactController.compute after ``dynamics.update``; returns status bits.

    ``dyn`` is a ``DynamicsArrays`` at (q, dq), ``state`` a ``ControllerState``. Without
    "run internal model" (mode "impedance") the model is skipped entirely. The callers check
    the input ranges first (``first_bad_input``: ``ImpactController.compute`` in Python, the
    closed loop's ``loop_tick`` in its own call, once per tick); a zero quaternion returns
    ``BAD_QUAT`` before anything is written.
    """
    tick = unpack_tick(state.tick.buffer, state.tick.scalars)[0]
    est = unpack_estimator(state.est.buffer, state.est.scalars)[0]
    sf = unpack_slow_filter(state.sf.buffer, state.sf.scalars)[0]
    guard = unpack_guard(state.guard.buffer, state.guard.scalars)[0]
    imp = unpack_impedance(state.imp.buffer, state.imp.scalars)[0]
    lim = unpack_limiter(state.lim.buffer, state.lim.scalars)[0]
    opt = state.opt.buffer  # optional stages: each named only on the ticks it runs
    model32, weights, biases, model = state.model32, state.weights, state.biases, state.model
    par, estimator_map = tick.params, tick.estimator_map
    if not quat_normalized(quat_target)[0]:
        return BAD_QUAT
    pos_t, quat_t = pos_target, quat_target
    if target_filter_on(opt):  # the target filter (off in default and paper)
        tf = optional_target_filter(opt)
        target_filter_step(pos_target, quat_target, dyn.pos_ee_world, dyn.rot_ee_world, tf)
        pos_t, quat_t = tf.pos, tf.quat
    regularized_wrench_map(dyn.jacobian, par.lambda_sq, tick.estimator_gram, estimator_map)
    if not par.maps_shared:
        regularized_wrench_map(dyn.jacobian, par.lambda_null_sq, tick.projector_gram,
                               tick.projector_map)
    if est.momentum:
        momentum_update(dq, tau_meas, fric, dyn, estimator_map, est.observer)
        wrench_ext = est.observer.wrench
    elif not observer_on(opt):
        residual_update(dq, tau_meas, fric, dyn, estimator_map, est.residual)
        wrench_ext = est.residual.wrench
    else:  # the wrench observer takes the residual estimator's place (authors' presets)
        obs = optional_observer(opt)
        observer_update(dq, tau_meas, dyn, estimator_map, obs)
        wrench_ext = obs.wrench
    slow_rate = slow_filter_tick(wrench_ext, dyn.rot_ee_world, sf)
    flags = 0
    m = unpack_model(model)[0]
    m32 = unpack_model32(model32, int(m.params.n_features[0]))
    pred = m.pred
    if par.run_model:
        push_features(q, dq, gripper_width, dyn.pos_ee_world, wrench_ext, m32, m)
        model_predict(m32, weights, biases, m)
        contact_guard_step(pred, dyn.pos_ee_world, pos_t, sf.wrench_slow, mask, guard)
        target = guard.target  # w_slow; force axes held by the guard replaced
        flags = model_gate_step(target, slow_rate, mask, m)
        flags = learner_tick(flags, target, mask, m32, m, weights, biases, state.learner)
    if tick.payload_feedforward[0] != 0.0:
        pay = optional_payload(opt)
        payload_step(wrench_ext, sf.wrench_slow, dyn.rot_ee_world, pay)
        _add_command(pay.wrench_ff, wrench_cmd, tick)
    else:
        if saturation_release_on(opt):  # the unscaled w_ff of the last tick back first
            saturation_release_restore(tick.wrench_ff, optional_saturation_release(opt))
        _feedforward(pred, wrench_cmd, mask, guard, tick)  # w_ff, w_ff + w_cmd
    if saturation_release_on(opt):  # w_ff scaled down while a joint stays at its bound
        saturation_release_step(lim.output, lim.params.tau_max, dyn.pos_ee_world[2],
                                optional_payload(opt).gripper_cmd[0], tick.wrench_ff,
                                tick.wrench_cmd, tick.wrench_extra,
                                optional_saturation_release(opt))
    wrench_map_null = estimator_map if par.maps_shared else tick.projector_map
    impedance_law(dyn, q, dq, pos_t, quat_t, wrench_map_null, tick.wrench_extra, imp)
    if joint_limits_on(opt):  # joint-limit repulsion, added as it is
        jl = optional_joint_limits(opt)
        joint_limit_torque(q, jl)
        for j in range(imp.tau_no_gravity.shape[0]):
            imp.tau_no_gravity[j] += jl.tau[j]
    torque_limiter(imp.tau_no_gravity, imp.tau_gravity, lim)
    _fill_scalars(imp.pose_error, slow_rate, m, par.run_model, tick)
    for v in lim.output:
        if not math.isfinite(v):
            flags |= NON_FINITE
    return flags


@njit(cache=True, inline="always")
def _add_command(w_ff, wrench_cmd, tick) -> None:
    """The payload model's feedforward ``w_ff`` as the tick's w_ff, and w_ff + w_cmd."""
    for i in range(6):
        tick.wrench_cmd[i] = wrench_cmd[i]
        tick.wrench_ff[i] = w_ff[i]
        tick.wrench_extra[i] = w_ff[i] + wrench_cmd[i]


@njit(cache=True, inline="always")
def _feedforward(pred, wrench_cmd, mask, guard, tick) -> None:
    """The tick's feedforward w_ff (the prediction, per axis; 0 in mode "impedance") and
    w_ff + w_cmd, which the impedance law maps by J^T."""
    par, w_ff = tick.params, tick.wrench_ff
    for i in range(6):
        tick.wrench_cmd[i] = wrench_cmd[i]
        if not par.apply_feedforward:
            w_ff[i] = 0.0
        elif mask[i] != 0.0:
            w_ff[i] = pred[i]
        # else: a masked axis keeps the feedforward of its last unmasked tick (its prediction
        # follows input features that the commanded contact changes: positive feedback)
    if par.run_model:
        guard_feedforward(w_ff, mask, guard)  # hold and bounds (a no-op when disabled)
    for i in range(6):
        tick.wrench_extra[i] = w_ff[i] + wrench_cmd[i]


@njit(cache=True, inline="always")
def _fill_scalars(pose_error, slow_rate, m, run_model, tick) -> None:
    """The tick's scalar outputs: |e_p|, |e_R|, slow rate, surprise, gate, learning."""
    e = pose_error
    tick.pos_error_norm[0] = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    tick.rot_error_norm[0] = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
    tick.slow_rate[0] = slow_rate
    tick.surprise[0] = m.surprise[0] if run_model else 0.0
    tick.gate_open[0] = m.gate_open[0] if run_model else 0.0
    tick.learning_active[0] = m.learning_active[0] if run_model else 0.0
