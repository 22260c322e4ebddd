"""The paper's dumbbell task on the robot: pick an object at one taught pose, place it at another.

``PickPlaceTarget`` is a ``runner.TargetSource``: a fixed sequence of steps, each a straight
TCP move (minimum-jerk in time at ``speed_m_per_s``, then a wait until the TCP is within
``settle_tol_m`` of it or ``settle_timeout_s`` has passed) or a Franka Hand command run by a
``GripperProcess`` while the loop holds the pose:

    open -> above_pick -> down_to_pick -> grasp -> lift -> above_place -> down_to_place
         -> release -> retreat

A failed grasp skips to ``retreat``. The load is never declared (``set_load``): with
``--controller impact`` the controller learns the object's weight while carrying it.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_control.lie import slerp
from impact_franka.fci import FciReading
from impact_franka.gripper import GripperCommand, GripperProcess


class Pose(NamedTuple):
    """A TCP pose: ``pos_m`` (3,) [m, base frame], ``quat_wxyz`` (4,) w-first."""

    pos_m: np.ndarray
    quat_wxyz: np.ndarray


class PickPlacePlan(NamedTuple):
    """Where and how (``pick`` / ``place``: the TCP pose that holds the object there)."""

    pick: Pose
    place: Pose
    grasp: GripperCommand
    lift_m: float = 0.10
    speed_m_per_s: float = 0.10
    open_width_m: float = 0.08
    settle_tol_m: float = 0.01
    settle_timeout_s: float = 1.5


GRIPPER_STEPS = ("open", "grasp", "release")
"""The steps a run fails on: a move that stops short (a contact, a load, joint friction)
is recorded and the sequence goes on; a hand that does not open or grasp ends it."""


class StepRecord(NamedTuple):
    """One step as it ran: times [s of robot clock], ``ok`` (a move: the TCP came within
    ``settle_tol_m`` of its pose; a hand step: the hand's success flag, and for the grasp
    ``is_grasped``), and a detail (the TCP's distance to the pose when the step ended, or
    the hand's reply)."""

    name: str
    t_start_s: float
    t_end_s: float
    ok: bool
    detail: str


class _Step(NamedTuple):
    name: str
    pose: Pose | None = None
    command: GripperCommand | None = None


def _above(pose: Pose, lift_m: float) -> Pose:
    return Pose(pose.pos_m + np.array([0.0, 0.0, lift_m]), pose.quat_wxyz)


def _min_jerk(alpha: float) -> float:
    return alpha ** 3 * (10.0 - 15.0 * alpha + 6.0 * alpha * alpha)


class PickPlaceTarget:
    """The pick-and-place sequence of ``plan`` with the hand behind ``gripper``."""

    def __init__(self, plan: PickPlacePlan, gripper: GripperProcess) -> None:
        if plan.speed_m_per_s <= 0 or plan.lift_m < 0:
            raise InvalidArgumentError("invalid plan; valid: speed > 0 m/s and lift >= 0 m")
        self.plan, self.gripper = plan, gripper
        opened = GripperCommand("move", plan.open_width_m, plan.grasp.speed_m_per_s)
        self.steps = (
            _Step("open", command=opened),
            _Step("above_pick", _above(plan.pick, plan.lift_m)),
            _Step("down_to_pick", plan.pick),
            _Step("grasp", command=plan.grasp),
            _Step("lift", _above(plan.pick, plan.lift_m)),
            _Step("above_place", _above(plan.place, plan.lift_m)),
            _Step("down_to_place", plan.place),
            _Step("release", command=opened),
            _Step("retreat", _above(plan.place, plan.lift_m)),
        )
        self.records: list[StepRecord] = []
        self.finished = False
        self.gripper_cmd = 1.0
        """-1 from an opening command on, +1 from a grasp on (the loop hands it over)."""

    @property
    def failure(self) -> str:
        """The first failed hand step, described ("" if none)."""
        return next((f"step {r.name} failed ({r.detail})" for r in self.records
                     if not r.ok and r.name in GRIPPER_STEPS), "")

    @property
    def grasped(self) -> bool:
        """Whether the grasp step succeeded."""
        return any(r.name == "grasp" and r.ok for r in self.records)

    def start(self, pos: np.ndarray, quat: np.ndarray, arm: object) -> None:
        self._arm = arm
        self._pose = Pose(pos.copy(), quat.copy())
        self._index, self._sent = 0, False
        self._enter(0, 0.0)

    def _enter(self, index: int, now_s: float) -> None:
        """Begin step ``index`` at ``now_s`` from the current target pose."""
        self._index, self._t0, self._sent = index, now_s, False
        step = self.steps[index]
        if step.pose is not None:
            self._from = self._pose
            distance = float(np.linalg.norm(step.pose.pos_m - self._from.pos_m))
            self._duration = max(0.2, distance / self.plan.speed_m_per_s)
            self._turn = not np.allclose(step.pose.quat_wxyz, self._from.quat_wxyz)

    def _finish_step(self, now_s: float, ok: bool, detail: str) -> None:
        step = self.steps[self._index]
        self.records.append(StepRecord(step.name, self._t0, now_s, ok, detail))
        if step.name == "grasp" and not ok:
            self._enter(len(self.steps) - 1, now_s)  # straight to retreat
        elif self._index + 1 < len(self.steps):
            self._enter(self._index + 1, now_s)
        else:
            self.finished = True

    def target(self, now_s: float, r: FciReading) -> tuple[np.ndarray, np.ndarray]:
        if self.finished:
            return self._pose
        step = self.steps[self._index]
        if step.command is not None:
            self._gripper_step(step.command, now_s)
        else:
            self._move_step(step.pose, now_s)
        return self._pose

    def _gripper_step(self, command: GripperCommand, now_s: float) -> None:
        if not self._sent:
            self.gripper.send(command)
            self.gripper_cmd = 1.0 if command.kind == "grasp" else -1.0
            self._sent = True
            return
        reply = self.gripper.poll()
        if reply is not None:
            ok = reply.ok and (command.kind == "move" or reply.is_grasped)
            self._finish_step(now_s, ok, f"width {1e3 * reply.width_m:.1f} mm, grasped "
                              f"{reply.is_grasped}{', ' + reply.message if reply.message else ''}")

    def _move_step(self, pose: Pose, now_s: float) -> None:
        alpha = min(1.0, (now_s - self._t0) / self._duration)
        s = _min_jerk(alpha)
        pos = self._from.pos_m + s * (pose.pos_m - self._from.pos_m)
        quat = (slerp(self._from.quat_wxyz, pose.quat_wxyz, np.array([s]))[0] if self._turn
                else pose.quat_wxyz)
        self._pose = Pose(pos, quat)
        if alpha < 1.0:
            return
        error = float(np.linalg.norm(self._arm.pos_ee_world - pose.pos_m))  # type: ignore[attr-defined]
        timed_out = now_s - self._t0 - self._duration > self.plan.settle_timeout_s
        if error <= self.plan.settle_tol_m or timed_out:
            self._finish_step(now_s, error <= self.plan.settle_tol_m,
                              f"TCP {1e3 * error:.1f} mm from the pose")

    def close(self) -> None:
        self.gripper.close()
