"""The 1 kHz torque loop on the FCI: ``ImpactController`` through pylibfranka's active control.

``hold`` keeps the TCP where it was when the loop started (the paper's hold protocol) for a
given time, or streams zero torques (``float_only``: the robot's own gravity compensation
alone). Before the loop, every kernel is compiled and warmed on the current reading, so the
first 1 ms cycle does not wait on numba. Each tick: ``readOnce`` -> ``compute`` -> ``tau - g``
-> ``writeOnce``; the last command carries ``motion_finished``. A robot error ends the loop
and is reported with the robot's own error flags.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from impact_envs.control.controller import ImpactController
from impact_envs.control.lie import matrix_to_quat
from impact_franka.fci import FrankaError, reading, torque_command

WARM_TICKS = 200
"""``compute`` calls before the loop (numba compilation and the learner's first step)."""


@dataclass(frozen=True)
class LoopReport:
    """What a loop measured.

    Attributes:
        ticks: Control cycles answered.
        seconds: Wall time of the loop [s].
        compute_p50_us / compute_p999_us / compute_max_us: ``compute`` time per tick [us].
        pos_error_final_m / pos_error_max_m: TCP position error at the end / largest [m].
        tcp_vs_robot_m: Our TCP (Pinocchio, from ``q``) minus the robot's ``O_T_EE`` at the
            start [m] (frames reconciled: ~0 when Desk's end effector is the Franka Hand).
        robot_errors: The robot's error flags after the loop ("" if none).
    """

    ticks: int
    seconds: float
    compute_p50_us: float
    compute_p999_us: float
    compute_max_us: float
    pos_error_final_m: float
    pos_error_max_m: float
    tcp_vs_robot_m: float
    robot_errors: str

    @property
    def rate_hz(self) -> float:
        """Answered cycles per second."""
        return self.ticks / self.seconds if self.seconds > 0 else math.nan


def _warm(controller: ImpactController, q: np.ndarray, tau: np.ndarray, pos: np.ndarray,
          quat: np.ndarray) -> None:
    """Compile and warm every kernel on the current reading, then reset."""
    controller.reset(q)
    for _ in range(WARM_TICKS):
        controller.compute(q, np.zeros(7), tau, pos, quat)
    controller.reset(q)


def hold(robot: object, controller: ImpactController, seconds: float,
         float_only: bool = False) -> LoopReport:
    """Hold the current TCP pose for ``seconds`` (or float: zero torques) on ``robot``
    (a ``pylibfranka.Robot``); returns what the loop measured.

    Raises:
        FrankaError: The robot stopped the motion (its error flags in the message).
    """
    import pylibfranka as plf

    first = reading(robot.read_once())  # type: ignore[attr-defined]
    arm = controller.dynamics
    arm.update(first.q, np.zeros(7))
    pos, quat = arm.pos_ee_world.copy(), matrix_to_quat(arm.rot_ee_world)
    _warm(controller, first.q, first.tau_measured, pos, quat)
    costs, errors = [], []
    active = robot.start_torque_control()  # type: ignore[attr-defined]
    start = time.perf_counter()
    try:
        while True:
            state, _ = active.readOnce()
            r = reading(state)
            t0 = time.perf_counter_ns()
            tau = controller.compute(r.q, r.dq, r.tau_measured, pos, quat)
            cmd = np.zeros(7) if float_only else torque_command(tau, arm.gravity)
            costs.append((time.perf_counter_ns() - t0) * 1e-3)
            errors.append(controller.signals.pos_error_norm_m)
            torques = plf.Torques(cmd.tolist())
            done = time.perf_counter() - start >= seconds
            torques.motion_finished = done
            active.writeOnce(torques)
            if done:
                break
    except (plf.ControlException, plf.NetworkException, plf.CommandException) as exc:
        flags = str(robot.read_once().current_errors)  # type: ignore[attr-defined]
        msg = " ".join(str(exc).split())
        raise FrankaError(f"the robot stopped the motion: {msg}; errors: {flags}") from None
    elapsed = time.perf_counter() - start
    cost = np.asarray(costs)
    flags = robot.read_once().current_errors  # type: ignore[attr-defined]
    return LoopReport(
        ticks=len(costs), seconds=elapsed, compute_p50_us=float(np.percentile(cost, 50)),
        compute_p999_us=float(np.percentile(cost, 99.9)), compute_max_us=float(cost.max()),
        pos_error_final_m=float(errors[-1]), pos_error_max_m=float(max(errors)),
        tcp_vs_robot_m=float(np.linalg.norm(pos - first.pos_ee)),
        robot_errors="" if not bool(flags) else str(flags))
