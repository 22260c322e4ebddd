"""Taught pose files (impact_franka/poses.py): read whole and checked whole, any damaged
entry refused by name before connecting (exit 2); written atomically; the workspace defined
once (``check_workspace``) for typed and taught poses alike."""

from __future__ import annotations

import json

import numpy as np
import pytest
from robot_cli import DOWN, assert_refused, no_connect, pose, run_cli, write_poses

from impact_control.errors import InvalidArgumentError
from impact_franka.fci import FrankaError
from impact_franka.pick_place import Pose
from impact_franka.poses import check_workspace, read_poses, resolve_pose, save_pose

DAMAGED = {
    "bool_coordinate": {"pos_m": [True, 0.0, 0.3], "quat_wxyz": DOWN},
    "string_coordinate": {"pos_m": ["0.5", 0.0, 0.3], "quat_wxyz": DOWN},
    "null_coordinate": {"pos_m": [0.5, None, 0.3], "quat_wxyz": DOWN},
    "two_coordinates": {"pos_m": [0.5, 0.3], "quat_wxyz": DOWN},
    "out_of_reach": {"pos_m": [1.2, 0.0, 0.3], "quat_wxyz": DOWN},
    "below_mount": {"pos_m": [0.5, 0.0, -0.02], "quat_wxyz": DOWN},
    "inside_base": {"pos_m": [0.05, 0.05, 0.2], "quat_wxyz": DOWN},
    "no_quat": {"pos_m": [0.5, 0.0, 0.3]},
    "long_quat": {"pos_m": [0.5, 0.0, 0.3], "quat_wxyz": [0, 1, 0, 0, 0]},
    "scaled_quat": {"pos_m": [0.5, 0.0, 0.3], "quat_wxyz": [0, 3, 0, 0]},
    "bool_quat": {"pos_m": [0.5, 0.0, 0.3], "quat_wxyz": [False, True, False, False]},
    "short_q": {"pos_m": [0.5, 0.0, 0.3], "quat_wxyz": DOWN, "q_rad": [0.0] * 6},
    "extra_key": {**pose(), "note": "x"},
    "not_an_object": [0.5, 0.0, 0.3],
}


@pytest.mark.parametrize("damage", sorted(DAMAGED))
@pytest.mark.parametrize("flag", ["--pick", "--place"])
def test_a_damaged_entry_is_refused_by_name(damage, flag, tmp_path, monkeypatch,
                                            capsys) -> None:
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    text = write_poses(poses, {"good": pose(), "bad": DAMAGED[damage]})
    other = "--place" if flag == "--pick" else "--pick"
    argv = ["pick-place", "--host", "192.0.2.1", "--poses", str(poses), flag, "bad", other,
            "good"]
    assert_refused(*run_cli(argv, capsys), "pose 'bad' in")
    assert poses.read_text() == text


def test_a_damaged_entry_not_used_still_refuses_the_file(tmp_path, monkeypatch,
                                                         capsys) -> None:
    """No silent acceptance: the file is checked whole, even with X,Y,Z poses."""
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    write_poses(poses, {"good": pose(), "spare": DAMAGED["bool_coordinate"]})
    argv = ["pick-place", "--host", "192.0.2.1", "--poses", str(poses), "--pick", "0.5,0,0.3",
            "--place", "good"]
    assert_refused(*run_cli(argv, capsys), "pose 'spare' in")


@pytest.mark.parametrize(("content", "message"), [
    ('{"a": ' + json.dumps(pose()) + ', "a": ' + json.dumps(pose()) + "}", "repeated names"),
    ("[1, 2, 3]", "not an object of named poses"),
    ('{"a": {"pos_m": [NaN, 0, 0.3], "quat_wxyz": [0, 1, 0, 0]}}', "pos_m"),
    ('{"a": {"pos_m": [1' + "0" * 400 + ', 0, 0.3], "quat_wxyz": [0, 1, 0, 0]}}', "pos_m"),
    ('{"a": {"pos_m": [1e999, 0, 0.3], "quat_wxyz": [0, 1, 0, 0]}}', "pos_m"),
    ('{"a b": ' + json.dumps(pose()) + "}", "invalid pose name in"),
    ("", "cannot read taught poses"),
    ("[" * 100000 + "]" * 100000, "cannot read taught poses"),
    (b"\xff\xfe{}", "cannot read taught poses"),
])
def test_a_damaged_file_is_refused(content, message, tmp_path, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    if isinstance(content, bytes):
        poses.write_bytes(content)
    else:
        poses.write_text(content)
    argv = ["pick-place", "--host", "192.0.2.1", "--poses", str(poses), "--pick", "a",
            "--place", "0.5,0.1,0.3"]
    assert_refused(*run_cli(argv, capsys), message)


@pytest.mark.parametrize("where", ["missing", "a_directory"])
def test_pick_place_refuses_a_poses_file_it_cannot_read(where, tmp_path, monkeypatch,
                                                        capsys) -> None:
    no_connect(monkeypatch)
    path = tmp_path / "missing.json" if where == "missing" else tmp_path
    argv = ["pick-place", "--host", "192.0.2.1", "--poses", str(path), "--pick", "a",
            "--place", "0.5,0.1,0.3"]
    assert_refused(*run_cli(argv, capsys), "not a file")


def test_an_unknown_name_lists_the_taught_ones(tmp_path, monkeypatch, capsys) -> None:
    no_connect(monkeypatch)
    poses = tmp_path / "poses.json"
    write_poses(poses, {"pick": pose(), "place": pose(y=0.1)})
    argv = ["pick-place", "--host", "192.0.2.1", "--poses", str(poses), "--pick", "pik",
            "--place", "place"]
    assert_refused(*run_cli(argv, capsys), "valid: X,Y,Z in metres, or one of pick, place in")


def test_the_workspace_is_one_definition() -> None:
    assert check_workspace([0.5, 0.0, 0.3], "p").tolist() == [0.5, 0.0, 0.3]
    assert check_workspace([0.0, 0.0, 1.2], "p")[2] == 1.2  # straight up over the base
    assert check_workspace([-0.4, 0.0, 0.3], "p")[0] == -0.4  # behind the robot
    for bad, why in [([0.1, 0.0, 0.39], "inside the robot's base"),
                     ([0.3, 0.0, -1e-3], "below the robot's mount"),
                     ([0.0, 0.96, 0.333], "from the shoulder"), ([0.5, 0.0], "3 finite"),
                     ("abc", "3 finite"), ([0.5, -np.inf, 0.3], "3 finite")]:
        with pytest.raises(InvalidArgumentError, match=why):
            check_workspace(bad, "p")
    with pytest.raises(InvalidArgumentError, match="inside the robot's base"):
        resolve_pose("0.1,0.1,0.1", None, None, "--pick")


def test_save_pose_is_atomic_and_refuses_a_pose_outside_the_workspace(tmp_path) -> None:
    path = tmp_path / "poses.json"
    save_pose(path, "pick", Pose(np.array([0.5, 0.0, 0.3]), np.array(DOWN)), np.zeros(7))
    save_pose(path, "place", Pose(np.array([0.5, 0.1, 0.3]), np.array(DOWN)), np.zeros(7))
    before = path.read_text()
    assert sorted(read_poses(path)) == ["pick", "place"]
    with pytest.raises(FrankaError, match="below the robot's mount; .*not saved to"):
        save_pose(path, "low", Pose(np.array([0.5, 0.0, -0.1]), np.array(DOWN)), np.zeros(7))
    assert path.read_text() == before and [p.name for p in tmp_path.iterdir()] == [path.name]
    back = resolve_pose("place", path, None)
    np.testing.assert_allclose(back.pos_m, [0.5, 0.1, 0.3])
    np.testing.assert_allclose(back.quat_wxyz, DOWN)
