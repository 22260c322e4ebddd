"""Reaching the robot: one client per robot on this machine (``client_lock``), and a
connection that gives up on a host that does not answer (``probe``, ``connect``).

**The lock** is a Unix socket bound in Linux's abstract namespace under a name made from the
robot's address (``\\0impact-robot/ADDRESS``). It is not a file: it does not depend on
``TMPDIR``, on the user or on any directory's permissions, every process of the machine (its
network namespace) sees the same name, and the kernel releases it when the process ends,
however it ends (a crash, SIGKILL). A second ``impact-robot`` for the same robot fails to bind
it and names the first one's PID (read with ``SO_PEERCRED``).

**The watchdog.** pylibfranka's ``Robot(host)`` has no timeout of its own and holds Python's
GIL while it waits (measured: against a server that accepts the connection and never answers,
a thread beside it did not run for the 60 s tried), so neither a thread nor a signal handler
can stop it. ``probe`` makes the same connection and reads one state in a child process
(``sys.executable``, about 0.2 s) and kills it (by PID) after ``timeout_s``; the command's own
connection is made only after the probe was answered.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import hashlib
import socket
import struct
import subprocess
import sys
from collections.abc import Iterator

from impact_franka.fci import FrankaError

LOCK_PREFIX = "impact-robot"
"""First part of the lock's abstract socket name (``lock_name``)."""
CONNECT_TIMEOUT_S = 10.0
"""Default of ``--connect-timeout-s``: the longest wait for the robot to answer [s]."""
PROBE = """
import sys
import pylibfranka as plf
try:
    plf.Robot(sys.argv[1], plf.RealtimeConfig.kIgnore).read_once()
except Exception as exc:
    print(" ".join(str(exc).split()))
    sys.exit(3)
"""
"""The probe's program: connect as the command will, read one state, disconnect."""


def lock_name(host: str) -> str:
    """The abstract socket name of ``host``'s lock: its IPv4 address (else its first address,
    else the name as given, lower case), so ``localhost`` and ``127.0.0.1`` are one robot."""
    try:
        infos = socket.getaddrinfo(host, None, proto=socket.IPPROTO_TCP)
        addresses = [i[4][0] for i in infos]
        key = next((a for a in addresses if ":" not in a), addresses[0])
    except (OSError, IndexError, UnicodeError):
        key = host.lower()
    if len(key) > 64:
        key = hashlib.sha256(key.encode()).hexdigest()
    return f"\0{LOCK_PREFIX}/{key}"


def _owner(name: str) -> str:
    """The PID of the process holding the lock ``name`` ("?" if it cannot be told)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        probe.settimeout(1.0)
        try:
            probe.connect(name)
            pid, _, _ = struct.unpack("3i", probe.getsockopt(
                socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i")))
        except OSError:
            return "?"
    return str(pid)


@contextlib.contextmanager
def client_lock(host: str) -> Iterator[None]:
    """One ``impact-robot`` per robot on this machine, for the whole command (module doc). The
    FCI serves one controlling client; neither simulator refuses a second one (measured: both
    ran two torque loops at once), so a second run is refused here, before it connects."""
    if not sys.platform.startswith("linux"):
        raise FrankaError(f"impact-robot runs on Linux (pylibfranka's platform), not "
                          f"{sys.platform}")
    name = lock_name(host)
    lock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        lock.bind(name)
        lock.listen(8)
    except OSError as exc:
        lock.close()
        if exc.errno != errno.EADDRINUSE:
            raise FrankaError(f"cannot take the one-client lock for {host}: {exc}") from None
        raise FrankaError(f"another impact-robot (PID {_owner(name)}) is connected to {host}; "
                          "valid: one client per robot, stop it first") from None
    try:
        yield
    finally:
        lock.close()


def probe(host: str, timeout_s: float, program: str | None = None) -> None:
    """Connect to ``host`` and read one state in a child process (``program``, default
    ``PROBE``); ``FrankaError`` (one line) if it fails or takes longer than ``timeout_s``.
    However the wait ends (the timeout, Ctrl-C, SIGTERM made an exception by cli.py), a child
    still running is killed and reaped before this returns, so before the lock is released."""
    proc = subprocess.Popen([sys.executable, "-c", program or PROBE, host],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, text=True)
    try:
        out, err = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        raise FrankaError(f"cannot connect to {host}: no answer within {timeout_s:g} s "
                          "(--connect-timeout-s); valid: the robot's FCI address, FCI "
                          "activated in Desk") from None
    finally:
        _end(proc)
    if proc.returncode != 0:
        lines = (out.strip() or err.strip() or f"exit status {proc.returncode}").splitlines()
        raise FrankaError(f"cannot connect to {host}: {lines[-1]}")


def _end(proc: subprocess.Popen) -> None:
    """Kill ``proc`` if it still runs and reap it (a second interrupt does not stop this)."""
    if proc.poll() is None:
        proc.kill()
    while proc.returncode is None:
        with contextlib.suppress(KeyboardInterrupt):
            proc.wait()
    for pipe in (proc.stdout, proc.stderr):
        if pipe is not None:
            pipe.close()


def connect(args: argparse.Namespace) -> tuple[object, object]:
    """(pylibfranka module, Robot) with no errors pending (recovered on ``--recover``), once
    ``probe`` saw the robot answer within ``--connect-timeout-s``."""
    try:
        import pylibfranka as plf
    except ImportError:
        raise FrankaError("impact-robot needs pylibfranka: pip install -e '.[franka]'") from None
    probe(args.host, getattr(args, "connect_timeout_s", CONNECT_TIMEOUT_S))
    config = (plf.RealtimeConfig.kEnforce if args.realtime == "enforce"
              else plf.RealtimeConfig.kIgnore)
    try:
        robot = plf.Robot(args.host, config)
    except (plf.FrankaException, RuntimeError) as exc:  # pylibfranka's errors are RuntimeErrors
        msg = " ".join(str(exc).split())
        raise FrankaError(f"cannot connect to {args.host}: {msg}") from None
    state = robot.read_once()
    print(f"impact-robot: {args.host}: mode {state.robot_mode}, errors "
          f"{state.current_errors or 'none'}")
    if state.current_errors:
        if not args.recover:
            raise FrankaError(f"the robot reports errors {state.current_errors}; valid: clear "
                              "them, or --recover (libfranka's automatic error recovery)")
        robot.automatic_error_recovery()
        print(f"  recovered: errors now {robot.read_once().current_errors or 'none'}")
    return plf, robot
