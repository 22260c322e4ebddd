"""The 1 kHz torque loop on the FCI: ``ImpactController`` through pylibfranka's active control.

``hold`` keeps the TCP where it was when the loop started (the paper's hold protocol) for a
given time, or streams zero torques (``float_only``: the robot's own gravity compensation
alone). Before the loop, every kernel is compiled and warmed on the current reading, so the
first 1 ms cycle does not wait on numba. Each tick: ``readOnce`` -> ``compute`` -> ``tau - g``
-> ``writeOnce``; the last command carries ``motion_finished``, also when SIGINT or SIGTERM
arrives (the loop finishes its cycle and stops cleanly). A robot error ends the loop and is
reported with the robot's own error flags. Every tick is logged (``TICK_COLUMNS``).
"""

from __future__ import annotations

import gc
import math
import signal
import threading
import time
from dataclasses import dataclass, field, replace
from typing import NamedTuple, Protocol

import numpy as np
import pandas as pd

from impact_control.controller import ImpactController
from impact_control.lie import matrix_to_quat
from impact_control.limits import (
    LIBFRANKA_MAX_TORQUE_RATE_NM_PER_S,
    limit_rate_libfranka_kernel,
)
from impact_franka.fci import (
    FciReading,
    FrankaError,
    check_torque_source,
    reading,
    torque_command,
)

PRECOMPILE_TICKS = 200
"""``compute`` calls before the loop (numba compilation and the learner's first step)."""
TICK_COLUMNS = ("t_s", "pos_error_m", "pos_error_x_m", "pos_error_y_m", "pos_error_z_m",
                "wrench_ext_x_n", "wrench_ext_y_n", "wrench_ext_z_n", "wrench_slow_z_n",
                "wrench_pred_x_n", "wrench_pred_y_n", "wrench_pred_z_n", "wrench_imp_z_n",
                "wrench_ff_z_n", "gate_open", "guard_holding", "command_success_rate",
                "tick_compute_s")
"""Columns of ``LoopReport.ticks_table`` (``ticks.csv``), one row per control tick."""
RAMP_S = 0.3
"""Torque ramp-in at the start and ramp-out at every end (time, signal, budget) [s]."""
SUCCESS_RATE_AFTER_S = 0.5
"""The robot's command success rate is a share of its last 100 cycles: read after 0.5 s."""
BUDGET_S, BUDGET_STRIKES = 0.8e-3, 3
"""Per-tick compute budget [s] and the consecutive ticks over it that stop the loop."""


class TargetStep(NamedTuple):
    """A step of the held TCP target: ``offset_m`` (3,) [m, world] from ``at_s`` [s] on."""

    offset_m: np.ndarray
    at_s: float


class _StopRequest:
    """SIGINT / SIGTERM during the loop ask it to finish (last command ``motion_finished``)
    instead of raising inside a 1 ms cycle; the previous handlers come back afterwards."""

    def __init__(self) -> None:
        self.requested = False
        self._previous: dict[int, object] = {}

    def __enter__(self) -> _StopRequest:
        if threading.current_thread() is threading.main_thread():  # else: signals stay as set
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._previous[sig] = signal.signal(sig, self._request)
        return self

    def _request(self, signum: int, frame: object) -> None:
        self.requested = True

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


@dataclass(frozen=True)
class LoopReport:
    """What a loop measured.

    Attributes:
        ticks: Control cycles answered.
        seconds: Wall time of the loop [s].
        compute_p50_us / compute_p999_us / compute_max_us: ``compute`` time per tick [us].
        pos_error_final_m: TCP position error on the last tick of the hold, before the
            ramp-out [m].
        pos_error_max_m: Largest TCP position error of the hold, ramp-out excluded [m].
        pos_error_after_ramp_m: TCP position error on the very last tick [m]: the ramp-out
            hands the arm to the robot's own gravity compensation, which does not know an
            undeclared load, so a held payload sags during it.
        tcp_vs_robot_m: Our TCP (Pinocchio, from ``q``) minus the robot's ``O_T_EE`` at the
            start [m] (frames reconciled: ~0 when Desk's end effector is the Franka Hand).
        robot_errors: The robot's error flags after the loop ("" if none).
        stop_reason: "" (ran its time), "signal" (SIGINT / SIGTERM), "budget" (compute over
            the per-tick budget on ``BUDGET_STRIKES`` ticks in a row; these three ramp out)
            or "reflex" (the robot stopped the motion itself).
        robot_message: With "reflex", libfranka's message (it names the reflex).
        command_success_rate_min: Lowest ``control_command_success_rate`` the robot reported
            after ``SUCCESS_RATE_AFTER_S`` (the share of its last 100 cycles whose command
            arrived in time).
        lost_in_a_row_max: Longest run of robot cycles the loop did not answer, from the
            robot's clock (``RobotState.time`` advances 1 ms per cycle; a gap of k ms between
            two states read is k - 1 cycles unanswered). The robot aborts the motion with
            ``communication_constraints_violation`` at 20 in a row (libfranka's
            docs/network_requirements.rst), whatever the success rate.
        ticks_table: One row per tick, ``TICK_COLUMNS``.
    """

    ticks: int
    seconds: float
    compute_p50_us: float
    compute_p999_us: float
    compute_max_us: float
    pos_error_final_m: float
    pos_error_max_m: float
    pos_error_after_ramp_m: float
    tcp_vs_robot_m: float
    robot_errors: str
    stop_reason: str = ""
    robot_message: str = ""
    command_success_rate_min: float = math.nan
    lost_in_a_row_max: int = 0
    ticks_table: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=TICK_COLUMNS))

    @property
    def stopped_by_signal(self) -> bool:
        """Whether SIGINT / SIGTERM ended the loop early."""
        return self.stop_reason == "signal"

    @property
    def rate_hz(self) -> float:
        """Answered cycles per second."""
        return self.ticks / self.seconds if self.seconds > 0 else math.nan


def _precompile(controller: ImpactController, q: np.ndarray, tau: np.ndarray, pos: np.ndarray,
          quat: np.ndarray) -> None:
    """Compile and warm every path of ``compute`` on the current reading, then reset: ticks
    at rest, then ticks with a fake 30 N load in the measured torque, so the gate opens and
    the learner, the guard and their Python bookkeeping run once before the loop (a path met
    first inside the loop cost 2-4 ms there: missed cycles)."""
    controller.reset(q)
    for _ in range(PRECOMPILE_TICKS):
        controller.compute(q, np.zeros(7), tau, pos, quat)
    load = controller.dynamics.jacobian.T @ np.array([0.0, 0.0, -30.0, 0.0, 0.0, 0.0])
    for _ in range(2 * PRECOMPILE_TICKS):
        controller.compute(q, np.zeros(7), tau + load, pos, quat)
    controller.reset(q)


def _ramp(now: float, end: float | None, ramp_s: float) -> float:
    """Torque scale in [0, 1]: up over ``ramp_s`` from the start, down over ``ramp_s`` from
    ``end`` (None: not ending)."""
    up = min(1.0, now / ramp_s)
    return up if end is None else min(up, max(0.0, 1.0 - (now - end) / ramp_s))


class TargetSource(Protocol):
    """Where the loop's TCP target comes from, read once per 1 ms cycle (keep it cheap).

    ``start`` gets the TCP pose when the loop begins (after the warm-up) and the controller's
    arm model (its TCP is updated every cycle); ``target`` returns
    ``(position (3,) [m], quaternion (4,) w-first)`` for the cycle at ``now_s`` seconds into
    the loop, given that cycle's reading; ``close`` ends it (every exit path calls it).
    ``finished`` turns True when the source has nothing more to do: the loop then ramps out
    and ends as when its time is up. ``gripper_cmd`` is the hand's current command (-1 open
    ... +1 closed), handed to the controller whenever it changes (the authors' payload model
    holds off while the hand is commanded open; ``ImpactController.set_gripper_command``); a
    source without a hand keeps +1 (never commanded open), as does one without the
    attribute."""

    finished: bool
    gripper_cmd: float

    def start(self, pos: np.ndarray, quat: np.ndarray, arm: object) -> None: ...

    def target(self, now_s: float, r: FciReading) -> tuple[np.ndarray, np.ndarray]: ...

    def close(self) -> None: ...


class HoldTarget:
    """The start pose, moved once by ``step`` (``TargetStep``) if given."""

    def __init__(self, step: TargetStep | None = None) -> None:
        self.step = step
        self.finished = False
        self.gripper_cmd = 1.0  # no hand commanded
        self.pos, self.quat = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])

    def start(self, pos: np.ndarray, quat: np.ndarray, arm: object) -> None:
        self.pos, self.quat = pos.copy(), quat.copy()
        self._stepped = pos + (self.step.offset_m if self.step is not None else 0.0)

    def target(self, now_s: float, r: FciReading) -> tuple[np.ndarray, np.ndarray]:
        if self.step is None or now_s < self.step.at_s:
            return self.pos, self.quat
        return self._stepped, self.quat

    def close(self) -> None:
        pass


def hold(robot: object, controller: ImpactController, seconds: float,
         float_only: bool = False, budget_s: float = BUDGET_S,
         ramp_s: float = RAMP_S, torque_source: str = "tau_J",
         step: TargetStep | None = None) -> LoopReport:
    """Hold the current TCP pose for ``seconds`` (or float: zero torques) on ``robot``
    (a ``pylibfranka.Robot``), ``step`` moving the target once; ``run_loop``."""
    return run_loop(robot, controller, seconds, HoldTarget(step), float_only=float_only,
                    budget_s=budget_s, ramp_s=ramp_s, torque_source=torque_source)


def run_loop(robot: object, controller: ImpactController, seconds: float,
             source: TargetSource, float_only: bool = False, budget_s: float = BUDGET_S,
             ramp_s: float = RAMP_S, torque_source: str = "tau_J") -> LoopReport:
    """Track ``source``'s targets for ``seconds`` (or float: zero torques) on ``robot``;
    returns what the loop measured. Time is the robot's own clock (``RobotState.time``, 1 ms
    per cycle; a simulator slower than real time runs its clock slower): the targets, the
    duration, the ramps and ``ticks.csv``'s ``t_s`` follow it, not the wall clock.

    The command is ramped in over ``ramp_s`` and out over ``ramp_s`` at every end, then
    rate-limited against the previous command exactly as libfranka's ``limitRate`` (the
    ramp must not add a step the robot refuses). ``torque_source`` (``fci.TORQUE_SOURCES``)
    says what the controller reads as the measured joint torque.

    A reflex (the robot stops the motion) ends the loop with ``stop_reason`` "reflex", the
    robot's message in ``robot_message`` and its error flags in ``robot_errors``; the ticks
    up to it are kept.
    """
    import pylibfranka as plf

    add_gravity = check_torque_source(torque_source)
    first = reading(robot.read_once())  # type: ignore[attr-defined]
    arm = controller.dynamics
    arm.update(first.q, np.zeros(7))
    pos, quat = arm.pos_ee_world.copy(), matrix_to_quat(arm.rot_ee_world)
    _precompile(controller, first.q, first.tau_measured, pos, quat)
    rows: list[tuple] = []
    sent, reason, end, strikes, held, message = np.zeros(7), "", None, 0, 0, ""
    success, robot_t0, gripper, previous_t, lost = 1.0, None, 1.0, None, 0
    controller.set_gripper_command(gripper)
    source.start(pos, quat, arm)
    _pause_gc()
    start = time.perf_counter()
    try:
        active = _start_torque_control(robot, plf)
        with _StopRequest() as stop:
            while True:
                state, _ = active.readOnce()
                robot_t = state.time.to_sec()  # the robot's clock: 1 ms per cycle
                robot_t0 = robot_t if robot_t0 is None else robot_t0
                if previous_t is not None:
                    lost = max(lost, round((robot_t - previous_t) * 1e3) - 1)
                previous_t = robot_t
                now = robot_t - robot_t0
                r = reading(state)
                t0 = time.perf_counter_ns()
                tau_meas = r.tau_measured + arm.gravity if add_gravity else r.tau_measured
                target_pos, target_quat = source.target(now, r)
                if getattr(source, "gripper_cmd", 1.0) != gripper:
                    gripper = getattr(source, "gripper_cmd", 1.0)
                    controller.set_gripper_command(gripper)
                tau = controller.compute(r.q, r.dq, tau_meas, target_pos, target_quat)
                cmd = np.zeros(7) if float_only else torque_command(tau, arm.gravity)
                cost = (time.perf_counter_ns() - t0) * 1e-9
                rate = float(state.control_command_success_rate)
                if now > SUCCESS_RATE_AFTER_S:
                    success = min(success, rate)
                strikes = strikes + 1 if cost > budget_s else 0
                if end is None and (now >= seconds or stop.requested or source.finished or
                                    strikes >= BUDGET_STRIKES):
                    end, held = now, len(rows)
                    reason = ("signal" if stop.requested else
                              "budget" if strikes >= BUDGET_STRIKES else "")
                scale = _ramp(now, end, ramp_s)
                limit_rate_libfranka_kernel(cmd * scale, sent.copy(),
                                            LIBFRANKA_MAX_TORQUE_RATE_NM_PER_S, sent)
                rows.append(_tick_row(now, controller, rate, cost))
                done = end is not None and scale == 0.0 and not np.any(sent)
                torques = plf.Torques(sent.tolist())
                torques.motion_finished = done
                active.writeOnce(torques)
                if done:
                    break
    except (plf.ControlException, plf.NetworkException, plf.CommandException) as exc:
        message, reason = " ".join(str(exc).split()), "reflex"
        held = held if end is not None else len(rows)
    finally:
        gc.enable()
        gc.unfreeze()
        source.close()
    report = _report(pd.DataFrame(rows, columns=TICK_COLUMNS), time.perf_counter() - start,
                     float(np.linalg.norm(pos - first.pos_ee)), robot, reason, held)
    return replace(report, robot_message=message, command_success_rate_min=success,
                   lost_in_a_row_max=lost)


def _pause_gc() -> None:
    """No garbage collection inside the 1 kHz loop: a full collection of a large heap took
    18 ms here (missed cycles). Reference counting still frees what the loop drops; the loop's
    ``finally`` re-enables collection."""
    gc.collect()
    gc.freeze()
    gc.disable()


def _tick_row(now: float, controller: ImpactController, rate: float, cost: float) -> tuple:
    """One ``ticks.csv`` row (``TICK_COLUMNS``) from the controller's last tick."""
    sig = controller.signals
    ext, pred, err = sig.wrench_ext_world, sig.wrench_pred_world, sig.pose_error
    return (now, sig.pos_error_norm_m, err[0], err[1], err[2], ext[0], ext[1], ext[2],
            sig.wrench_slow_world[2], pred[0], pred[1], pred[2], sig.wrench_imp_world[2],
            sig.wrench_ff_world[2], int(sig.gate_open), int(controller.guard.holding), rate,
            cost)


def _start_torque_control(robot: object, plf: object) -> object:
    """The robot's active torque control, or ``FrankaError`` (one line) if it refuses: the
    robot is not ready (a reflex, the user stop pressed) or another client is in control."""
    try:
        return robot.start_torque_control()  # type: ignore[attr-defined]
    except (plf.ControlException, plf.NetworkException,  # type: ignore[attr-defined]
            plf.CommandException) as exc:  # type: ignore[attr-defined]
        raise FrankaError("the robot refused torque control: "
                          f"{' '.join(str(exc).split())}") from None


def _report(table: pd.DataFrame, elapsed: float, tcp_vs_robot_m: float, robot: object,
            reason: str, held: int) -> LoopReport:
    """The ``LoopReport`` of a finished loop's tick log (reads the robot's error flags);
    its first ``held`` rows are the hold, the rest the ramp-out."""
    cost_us = table["tick_compute_s"].to_numpy() * 1e6
    errors = table["pos_error_m"].to_numpy()
    if not len(table):  # a reflex on the first cycle
        cost_us, errors = np.full(1, math.nan), np.full(1, math.nan)
    held = min(max(held, 1), len(errors))
    flags = robot.read_once().current_errors  # type: ignore[attr-defined]
    return LoopReport(
        ticks=len(table), seconds=elapsed, compute_p50_us=float(np.percentile(cost_us, 50)),
        compute_p999_us=float(np.percentile(cost_us, 99.9)),
        compute_max_us=float(cost_us.max()), pos_error_final_m=float(errors[held - 1]),
        pos_error_max_m=float(errors[:held].max()), pos_error_after_ramp_m=float(errors[-1]),
        tcp_vs_robot_m=tcp_vs_robot_m,
        robot_errors="" if not bool(flags) else str(flags), stop_reason=reason,
        ticks_table=table)
