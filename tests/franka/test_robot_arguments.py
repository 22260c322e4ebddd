"""``impact-robot`` refuses every bad argument before it connects: exit 2, one line, nothing
connected, created or changed. No simulator and no pylibfranka needed (192.0.2.1 and
127.0.0.1 are never dialled: the connection is a sentinel, robot_cli.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from robot_cli import assert_refused, no_connect, pose, run_cli, write_poses

HOST = ["--host", "192.0.2.1"]
PICK_PLACE = ["pick-place", *HOST, "--pick", "0.5,-0.1,0.3", "--place", "0.5,0.1,0.3"]


@pytest.mark.parametrize(("argv", "message"), [
    (["check", *HOST, "--seconds", "inf"], "--seconds: invalid value 'inf'"),
    (["check", *HOST, "--seconds", "nan"], "--seconds"),
    (["check", *HOST, "--seconds", "0"], "valid: a finite number > 0"),
    (["hold", *HOST, "--seconds", "-3"], "--seconds"),
    (["hold", *HOST, "--seconds", "1e9"], "<= 600"),
    (["pick-place", *HOST, "--pick", "a", "--place", "b", "--seconds", "abc"], "--seconds"),
    (["check", "--host", ""], "invalid address ''"),
    (["hold", "--host", "   "], "invalid address"),
    (["teach", "--host", "robot one", "--poses", "p.json", "--name", "a"], "invalid address"),
    ([*PICK_PLACE, "--gripper-host", ""], "--gripper-host: invalid address"),
    (["hold", *HOST, "--step-at-s", "1"], "--step-at-s without --step-m"),
    (["hold", *HOST, "--seconds", "2", "--step-m", "0,0,0.01", "--step-at-s", "2"],
     "valid: 0 <= value < --seconds (2)"),
    (["hold", *HOST, "--step-m", "0,0,0.01", "--step-at-s", "inf"], "--step-at-s"),
    (["hold", *HOST, "--step-m", "nan,0,0"], "invalid step"),
    (["hold", *HOST, "--step-m", "0,0,0.5"], "each within 0.1"),
    (["hold", *HOST, "--max-payload-kg", "-1"], "--max-payload-kg"),
    (["check", *HOST, "--max-payload-kg", "inf"], "--max-payload-kg"),
    (["hold", *HOST, "--budget-ms", "0"], "--budget-ms"),
    (["check", *HOST, "--budget-ms", "11"], "--budget-ms"),
    (["teach", *HOST, "--poses", "p.json", "--name", "a", "--budget-ms", "nan"], "--budget-ms"),
    (["check", *HOST, "--connect-timeout-s", "0"], "--connect-timeout-s"),
    (["check", *HOST, "--connect-timeout-s", "nan"], "--connect-timeout-s"),
    (["teach", *HOST, "--poses", "p.json", "--name", ""], "--name: invalid name ''"),
    (["teach", *HOST, "--poses", "p.json", "--name", "0.5,0,0.3"], "not X,Y,Z"),
    (["teach", *HOST, "--poses", "p.json", "--name", "a b"], "--name"),
    (["teach", *HOST, "--poses", "p.json", "--name", "a", "--float-seconds", "inf"],
     "--float-seconds"),
    (["teach", *HOST, "--poses", "", "--name", "a"], "--poses: invalid path"),
    ([*PICK_PLACE, "--grasp-force-n", "141"], "--grasp-force-n"),
    ([*PICK_PLACE, "--grasp-width-m", "-0.01"], "--grasp-width-m"),
    ([*PICK_PLACE, "--speed-m-s", "0"], "--speed-m-s"),
    ([*PICK_PLACE, "--lift-m", "nan"], "--lift-m"),
    (["hold", *HOST, "--controller", "pid"], "invalid choice: 'pid'"),
])
def test_a_bad_value_is_exit_2_in_one_line(argv, message, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    assert_refused(*run_cli(argv, capsys), message)


@pytest.mark.parametrize(("flag", "spec", "message"), [
    ("--pick", "0.05,0,0.2", "inside the robot's base"),
    ("--place", "0,-0.1,0.1", "inside the robot's base"),
    ("--pick", "0.5,0,-0.05", "below the robot's mount"),
    ("--place", "0.4,0.3,-0.2", "below the robot's mount"),
    ("--pick", "1.5,0,0.3", "from the shoulder"),
    ("--place", "0,0,1.4", "from the shoulder"),
    ("--pick", "nan,0,0.3", "3 finite numbers"),
    ("--place", "0.5,inf,0.3", "3 finite numbers"),
    ("--pick", "0.5,0", "valid: X,Y,Z in metres, or a pose name with --poses"),
    ("--place", "a,b,c", "valid: X,Y,Z in metres"),
])
def test_a_pick_or_place_outside_the_workspace_is_refused(flag, spec, message, monkeypatch,
                                                          capsys) -> None:
    no_connect(monkeypatch)
    argv = [*PICK_PLACE[:3], "--pick", "0.5,-0.1,0.3", "--place", "0.5,0.1,0.3", flag, spec]
    assert_refused(*run_cli(argv, capsys), message)


def test_the_lift_above_a_pose_must_be_in_reach_too(monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    argv = [*PICK_PLACE[:3], "--pick", "0.5,0,1.05", "--place", "0.5,0.1,0.3", "--lift-m",
            "0.3"]
    assert_refused(*run_cli(argv, capsys), "--pick raised by --lift-m 0.3")


def test_a_good_command_gets_past_the_checks(monkeypatch, capsys) -> None:
    """The control: valid arguments reach the connection (the sentinel, exit 1)."""
    no_connect(monkeypatch)
    code, err = run_cli([*PICK_PLACE, "--lift-m", "0.1"], capsys)
    assert code == 1 and "CONNECT CALLED" in err


@pytest.mark.parametrize("command", ["hold", "pick-place"])
def test_out_holding_an_earlier_run_is_refused_and_kept(command, tmp_path, monkeypatch,
                                                        capsys) -> None:
    no_connect(monkeypatch)
    out = tmp_path / "run"
    out.mkdir()
    (out / "run.json").write_text("{}")
    argv = (PICK_PLACE if command == "pick-place" else ["hold", *HOST]) + ["--out", str(out)]
    assert_refused(*run_cli(argv, capsys), "already holds files")
    assert [p.name for p in out.iterdir()] == ["run.json"]
    assert (out / "run.json").read_text() == "{}"


def test_out_that_is_a_file_or_under_a_file_is_refused(tmp_path, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    blocker = tmp_path / "file"
    blocker.write_text("keep me")
    for out in (blocker, blocker / "run", blocker / "a" / "b"):
        assert_refused(*run_cli(["hold", *HOST, "--out", str(out)], capsys), "invalid --out")
    assert blocker.read_text() == "keep me"


@pytest.mark.parametrize("nested", ["run", "a/b/run"])
def test_a_failed_connection_leaves_no_out_folder(nested, tmp_path, monkeypatch,
                                                  capsys) -> None:
    """The folder is created after the run: a connection that fails leaves nothing."""
    no_connect(monkeypatch)
    code, err = run_cli(["hold", *HOST, "--out", str(tmp_path / nested)], capsys)
    assert code == 1 and "CONNECT CALLED" in err
    assert list(tmp_path.iterdir()) == []


def test_an_empty_out_folder_is_accepted_and_left_as_it_was(tmp_path, monkeypatch,
                                                            capsys) -> None:
    no_connect(monkeypatch)
    out = tmp_path / "empty"
    out.mkdir()
    code, _ = run_cli(["hold", *HOST, "--out", str(out)], capsys)
    assert code == 1 and out.is_dir() and list(out.iterdir()) == []


def test_teach_refuses_a_read_only_poses_file_and_keeps_it(tmp_path, monkeypatch,
                                                           capsys) -> None:
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    text = write_poses(poses, {"home": pose()})
    poses.chmod(0o444)
    argv = ["teach", *HOST, "--poses", str(poses), "--name", "pick"]
    assert_refused(*run_cli(argv, capsys), "not a writable file")
    assert poses.read_text() == text


@pytest.mark.parametrize("where", ["missing_dir", "a_dir", "under_a_file"])
def test_teach_refuses_a_poses_path_it_cannot_write(where, tmp_path, monkeypatch,
                                                    capsys) -> None:
    no_connect(monkeypatch)
    (tmp_path / "file").write_text("x")
    path = {"missing_dir": tmp_path / "no" / "p.json", "a_dir": tmp_path,
            "under_a_file": tmp_path / "file" / "p.json"}[where]
    argv = ["teach", *HOST, "--poses", str(path), "--name", "pick"]
    assert_refused(*run_cli(argv, capsys), "invalid --poses")


def test_teach_refuses_a_taught_name_unless_replace(tmp_path, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    text = write_poses(poses, {"pick": pose()})
    argv = ["teach", *HOST, "--poses", str(poses), "--name", "pick"]
    assert_refused(*run_cli(argv, capsys), "already taught in")
    code, err = run_cli([*argv, "--replace"], capsys)
    assert code == 1 and "CONNECT CALLED" in err and poses.read_text() == text


def test_teach_refuses_to_extend_a_damaged_file(tmp_path, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    poses.write_text('{"pick": {"pos_m": [0.5, 0.0, 0.3], "quat_wxyz": [0, 1, 0')
    argv = ["teach", *HOST, "--poses", str(poses), "--name", "place"]
    assert_refused(*run_cli(argv, capsys), "cannot read taught poses")
    assert poses.read_text().endswith("[0, 1, 0")


def test_help_describes_each_command_and_names_the_choices(capsys) -> None:
    from impact_franka.cli import COMMANDS

    code, _ = run_cli(["--help"], capsys)
    for name in COMMANDS:
        with pytest.raises(SystemExit) as exc:
            from impact_franka.cli import main

            main([name, "--help"])
        out = capsys.readouterr().out
        assert exc.value.code == 0 and COMMANDS[name][1].split(",")[0] in " ".join(out.split())
        for flag in ("--host", "--seconds", "--connect-timeout-s"):
            assert flag in out
        if name in ("hold", "pick-place"):
            text = " ".join(out.split())
            assert "impact: impedance + learned feedforward" in text
            assert "controller configuration: default (what we ship)" in text
            assert "paper (the paper's table read literally)" in text
    assert code == 0


@pytest.mark.parametrize("address", [
    "127.0.0.1:1337", "172.16.0.2:80", "[::1]:1337", "robot.lab:1337", "localhost:0",
])
def test_an_address_with_a_port_is_refused(address, monkeypatch, capsys) -> None:
    """The FCI's ports are fixed: ``HOST:PORT`` was accepted and failed at connect (exit 1)."""
    no_connect(monkeypatch)
    for argv in (["check", "--host", address], [*PICK_PLACE, "--gripper-host", address]):
        assert_refused(*run_cli(argv, capsys), f"invalid address {address!r} (a port is not "
                       "part of it); valid: a host name, an IPv4 or an IPv6 address")


@pytest.mark.parametrize("address", [
    "[::1]", "256.1.1.1", "172.16.0", "1.2.3.4.5", "http://172.16.0.2", "robot_1", "a..b",
    "-robot", "robot-", "172.16.0.2/24", "fe80::1::2", "x" * 64 + ".lab",
])
def test_what_is_no_host_name_or_address_is_refused(address, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    code, err = run_cli(["hold", f"--host={address}"], capsys)
    assert_refused(code, err, "valid: a host name, an IPv4 or an IPv6 address")
    assert "a port is not part of it" not in err


@pytest.mark.parametrize("address", [
    "172.16.0.2", "127.0.0.1", "::1", "fe80::1%eth0", "2001:db8::7", "localhost", "fr3",
    "fr3-arm.lab.example", "fr3.lab.", "robot1",
])
def test_host_names_and_ip_addresses_get_past_the_checks(address, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    code, err = run_cli(["check", "--host", address], capsys)
    assert code == 1 and "CONNECT CALLED" in err


def _empty_proc_folder() -> str | None:
    """An existing empty folder under /proc (where no file can be created), if any."""
    for folder in sorted(Path("/proc/fs").glob("*")) + sorted(Path("/proc/irq").glob("*/*")):
        try:
            if folder.is_dir() and not any(folder.iterdir()):
                return str(folder)
        except OSError:
            continue
    return None


@pytest.mark.parametrize("out", ["/proc/impact-run", "/proc/a/b/run", "/proc/self/run",
                                 "/proc/self/status/run", "/sys/impact-run",
                                 "empty_proc_folder"])
def test_out_where_nothing_can_be_created_is_refused_before_connecting(out, monkeypatch,
                                                                         capsys) -> None:
    """Permission bits let root write anywhere, /proc too: the folder and a file in it are
    tried, so the refusal comes before the robot is held, not after the run."""
    if not Path("/proc/self").is_dir():
        pytest.skip("no /proc")
    if out == "empty_proc_folder":
        out = _empty_proc_folder() or pytest.skip("no empty folder under /proc")
    no_connect(monkeypatch)
    for command in (["hold", *HOST], PICK_PLACE):
        assert_refused(*run_cli([*command, "--out", out], capsys), f"invalid --out {out}: "
                       "cannot create")



@pytest.mark.parametrize("poses", ["/proc/poses.json", "/proc/self/poses.json",
                                   "/sys/poses.json"])
def test_teach_refuses_poses_where_no_file_can_be_created(poses, monkeypatch, capsys) -> None:
    """The same for ``teach --poses``: refused before connecting, not after the float."""
    if not Path("/proc/self").is_dir():
        pytest.skip("no /proc")
    no_connect(monkeypatch)
    argv = ["teach", *HOST, "--poses", poses, "--name", "pick"]
    assert_refused(*run_cli(argv, capsys), f"invalid --poses {poses}: ")


def test_teach_poses_in_a_writable_folder_leaves_nothing_there(tmp_path, monkeypatch,
                                                               capsys) -> None:
    no_connect(monkeypatch)
    code, err = run_cli(["teach", *HOST, "--poses", str(tmp_path / "p.json"), "--name", "a"],
                        capsys)
    assert code == 1 and "CONNECT CALLED" in err and list(tmp_path.iterdir()) == []
