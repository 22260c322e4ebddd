"""The Franka Hand from beside the 1 kHz loop: pylibfranka's ``Gripper`` in a child process.

A ``Gripper`` call blocks until the fingers stop and holds Python's GIL all the while
(measured against franky-sim: a ``move`` stalled another thread of the same process for
710 ms), so it can run neither in the loop nor in a thread beside it. ``GripperProcess``
connects in a ``spawn`` child before the loop starts (a wrong host is one line, before any
motion), then takes one command at a time: ``send`` returns at once, ``poll`` (a pipe poll,
a few microseconds) says whether the reply is in.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
from typing import Any, NamedTuple

from impact_control.errors import InvalidArgumentError
from impact_franka.fci import FrankaError

CONNECT_TIMEOUT_S = 30.0
"""Default longest wait for the child to import pylibfranka and connect to the hand [s]
(``impact-robot`` passes ``--connect-timeout-s``)."""


class GripperCommand(NamedTuple):
    """One command of pylibfranka's ``Gripper``: ``kind`` "move" (to ``width_m`` at
    ``speed_m_per_s``) or "grasp" (close toward ``width_m`` until the fingers stop, then
    squeeze with ``force_n``; success if the stop lies within ``width_m`` -
    ``epsilon_inner_m`` … ``width_m`` + ``epsilon_outer_m``)."""

    kind: str
    width_m: float
    speed_m_per_s: float = 0.1
    force_n: float = 40.0
    epsilon_inner_m: float = 0.005
    epsilon_outer_m: float = 0.005


class GripperReply(NamedTuple):
    """What a command ended with: ``ok`` (the hand's own success flag), the finger opening
    ``width_m`` [m] and ``is_grasped`` after it, and libfranka's message on an error."""

    ok: bool
    width_m: float
    is_grasped: bool
    message: str = ""


CHILD_NICE = 10
"""The hand's and the policy's processes yield the CPU to the 1 kHz loop (``os.nice``)."""


def _child(conn: Any, host: str) -> None:
    """Connect, say so (or why not), then answer commands until None."""
    import pylibfranka as plf

    os.nice(CHILD_NICE)
    try:
        gripper = plf.Gripper(host)
    except Exception as exc:  # noqa: BLE001 - pylibfranka raises RuntimeError subclasses
        conn.send(("error", " ".join(str(exc).split())))
        return
    conn.send(("ready", gripper.read_once().max_width))
    while (command := conn.recv()) is not None:
        try:
            if command.kind == "move":
                ok = gripper.move(command.width_m, command.speed_m_per_s)
            else:
                ok = gripper.grasp(command.width_m, command.speed_m_per_s, command.force_n,
                                   command.epsilon_inner_m, command.epsilon_outer_m)
            state, message = gripper.read_once(), ""
        except Exception as exc:  # noqa: BLE001 - reported to the loop, which decides
            ok, message = False, " ".join(str(exc).split())
            state = gripper.read_once()
        conn.send(GripperReply(bool(ok), float(state.width), bool(state.is_grasped), message))


class GripperProcess:
    """pylibfranka's ``Gripper`` for ``host`` in a child process (``open`` / ``close``)."""

    def __init__(self, host: str) -> None:
        self.host = host
        self.max_width_m = 0.0
        self._proc: Any = None

    def open(self, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
        """Start the child and wait until it is connected; ``FrankaError`` (one line) if the
        hand cannot be reached within ``timeout_s`` (the child is then killed: pylibfranka's
        ``Gripper(host)`` has no timeout of its own)."""
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_child, args=(child, self.host), daemon=True)
        self._proc.start()
        try:
            answered = self._conn.poll(timeout_s)
        except KeyboardInterrupt:  # Ctrl-C, or SIGTERM (cli.Terminated): the child ends first
            self._proc.kill()
            self.close()
            raise
        reply = self._conn.recv() if answered else ("error", f"no answer within {timeout_s:g} s")
        if reply[0] != "ready":
            if not answered:
                self._proc.kill()
            self.close()
            raise FrankaError(f"cannot connect to the Franka Hand at {self.host}: {reply[1]}; "
                              "valid: the address of a gripper server (port 1338), see "
                              "--gripper-host")
        self.max_width_m = float(reply[1])

    def send(self, command: GripperCommand) -> None:
        """Start ``command`` (the previous one must have replied)."""
        if command.kind not in ("move", "grasp"):
            raise InvalidArgumentError(f"invalid gripper command {command.kind!r}; valid: move, "
                                       "grasp")
        self._conn.send(command)

    def poll(self) -> GripperReply | None:
        """The reply of the running command if it is in, else None (does not block)."""
        return self._conn.recv() if self._conn.poll() else None

    def close(self) -> None:
        """Stop the child (a command in progress finishes on the hand first)."""
        if self._proc is None:
            return
        with contextlib.suppress(OSError, ValueError):
            self._conn.send(None)
        self._proc.join(timeout=10.0)
        if self._proc.is_alive():
            self._proc.kill()
        self._proc = None
