"""One 1 kHz tick as one numba call: sense -> model update -> controller -> actuate.

The data crosses as named structures: ``StepPlan`` (this step's targets, noise draws and
records), ``SimArrays`` (the simulator's views, ``robot/sim.py``), ``ArmArrays`` (the arm
model, ``impact_control/chain_dynamics.py``), ``DynamicsArrays`` and ``ControllerState`` (the
controller's, ``control/``). ``bundle_tick_args`` gathers them once per policy step into one
``TickArgs`` (a numba structref), so each tick's call (``bundled_tick``) crosses one pointer
instead of unboxing some 60 arrays (measured by ``impact_experiments.crossing_cost``).
The physics step (``mj_step``) follows in Python (``closed_loop.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.experimental import structref

from impact_control.chain_dynamics import chain_terms
from impact_control.kernels import (
    BAD_INPUT,
    BAD_QUAT,
    NON_FINITE,
    controller_tick,
    first_bad_input,
    unpack_limiter,
)
from impact_envs.robot.sim_kernels import send, sense


class StepPlan(NamedTuple):
    """The ticks of one policy step: inputs (one row per tick) and records.

    ``noise`` (n, 21) standard-normal sensor draws; ``pos_targets`` (n, 3) [m] and
    ``quat_targets`` (n, 4) TCP targets; ``taus`` (n, 7) output: applied torques [Nm];
    ``qvels`` (n, 7) output: arm velocities after each tick [rad/s] (the last row is filled by
    ``ClosedLoop``); ``sensed`` (21,) output: the last readings [q, dq, tau];
    ``gripper_cmd`` in [-1, 1]; ``wrench_cmd`` (6,) [N, Nm] and ``mask`` (6,) float32 as
    ``ImpactController.loop_inputs`` gives them; ``fric_model`` (7,) zeros (the loop feeds no
    joint-friction model); ``lost`` (n,) uint8: 1 where the tick's command is lost (the
    drives repeat their last torque).
    """

    noise: np.ndarray
    pos_targets: np.ndarray
    quat_targets: np.ndarray
    taus: np.ndarray
    qvels: np.ndarray
    sensed: np.ndarray
    gripper_cmd: float
    wrench_cmd: np.ndarray
    mask: np.ndarray
    fric_model: np.ndarray
    lost: np.ndarray


class ArmArrays(NamedTuple):
    """The arm model as ``chain_terms`` reads and writes it (``PinocchioArm``'s arrays):
    ``q_model``/``dq_model`` receive the readings the model is evaluated at, ``out`` its
    ``ModelArrays``."""

    chain: tuple
    work: np.ndarray
    need_coriolis: bool
    q_model: np.ndarray
    dq_model: np.ndarray
    out: tuple


@njit(cache=True)
def loop_tick(i, frictionloss, plan, sim, arm, dyn, state) -> int:
    """Tick ``i``: read the sensors (noise row ``i``), update the arm model, run the
    controller, send the torques; returns the controller's status bits.

    ``frictionloss`` is the arm's dof Coulomb-friction force (MuJoCo's ``frictionloss``) of
    the last physics step [Nm]. Nothing is actuated when the bits report an input out of
    range, an invalid target or a non-finite torque (``ClosedLoop`` then raises). Also
    records the applied torque in ``taus[i]`` and the velocity the previous step produced in
    ``qvels[i - 1]``.
    """
    n = sim.qpos_arm.shape[0]
    if i > 0:
        for j in range(n):
            plan.qvels[i - 1, j] = sim.qvel_arm[j]
    sensed = plan.sensed
    sense(plan.noise[i], sim.noise_stds, sim.qpos_arm, sim.qvel_arm, sim.qfrc_actuator_arm,
          sim.qfrc_damper_arm, frictionloss, sim.tau_bias, sensed)
    q, dq, tau = sensed[:n], sensed[n:2 * n], sensed[2 * n:]
    width = sim.qpos[sim.finger_i] + sim.qpos[sim.finger_j]
    pos_target, quat_target = plan.pos_targets[i], plan.quat_targets[i]
    if first_bad_input(q, dq, tau, pos_target, quat_target, plan.wrench_cmd, width) >= 0:
        flags = BAD_INPUT
    else:
        for j in range(n):
            arm.q_model[j] = q[j]
            arm.dq_model[j] = dq[j]
        chain_terms(arm.chain, arm.q_model, arm.dq_model, arm.need_coriolis, arm.work, arm.out)
        flags = controller_tick(q, dq, tau, pos_target, quat_target, plan.wrench_cmd, plan.mask,
                                width, plan.fric_model, dyn, state)
    if not flags & (BAD_INPUT | BAD_QUAT | NON_FINITE):
        tau = unpack_limiter(state.lim.buffer, state.lim.scalars)[0].output
        send(tau, sim.torque_limits, sim.tau_applied, sim.ctrl, sim.arm_act, sim.gripper_act,
             plan.gripper_cmd, sim.tau_pending, sim.tau_scratch, sim.delay_ticks,
             plan.lost[i] != 0)
    for j in range(n):
        plan.taus[i, j] = sim.tau_applied[j]
    return flags


@structref.register
class TickArgsType(types.StructRef):
    """numba type of ``TickArgs`` (fields typed as given, literals widened)."""

    def preprocess_fields(self, fields):  # noqa: D102 - numba's hook
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class TickArgs(structref.StructRefProxy):
    """``loop_tick``'s arguments but the tick index and the friction force, held by reference:
    ``plan`` (``StepPlan``), ``sim`` (``SimArrays``), ``arm`` (``ArmArrays``), ``dyn``
    (``DynamicsArrays``) and ``state`` (``ControllerState``). Made by ``bundle_tick_args``."""


structref.define_proxy(TickArgs, TickArgsType, ["plan", "sim", "arm", "dyn", "state"])


@njit(cache=True)
def bundle_tick_args(plan, sim, arm, dyn, state) -> TickArgs:
    """One policy step's ``TickArgs`` (the arrays are shared, not copied)."""
    return TickArgs(plan, sim, arm, dyn, state)


@njit(cache=True)
def bundled_tick(i, frictionloss, args) -> int:
    """``loop_tick`` on the arguments held by ``args`` (a ``TickArgs``)."""
    return loop_tick(i, frictionloss, args.plan, args.sim, args.arm, args.dyn, args.state)
