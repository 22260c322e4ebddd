"""One 1 kHz tick of the closed loop: sense (with noise) -> control -> actuate -> step physics.

Shared by the Gymnasium envs and the physics experiments so that both run identical code.
``control_tick`` calls the controller's public API (``compute``); ``FusedTicks`` runs the
same numbers with sensing, the controller's kernel and actuation in one numba call per tick,
which the envs use when nothing needs Python between those stages (tests/test_envs.py checks
that both give identical trajectories).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from impact_envs.control.controller import ImpactController, describe_bad_input
from impact_envs.control.kernels import (
    BAD_INPUT,
    BAD_QUAT,
    NON_FINITE,
    controller_tick_chain,
    limiter_views,
)
from impact_envs.errors import SimulationError
from impact_envs.robot.sim import FrankaSim
from impact_envs.robot.sim_kernels import actuate, sense


def control_tick(
    sim: FrankaSim,
    controller: ImpactController,
    rng: np.random.Generator,
    pos_target_world: np.ndarray,
    quat_target_world: np.ndarray,
    gripper_cmd: float,
    wrench_cmd_world: np.ndarray | None = None,
    learn_mask: np.ndarray | None = None,
    noise: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Run one control tick; return the sensed ``(q, dq)`` the controller used.

    ``noise``: optional (21,) standard-normal draws for the sensor reading instead of drawing
    them from ``rng`` (see ``FrankaSim.read_sensors``).
    """
    q, dq, tau_meas = sim.read_sensors(rng, noise)
    tau = controller.compute(q, dq, tau_meas, pos_target_world, quat_target_world,
                             wrench_cmd_world=wrench_cmd_world, learn_mask=learn_mask,
                             gripper_width_m=sim.gripper_width())
    sim.apply(tau, gripper_cmd)
    sim.step()
    return q, dq


@njit(cache=True)
def fused_tick(
    i, friction, noise, pos_targets, quat_targets, taus, qvels, stds, qpos_arm, qvel_arm,
    qfrc_act, qfrc_damp, bias, qpos, finger_i, finger_j, torque_limits, tau_applied, ctrl,
    arm_act, gripper_act, gripper_cmd, sensed, chain, chain_work, need_coriolis, q_model,
    dq_model, wrench_cmd, mask, fric_model, dyn, ctl, grams, wrench_maps, est, sf, model32,
    weights, biases, model, imp, lim,
) -> int:  # fmt: skip
    """read_sensors -> ImpactController.compute -> FrankaSim.apply for tick ``i``, one call.

    Tick i uses ``noise[i]`` (21 draws), ``pos_targets[i]``, ``quat_targets[i]``; it records
    the applied torque in ``taus[i]`` and the arm velocity the previous step produced in
    ``qvels[i - 1]`` (the caller records the last row after the last step). Sensor readings
    land in ``sensed`` (21,) = [q, dq, tau]; returns the controller's status bits. Nothing
    is actuated when the bits report an invalid target or a non-finite torque (``finish_tick``
    then raises, as ``compute`` does).
    """
    n = qpos_arm.shape[0]
    if i > 0:
        for j in range(n):
            qvels[i - 1, j] = qvel_arm[j]
    sense(noise[i], stds, qpos_arm, qvel_arm, qfrc_act, qfrc_damp, friction, bias, sensed)
    flags = controller_tick_chain(
        chain, chain_work, need_coriolis, q_model, dq_model, sensed[:n], sensed[n:2 * n],
        sensed[2 * n:], pos_targets[i], quat_targets[i], wrench_cmd, mask,
        qpos[finger_i] + qpos[finger_j], fric_model, dyn, ctl, grams, wrench_maps, est, sf,
        model32, weights, biases, model, imp, lim,
    )  # fmt: skip
    if not flags & (BAD_INPUT | BAD_QUAT | NON_FINITE):
        actuate(limiter_views(lim)[3], torque_limits, tau_applied, ctrl, arm_act, gripper_act,
                 gripper_cmd)
    for j in range(n):
        taus[i, j] = tau_applied[j]
    return flags


class FusedTicks:
    """The ticks of one policy step through ``fused_tick`` (build per step, then ``tick``).

    Args:
        sim: The simulator; ``sim.fused_args()`` must not be None.
        controller: The controller whose ``fused_inputs`` gave ``inputs``.
        inputs: ``controller.fused_inputs(wrench_cmd, learn_mask)`` (not None).
        noise: (n, 21) standard-normal sensor draws, one row per tick.
        taus: (n, 7) output: applied joint torques per tick [Nm].
        qvels: (n, 7) output: arm joint velocities after each tick [rad/s].
        pos_targets: (n, 3) TCP position targets [m], one row per tick.
        quat_targets: (n, 4) TCP orientation targets (w, x, y, z), one row per tick.
        gripper_cmd: Gripper command of this policy step in [-1, 1].
        learn_mask: The learning mask of this step (for ``finish_tick``).
    """

    def __init__(self, sim: FrankaSim, controller: ImpactController, inputs: tuple,
                 noise: np.ndarray, pos_targets: np.ndarray, quat_targets: np.ndarray,
                 taus: np.ndarray, qvels: np.ndarray, gripper_cmd: float,
                 learn_mask: np.ndarray | None) -> None:
        self.sim, self.controller, self.learn_mask = sim, controller, learn_mask
        self.sensed = np.empty(21)
        self._quats, self._qvels, self._pos = quat_targets, qvels, pos_targets
        head, tail = inputs
        self._wrench_cmd = tail[0]
        self._static = (noise, pos_targets, quat_targets, taus, qvels, *sim.fused_args(),
                        float(gripper_cmd), self.sensed, *head, *tail)

    def tick(self, i: int) -> None:
        """Tick ``i``: sense, control, actuate, step physics (signals: call ``finish``)."""
        sim = self.sim
        flags = fused_tick(i, sim.friction_torque(), *self._static)
        if flags & BAD_INPUT:  # the action was validated on entry: the sensed state is off
            s = self.sensed
            raise SimulationError(f"controller input out of range at tick {i}: "
                                  + describe_bad_input(s[:7], s[7:14], s[14:], self._pos[i],
                                                       self._quats[i], self._wrench_cmd,
                                                       sim.gripper_width()))
        if flags:
            self.controller.finish_tick(flags, self._quats[i], self.learn_mask)
        sim.step()

    def finish(self) -> None:
        """Record the last velocity row; refresh the controller's ``signals`` (those of the
        last tick, as ``compute`` leaves them)."""
        self._qvels[-1] = self.sim.fused_args()[2]
        self.controller.finish_tick(0, self._quats[-1], self.learn_mask)
