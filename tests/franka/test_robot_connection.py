"""The one-client lock (independent of TMPDIR and of the user, released by the kernel) and
the connection watchdog (a host that accepts and never answers, a hand that never answers).
Only the silent-server cases need pylibfranka; nothing dials beyond 127.0.0.1."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from franka_servers import port_open
from robot_cli import no_connect, run_cli

from impact_franka.connection import client_lock, lock_name, probe
from impact_franka.fci import FrankaError

HOLD = """
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
s.bind("\\0" + sys.argv[1]); s.listen(8)
print("held", flush=True)
sys.stdin.read()
"""
"""Another process holding a lock name (no package import: a plain abstract socket; argv
cannot carry the name's leading NUL)."""


def _holder(name: str, tmp_path: Path, uid: int | None = None) -> subprocess.Popen:
    """A process holding ``name`` with its own TMPDIR (as user ``uid`` if given: then the
    system's python, which any user may run)."""
    env = {**os.environ, "TMPDIR": str(tmp_path), "HOME": str(tmp_path)}
    preexec = (lambda: os.setuid(uid)) if uid is not None else None
    python = sys.executable
    if uid is not None:
        python = shutil.which("python3", path="/usr/bin:/bin") or ""
        if not python:
            pytest.skip("no system python3 another user may run")
    proc = subprocess.Popen([python, "-I", "-S", "-c", HOLD, name[1:]], env=env,
                            text=True,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            preexec_fn=preexec)  # noqa: PLW1509 - a test's own child
    assert proc.stdout is not None and proc.stdout.readline() == "held\n"
    return proc


def _stop(proc: subprocess.Popen) -> None:
    proc.kill()
    proc.wait(timeout=10)


def test_a_second_lock_in_this_process_is_refused_naming_the_pid() -> None:
    with client_lock("127.0.0.1"), pytest.raises(FrankaError) as exc, client_lock("127.0.0.1"):
        pass
    assert f"another impact-robot (PID {os.getpid()}) is connected to 127.0.0.1" in str(exc.value)
    with client_lock("127.0.0.1"):  # released on exit
        pass


@pytest.mark.parametrize("uid", [None, 65534], ids=["other_tmpdir", "other_user"])
def test_a_lock_held_under_another_tmpdir_or_user_refuses(uid, tmp_path, monkeypatch) -> None:
    if uid is not None and os.geteuid() != 0:
        pytest.skip("switching user needs root")
    other = tmp_path / "other"
    other.mkdir(mode=0o777)
    holder = _holder(lock_name("127.0.0.1"), other, uid)
    try:
        monkeypatch.setenv("TMPDIR", str(tmp_path))
        with pytest.raises(FrankaError, match=f"PID {holder.pid}"), client_lock("127.0.0.1"):
            pass
    finally:
        _stop(holder)
    with client_lock("127.0.0.1"):  # the kernel released it with the killed holder
        pass


def test_our_lock_refuses_another_process_with_another_tmpdir(tmp_path) -> None:
    with client_lock("localhost"):
        result = subprocess.run([sys.executable, "-I", "-S", "-c", HOLD,
                                 lock_name("127.0.0.1")[1:]], env={"TMPDIR": str(tmp_path)},
                                capture_output=True, text=True, timeout=30, input="")
    assert result.returncode == 1 and "Address already in use" in result.stderr


def test_the_lock_name_ignores_tmpdir_and_spelling(monkeypatch, tmp_path) -> None:
    name = lock_name("127.0.0.1")
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    assert lock_name("127.0.0.1") == lock_name("localhost") == name
    assert name.startswith("\0impact-robot") and name.endswith("/127.0.0.1")
    assert lock_name("192.0.2.7") != name
    assert len(lock_name("a" * 200).encode()) < 108  # a socket name's limit
    with client_lock("127.0.0.1"), client_lock("192.0.2.7"):  # robots apart
        pass


def test_the_cli_refuses_a_second_client_before_connecting(tmp_path, monkeypatch,
                                                           capsys) -> None:
    no_connect(monkeypatch)
    holder = _holder(lock_name("127.0.0.1"), tmp_path)
    try:
        code, err = run_cli(["check", "--host", "127.0.0.1"], capsys)
    finally:
        _stop(holder)
    assert code == 1 and err.count("\n") == 1 and f"PID {holder.pid}" in err


def test_the_watchdog_kills_a_connection_that_never_answers(tmp_path) -> None:
    pid_file = tmp_path / "pid"
    blocking = ("import os, sys, time\nopen(sys.argv[2], 'w').write(str(os.getpid()))\n"
                "time.sleep(60)\n").replace("sys.argv[2]", repr(str(pid_file)))
    start = time.monotonic()
    with pytest.raises(FrankaError, match=r"no answer within 1\.5 s \(--connect-timeout-s\)"):
        probe("127.0.0.1", 1.5, blocking)
    assert time.monotonic() - start < 10.0
    assert not Path(f"/proc/{pid_file.read_text()}").exists()  # killed and reaped


def test_the_probe_reports_the_connection_s_own_error() -> None:
    failing = "import sys\nprint('libfranka: Connection refused')\nsys.exit(3)\n"
    with pytest.raises(FrankaError, match="cannot connect to 10.0.0.9: libfranka: Connection "
                                          "refused$"):
        probe("10.0.0.9", 30.0, failing)


def test_an_interrupt_before_the_loop_is_one_line(monkeypatch, capsys) -> None:
    from impact_franka import session

    def interrupted(args: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(session, "connect", interrupted)
    code, err = run_cli(["check", "--host", "192.0.2.1"], capsys)
    assert code == 130 and err.count("\n") == 1 and "interrupted" in err


class _SilentServer:
    """Accepts on 127.0.0.1:``port`` and never answers (a hung robot)."""

    def __init__(self, port: int) -> None:
        if port_open(port):
            pytest.skip(f"127.0.0.1:{port} is taken")
        self.sock = socket.socket()
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", port))
        self.sock.listen(8)
        self.accepted: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                self.accepted.append(self.sock.accept()[0])
            except OSError:
                return

    def close(self) -> None:
        self.sock.close()
        for conn in self.accepted:
            conn.close()


def test_a_robot_that_accepts_and_never_answers_is_given_up(tmp_path, capsys) -> None:
    """The issue's hang: `check` against a host that accepts the connection and stays
    silent ended only past 75 s. Now: exit 1, one line, within the timeout, nothing left."""
    pytest.importorskip("pylibfranka")
    server = _SilentServer(1337)
    try:
        start = time.monotonic()
        code, err = run_cli(["hold", "--host", "127.0.0.1", "--connect-timeout-s", "2",
                             "--out", str(tmp_path / "run")], capsys)
        elapsed = time.monotonic() - start
    finally:
        server.close()
    assert code == 1 and err.count("\n") == 1 and "no answer within 2 s" in err
    assert elapsed < 10.0 and list(tmp_path.iterdir()) == []


def test_a_hand_that_never_answers_is_given_up() -> None:
    pytest.importorskip("pylibfranka")
    from impact_franka.gripper import GripperProcess

    server = _SilentServer(1338)
    hand = GripperProcess("127.0.0.1")
    try:
        with pytest.raises(FrankaError, match="Franka Hand at 127.0.0.1: no answer within 2 s"):
            hand.open(2.0)
    finally:
        server.close()
    assert hand._proc is None  # the child was killed and reaped


def test_sigterm_to_a_lock_holder_frees_the_lock(tmp_path) -> None:
    holder = _holder(lock_name("127.0.0.1"), tmp_path)
    holder.send_signal(signal.SIGTERM)
    holder.wait(timeout=10)
    with client_lock("127.0.0.1"):
        pass


STUCK_PROBE = """
import os, signal, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN)  # as pylibfranka's connect, which holds the GIL
signal.signal(signal.SIGTERM, signal.SIG_IGN)
with open(os.environ["IMPACT_TEST_PID_FILE"], "w") as f:
    f.write(str(os.getpid()))
time.sleep(120)
"""
"""A probe child that never answers and ignores the signals sent to the command."""
DRIVER = """
import contextlib, os, signal, sys, types
from impact_franka import commands, connection
from impact_franka.cli import main
sys.modules.setdefault("pylibfranka", types.ModuleType("pylibfranka"))  # never called
connection.PROBE = sys.argv[1]
connection.LOCK_PREFIX = sys.argv[2]
real_lock = connection.client_lock

@contextlib.contextmanager
def watched(host):
    with real_lock(host):
        try:
            yield
        finally:
            pid = open(os.environ["IMPACT_TEST_PID_FILE"]).read()
            print("probe alive at release:", os.path.exists(f"/proc/{pid}"), flush=True)

commands.client_lock = watched
signal.signal(signal.SIGINT, signal.default_int_handler)  # pytest-xdist's workers ignore it
raise SystemExit(main(sys.argv[3:]))
"""
"""``impact-robot`` with the stuck probe, reporting whether the probe's child still existed
(running or unreaped) when the one-client lock was released."""


@pytest.mark.parametrize(("sig", "code", "group"), [
    (signal.SIGINT, 130, False), (signal.SIGTERM, 143, False), (signal.SIGINT, 130, True),
], ids=["sigint", "sigterm", "ctrl_c_to_the_group"])
def test_an_interrupted_probe_ends_its_child_before_the_lock_is_released(sig, code, group,
                                                                        tmp_path) -> None:
    """Ctrl-C or SIGTERM while the probe waits: the child (which ignores both, as a child
    stuck in pylibfranka does) is killed and reaped, then the lock is released; one line."""
    pid_file = tmp_path / "probe.pid"
    env = {**os.environ, "IMPACT_TEST_PID_FILE": str(pid_file),
           "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[2]),
                                          os.environ.get("PYTHONPATH", "")])}
    command = [sys.executable, "-c", DRIVER, STUCK_PROBE, f"impact-robot-test{os.getpid()}",
               "hold", "--host", "192.0.2.1", "--connect-timeout-s", "120", "--out",
               str(tmp_path / "run")]
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 30.0
        while not (pid_file.exists() and pid_file.read_text()) and time.monotonic() < deadline:
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        child = int(pid_file.read_text())
        (os.killpg if group else os.kill)(proc.pid, sig)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    alive = Path(f"/proc/{child}").exists()
    if alive:
        os.kill(child, signal.SIGKILL)
    assert not alive, "the probe's child outlived the command"
    assert "probe alive at release: False" in out, out
    assert proc.returncode == code, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("impact-robot: ") and "outside the control loop" in err
    assert ("SIGTERM" in err) == (sig == signal.SIGTERM), err
    assert [p.name for p in tmp_path.iterdir()] == ["probe.pid"]  # no --out folder


def test_an_interrupted_probe_call_kills_and_reaps_its_child(tmp_path) -> None:
    """``probe`` itself: a KeyboardInterrupt during its wait leaves no child behind."""
    pid_file = tmp_path / "probe.pid"
    program = STUCK_PROBE.replace('os.environ["IMPACT_TEST_PID_FILE"]', repr(str(pid_file)))

    def interrupt() -> None:
        deadline = time.monotonic() + 30.0
        while not (pid_file.exists() and pid_file.read_text()) and time.monotonic() < deadline:
            time.sleep(0.02)
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # xdist ignores it
    try:
        threading.Thread(target=interrupt, daemon=True).start()
        with pytest.raises(KeyboardInterrupt):
            probe("192.0.2.1", 60.0, program)
    finally:
        signal.signal(signal.SIGINT, previous)
    child = int(pid_file.read_text())
    alive = Path(f"/proc/{child}").exists()
    if alive:
        os.kill(child, signal.SIGKILL)
    assert not alive, "the probe's child outlived the interrupt"
