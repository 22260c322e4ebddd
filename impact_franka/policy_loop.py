"""Any policy of the project's ``Policy`` protocol on the robot, at 30 Hz over the 1 kHz loop.

The policy runs in a child process (its inference may take tens of milliseconds and holds
the GIL; the 1 kHz loop may not wait). Every policy period the loop sends the child the
observation the robot can measure (``ee_pos``, ``ee_rot6d``, ``joint_pos``, ``joint_vel``,
``gripper_width``) and, in the child, the user's ``extra_obs()`` adds what it cannot (an
object's pose from a tracker); the action that comes back becomes the next target, reached by
linear / spherical interpolation over one policy period, as in the simulated envs. While the
child is computing, the loop keeps interpolating toward the last target; it never blocks.

Safety: every target is clipped into the workspace box the user gives and moved at most
``max_step_m`` per policy period; a non-finite action is refused (the last target stays) and
counted. The gripper (``action[9]``, -1 open / +1 closed) is driven from the child through
pylibfranka's ``Gripper`` when a gripper host is given.

    from impact_franka.policy_loop import PolicyTarget
    source = PolicyTarget(make_policy, extra_obs, workspace=(low, high))
    report = run_loop(robot, controller, 20.0, source)

``make_policy`` and ``extra_obs`` must be picklable (module-level functions or
``functools.partial`` of them): the child is started with ``spawn``. examples/robot_policy.py
shows the round trip.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
from collections.abc import Callable
from typing import Any

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_control.lie import matrix_from_rot6d, matrix_to_quat, rot6d_from_matrix, slerp
from impact_control.rates import POLICY_HZ
from impact_franka.fci import FciReading, FrankaError
from impact_franka.gripper import CHILD_NICE

START_TIMEOUT_S = 120.0
"""Longest wait for the child to build its policy (imports, checkpoint loading)."""


def _child(conn: Any, make_policy: Callable[[], Any], extra_obs: Callable[[], dict] | None,
           gripper_host: str | None) -> None:
    """The policy process: build, answer observations with actions, drive the gripper."""
    from impact_control.policy import stack_obs

    os.nice(CHILD_NICE)  # the loop wins the CPU over inference
    policy = make_policy()
    policy.reset(1)
    gripper, closed = None, None
    if gripper_host is not None:
        import pylibfranka as plf

        gripper = plf.Gripper(gripper_host)
    conn.send("ready")
    while (obs := conn.recv()) is not None:
        if gripper is not None:
            obs["gripper_width"] = np.array([gripper.read_once().width], np.float32)
        if extra_obs is not None:
            obs.update({k: np.asarray(v, np.float32) for k, v in extra_obs().items()})
        action = np.asarray(policy.act(stack_obs([obs]))[0], dtype=np.float64)
        conn.send(action)
        if gripper is not None and (want := bool(action[9] > 0.0)) != closed:
            closed = want  # after the reply: the loop does not wait on the fingers
            if want:
                gripper.grasp(0.0, 0.1, 40.0, 0.08, 0.08)
            else:
                gripper.move(0.08, 0.1)


class PolicyTarget:
    """A ``runner.TargetSource`` whose targets come from a policy at ``POLICY_HZ``.

    Args:
        make_policy: Builds the policy in the child process (picklable).
        extra_obs: Returns the observation entries the robot cannot measure (picklable;
            called in the child once per policy step), or None.
        workspace: ``(low (3,), high (3,))`` [m, base frame]: every target is clipped into it.
        max_step_m: Largest target move per policy period [m] (0.03: 0.9 m/s).
        gripper_host: The Franka Hand's address (pylibfranka ``Gripper``), or None.
    """

    def __init__(self, make_policy: Callable[[], Any],
                 extra_obs: Callable[[], dict[str, np.ndarray]] | None,
                 workspace: tuple[np.ndarray, np.ndarray], max_step_m: float = 0.03,
                 gripper_host: str | None = None) -> None:
        low, high = (np.asarray(w, dtype=float) for w in workspace)
        if low.shape != (3,) or high.shape != (3,) or not np.all(low < high):
            raise InvalidArgumentError("invalid workspace; valid: (low (3,), high (3,)) finite, "
                                       "with low < high")
        self.low, self.high, self.max_step_m = low, high, float(max_step_m)
        self._args = (make_policy, extra_obs, gripper_host)
        self.refused = self.actions = 0
        self.gripper_cmd = 1.0
        """The last accepted action's gripper value (``action[9]``, clipped to [-1, 1])."""
        self.finished = False  # a policy runs until the loop's time is up
        self._proc: Any = None

    def start(self, pos: np.ndarray, quat: np.ndarray, arm: Any) -> None:
        """Start the child and wait until its policy is built (before the loop runs); ``arm``
        is the controller's model, whose TCP pose the observations report."""
        self._arm = arm
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_child, args=(child, *self._args), daemon=True)
        self._proc.start()
        if not self._conn.poll(START_TIMEOUT_S) or self._conn.recv() != "ready":
            self.close()
            raise FrankaError(f"the policy process did not start in {START_TIMEOUT_S:g} s")
        self._from = self._to = np.clip(pos, self.low, self.high)
        self._q_from = self._q_to = quat.copy()
        self._t0, self._next, self._waiting = 0.0, 0.0, False

    def target(self, now_s: float, r: FciReading) -> tuple[np.ndarray, np.ndarray]:
        """The interpolated target; once per period, collect an action and send an obs."""
        if now_s >= self._next:
            self._next += 1.0 / POLICY_HZ
            if self._waiting and self._conn.poll():
                self._new_segment(now_s, self._conn.recv())
                self._waiting = False
            if not self._waiting:
                self._conn.send(self._observation(r))
                self._waiting = True
        alpha = min(1.0, (now_s - self._t0) * POLICY_HZ)
        return (self._from + alpha * (self._to - self._from),
                slerp(self._q_from, self._q_to, np.array([alpha]))[0])

    def _new_segment(self, now_s: float, action: np.ndarray) -> None:
        """Start interpolating from the current target to ``action``'s (clipped, bounded)."""
        self.actions += 1
        if action.shape != (10,) or not np.all(np.isfinite(action)):
            self.refused += 1
            return
        alpha = min(1.0, (now_s - self._t0) * POLICY_HZ)
        here = self._from + alpha * (self._to - self._from)
        q_here = slerp(self._q_from, self._q_to, np.array([alpha]))[0]
        move = np.clip(action[:3], self.low, self.high) - here
        norm = float(np.linalg.norm(move))
        if norm > self.max_step_m:
            move *= self.max_step_m / norm
        self._from, self._to = here, here + move
        self._q_from, self._q_to = q_here, matrix_to_quat(matrix_from_rot6d(action[3:9]))
        self._t0 = now_s
        self.gripper_cmd = float(np.clip(action[9], -1.0, 1.0))

    def _observation(self, r: FciReading) -> dict[str, np.ndarray]:
        """What the robot measures, as the envs name it (float32; the TCP from our model at
        the previous cycle's reading, 1 ms old, as the controller tracks it)."""
        return {"ee_pos": self._arm.pos_ee_world.astype(np.float32),
                "ee_rot6d": rot6d_from_matrix(self._arm.rot_ee_world).astype(np.float32),
                "joint_pos": r.q.astype(np.float32), "joint_vel": r.dq.astype(np.float32),
                "gripper_width": np.zeros(1, np.float32)}

    def close(self) -> None:
        """Stop the child (on every exit path of the loop)."""
        if self._proc is None:
            return
        with contextlib.suppress(OSError, ValueError):  # the child may be gone already
            self._conn.send(None)
        self._proc.join(timeout=5.0)
        if self._proc.is_alive():
            self._proc.kill()
        self._proc = None
