"""The closed loop over robot/ and control/: sense -> control -> actuate -> step, at 1 kHz.

One path for every task: ``ClosedLoop.run`` runs the ticks of one policy step, each one numba
call (``tick.bundled_tick`` on the step's ``TickArgs``) followed by ``mj_step``; a task that
declares a per-tick hook (``Task.has_tick_hook``) gets it called before each tick.
``control_tick`` is the same tick through the controller's public ``compute`` (what a real FR3
would run); tests/loop/test_loop.py checks that both give identical trajectories.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numba
import numpy as np

from impact_control.arm_model import dynamics_arrays
from impact_control.controller import ImpactController, describe_bad_input
from impact_control.dynamics import PinocchioArm
from impact_control.errors import SimulationError
from impact_control.kernels import BAD_INPUT
from impact_envs.loop.tick import ArmArrays, StepPlan, bundle_tick_args, bundled_tick
from impact_envs.robot.sim import FrankaSim

CONTACT_EVERY = 4
"""Contact forces are sampled every 4th tick and on a step's last one."""

FF_PUSH_FROM_N = 10.0
"""The feedforward's push into the robot's contact (``StepTrace.ff_into_contact_n``) is
computed only where that contact exceeds this [N] (0 elsewhere; the diagnostic that reads it
counts contacts above 20 N)."""


class StepTrace(NamedTuple):
    """What one policy step's ticks leave: per-tick ``taus`` (n, 7) [Nm] and ``qvels`` (n, 7)
    [rad/s], the last sensed ``q`` [rad] and ``dq`` [rad/s], the peak contact forces [N] on
    the robot and on the objects (``FrankaSim.contact_forces``), and both forces per tick
    ``contact_robot_n`` / ``contact_object_n`` (n,) [N], each sample held over the ticks
    since the previous one (sampled every ``CONTACT_EVERY`` ticks and on the last), and
    ``ff_into_contact_n`` (n,) [N], sampled with them when
    ``ClosedLoop.record_press_diagnostics`` is on (None otherwise): how hard the
    controller's feedforward wrench pushes the robot into the environment along the
    robot-environment contact normal
    (``FrankaSim.push_into_contact``; 0 where the robot's contact is at most
    ``FF_PUSH_FROM_N``), and with it ``contact_object_net_n`` (n,) [N]: the magnitude of the
    environment's net force on the objects (``FrankaSim.object_net_contact``: normals and
    friction as vectors, where ``contact_object_n`` sums normals)."""

    taus: np.ndarray
    qvels: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    peak_robot_contact_n: float
    peak_object_contact_n: float
    contact_robot_n: np.ndarray
    contact_object_n: np.ndarray
    ff_into_contact_n: np.ndarray | None
    contact_object_net_n: np.ndarray | None


class TickTargets(NamedTuple):
    """The inputs of one policy step: per-tick TCP targets ``positions`` (n, 3) [m] and
    ``quats`` (n, 4), sensor draws ``noise`` (n, 21), ``gripper_cmd`` in [-1, 1], and the
    task's ``wrench_cmd`` (6,) [N, Nm] and ``learn_mask`` (6 bools) or None."""

    positions: np.ndarray
    quats: np.ndarray
    noise: np.ndarray
    gripper_cmd: float
    wrench_cmd: np.ndarray | None
    learn_mask: np.ndarray | None


class ClosedLoop:
    """Runs policy steps of 1 kHz ticks for one simulator, arm model and controller.

    Args:
        sim: The simulator (its arm joints contiguous in MuJoCo's arrays).
        dynamics: The controller's arm model (its ``chain_terms`` arrays).
        controller: The controller; ``reset`` it before ``run``.
        tick_hook: Called as ``tick_hook(sim, time_s)`` before every tick, or None.
        command_loss_rate: Probability that a tick's command is lost (the drives repeat
            their last torque); the draws come from ``loss_rng`` (set it before ``run``), none
            are made at 0.
    """

    def __init__(self, sim: FrankaSim, dynamics: PinocchioArm, controller: ImpactController,
                 tick_hook: Callable[[FrankaSim, float], None] | None = None,
                 command_loss_rate: float = 0.0) -> None:
        self.sim, self.controller, self.tick_hook = sim, controller, tick_hook
        self.command_loss_rate = float(command_loss_rate)
        self.loss_rng = np.random.default_rng(0)
        """Source of the lost-command draws (the env reseeds it each episode)."""
        self._no_loss = np.zeros(0, dtype=np.uint8)
        self.arm = ArmArrays(dynamics.chain, dynamics.chain_work, bool(dynamics.need_coriolis),
                             dynamics.q_model, dynamics.dq_model, dynamics.model_arrays)
        self._dyn = dynamics_arrays(dynamics)
        self.record_press_diagnostics = False
        """Record ``StepTrace.ff_into_contact_n`` and ``contact_object_net_n`` (issue 54's
        diagnostics; off: the loop does none of their work, a Jacobian and a pseudo-inverse
        per contact sample and a pass over the object's contacts)."""
        self._fric_model = np.zeros(7)
        self._bundle: Callable[..., object] | None = None
        self._tick: Callable[..., int] | None = None

    def _entries(self, args: tuple, friction: Callable[[], np.ndarray]
                 ) -> tuple[Callable[..., object], Callable[..., int]]:
        """``bundle_tick_args`` and ``bundled_tick`` compiled for these argument types,
        resolved on the first step: calling them skips numba's per-call type dispatch (about
        0.1 us per array, some 60 arrays here). Every array the loop passes is built here or
        by the simulator and controller with fixed dtypes and dimensions, so the types never
        change (``friction``: gives the per-tick friction argument)."""
        if self._tick is None:
            self._bundle = bundle_tick_args.compile(tuple(numba.typeof(a) for a in args))
            bundled = self._bundle(*args)
            self._tick = bundled_tick.compile(
                (numba.typeof(0), numba.typeof(friction()), numba.typeof(bundled)))
        return self._bundle, self._tick

    def run(self, targets: TickTargets) -> StepTrace:
        """The ticks of one policy step (one per row of ``targets.positions``)."""
        sim, ctrl = self.sim, self.controller
        n = targets.positions.shape[0]
        cmd, mask = ctrl.loop_inputs(targets.wrench_cmd, targets.learn_mask)
        ctrl.set_gripper_command(targets.gripper_cmd)  # the payload model's hold-off reads it
        plan = StepPlan(targets.noise, targets.positions, targets.quats, np.empty((n, 7)),
                        np.empty((n, 7)), np.empty(21), float(targets.gripper_cmd), cmd, mask,
                        self._fric_model, self._lost(n))
        parts = (plan, sim.loop_arrays(), self.arm, self._dyn, ctrl.kernel_state())
        friction = sim.frictionloss_reader()  # the friction inside the torque reading
        bundle, tick = self._entries(parts, friction)
        args = bundle(*parts)
        contact = np.empty((n, 4))  # robot, object, feedforward push, object's net force
        ff = ctrl.tick.wrench_ff  # a view: this tick's applied feedforward
        record = self.record_press_diagnostics
        last = 0
        hook, data = self.tick_hook, sim.data
        for i in range(n):
            if hook is not None:
                hook(sim, float(data.time))
            flags = tick(i, friction(), args)
            if flags:
                self._raise_or_learn(i, flags, plan, targets.learn_mask)
            sim.step()
            if (i + 1) % CONTACT_EVERY == 0 or i == n - 1:
                robot, obj = sim.contact_forces()
                push = (sim.push_into_contact(ff) if record and robot > FF_PUSH_FROM_N
                        else 0.0)
                net = sim.object_net_contact() if record else 0.0
                contact[last:i + 1] = robot, obj, push, net
                last = i + 1
        sim.check_finite()
        plan.qvels[-1] = parts[1].qvel_arm
        ctrl.finish_tick(0, plan.quat_targets[-1], targets.learn_mask)
        q, dq = plan.sensed[:7].copy(), plan.sensed[7:14].copy()
        peak_robot, peak_obj = (max(float(v), 0.0) for v in contact[:, :2].max(axis=0))
        return StepTrace(plan.taus, plan.qvels, q, dq, peak_robot, peak_obj,
                         contact[:, 0], contact[:, 1], contact[:, 2] if record else None,
                         contact[:, 3] if record else None)

    def _lost(self, n: int) -> np.ndarray:
        """(n,) uint8: 1 where a tick's command is lost (drawn only when the rate is > 0)."""
        if self.command_loss_rate > 0.0:
            return (self.loss_rng.random(n) < self.command_loss_rate).astype(np.uint8)
        if self._no_loss.shape[0] != n:
            self._no_loss = np.zeros(n, dtype=np.uint8)
        return self._no_loss

    def _raise_or_learn(self, i: int, flags: int, plan: StepPlan,
                        learn_mask: np.ndarray | None) -> None:
        """After tick ``i``: raise on a refused tick, else run the scheduled learning."""
        if flags & BAD_INPUT:  # the action was validated on entry: the sensed state is off
            s = plan.sensed
            raise SimulationError(
                f"controller input out of range at tick {i}: " + describe_bad_input(
                    s[:7], s[7:14], s[14:], plan.pos_targets[i], plan.quat_targets[i],
                    plan.wrench_cmd, self.sim.gripper_width()))
        self.controller.finish_tick(flags, plan.quat_targets[i], learn_mask)


def control_tick(
    sim: FrankaSim,
    controller: ImpactController,
    rng: np.random.Generator,
    pos_target_world: np.ndarray,
    quat_target_world: np.ndarray,
    gripper_cmd: float,
) -> tuple[np.ndarray, np.ndarray]:
    """One tick through the controller's public ``compute`` (no commanded wrench, learning on
    every axis); returns the sensed ``(q, dq)`` it used. Draws the 21 sensor-noise numbers
    from ``rng``."""
    q, dq, tau_meas = sim.read_sensors(rng)
    tau = controller.compute(q, dq, tau_meas, pos_target_world, quat_target_world,
                             gripper_width_m=sim.gripper_width(), gripper_cmd=gripper_cmd)
    sim.apply(tau, gripper_cmd)
    sim.step()
    return q, dq
