"""Taught TCP poses: a small JSON file of named poses (``impact-robot teach`` writes it), and
the one definition of where a TCP target may lie (``check_workspace``).

    {"pick": {"pos_m": [x, y, z], "quat_wxyz": [w, x, y, z], "q_rad": [7 joints]}, ...}

A pose is the controller's TCP (our model's forward kinematics of the measured ``q``), the
frame the controller tracks, not the robot's ``O_T_EE``. A file is read whole and checked
whole: one damaged entry (a missing key, a boolean, string or non-finite number, a quaternion
that is not unit, a position outside the workspace, a repeated name) refuses the file, naming
the entry; nothing is accepted silently. Writes replace the file atomically.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
from pathlib import Path

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_franka.fci import FrankaError
from impact_franka.pick_place import Pose
from impact_franka.writable import try_writing

SHOULDER_M = np.array([0.0, 0.0, 0.333])
"""The FR3's shoulder (joint 2's axis) in the base frame [m]."""
REACH_M = 0.95
"""Farthest TCP position accepted from the shoulder [m]: the FR3's 855 mm reach to the
flange plus the Franka Hand's 103 mm, rounded down."""
MOUNT_Z_M = 0.0
"""Lowest TCP height [m, base frame]: the plane the robot's base is mounted on."""
BASE_RADIUS_M, BASE_TOP_M = 0.15, 0.40
"""The base column the TCP keeps out of: within ``BASE_RADIUS_M`` of the base's z axis below
``BASE_TOP_M`` [m]. Link 1's collision capsule (radius 0.06 m) reaches from the mount up to
0.343 m and link 0's to 0.15 m behind the axis; plus the hand's 0.04 m capsule and 0.05 m."""
WORKSPACE = (f"valid: within {REACH_M} m of the shoulder (0, 0, 0.333) m, at z >= "
             f"{MOUNT_Z_M:g} m (the mount) and outside the base ({BASE_RADIUS_M} m around its "
             f"axis below z = {BASE_TOP_M} m)")
NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.-]{0,63}")
"""A pose name: a letter or _ first (so it never reads as X,Y,Z), then letters, digits, _.-"""
ENTRY_SIZES = {"pos_m": 3, "quat_wxyz": 4, "q_rad": 7}
"""Keys of a file entry and their lengths (``q_rad`` optional)."""


def check_workspace(pos_m: object, what: str) -> np.ndarray:
    """``pos_m`` as a (3,) array, or ``InvalidArgumentError`` (one line) unless it is three
    finite numbers within the FR3's reach, above its mount and outside its base column."""
    try:
        pos = np.asarray(pos_m, dtype=float)
    except (TypeError, ValueError):
        pos = np.zeros(0)
    if pos.shape != (3,) or not np.all(np.isfinite(pos)):
        shown = pos.tolist() if pos.shape == (3,) else pos_m
        raise InvalidArgumentError(f"invalid {what} {shown!r}; valid: 3 finite numbers [m]")
    shown = np.round(pos, 4).tolist()
    distance = float(np.linalg.norm(pos - SHOULDER_M))
    if distance > REACH_M:
        why = f"{distance:.3f} m from the shoulder"
    elif pos[2] < MOUNT_Z_M:
        why = "below the robot's mount"
    elif math.hypot(pos[0], pos[1]) < BASE_RADIUS_M and pos[2] < BASE_TOP_M:
        why = "inside the robot's base"
    else:
        return pos
    raise InvalidArgumentError(f"invalid {what} {shown}: {why}; {WORKSPACE}")


def check_name(name: str, flag: str = "--name") -> str:
    """``name`` if it is a valid pose name, else ``InvalidArgumentError``."""
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise InvalidArgumentError(f"invalid {flag} {name!r}; valid: a letter or _ then up to 63 "
                                   "letters, digits, _ . - (a pose name, not X,Y,Z)")
    return name


def _mode_read_only(path: Path) -> bool:
    """No write bit for anyone (os.access says yes to root for any file)."""
    return not path.stat().st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH)


def check_writable(path: Path, name: str | None = None, replace: bool = True) -> None:
    """Before anything moves: a pose can be saved at ``path`` (its directory exists and is
    writable; an existing file is a writable file of valid taught poses), and ``name`` is new
    there unless ``replace``. ``InvalidArgumentError`` (one line) otherwise."""
    folder = path.parent if str(path.parent) else Path(".")
    valid = "valid: a file in a writable directory"
    if not folder.is_dir() or not os.access(folder, os.W_OK | os.X_OK):
        raise InvalidArgumentError(f"invalid --poses {path}: its directory is missing or not "
                                   f"writable; {valid}")
    try:  # save_pose writes a file beside it: tried, since root passes os.access (/proc too)
        try_writing(folder)
    except OSError as exc:
        raise InvalidArgumentError(f"invalid --poses {path}: cannot create a file in {folder} "
                                   f"({exc.strerror or exc}); {valid}") from None
    if not path.exists():
        return
    if not path.is_file() or not os.access(path, os.W_OK) or _mode_read_only(path):
        raise InvalidArgumentError(f"invalid --poses {path}: not a writable file; valid: a new "
                                   "file, or a writable one written by impact-robot teach")
    poses = read_poses(path)
    if name is not None and name in poses and not replace:
        raise InvalidArgumentError(f"invalid --name {name!r}: already taught in {path}; valid: "
                                   "a new name, or --replace to overwrite it")


def _no_repeats(pairs: list[tuple[str, object]]) -> dict:
    keys = [k for k, _ in pairs]
    repeated = sorted({k for k in keys if keys.count(k) > 1})
    if repeated:
        raise ValueError(f"repeated names {repeated}")
    return dict(pairs)


def read_poses(path: Path) -> dict[str, dict]:
    """Every entry of the file at ``path``, each checked (``entry_pose``); one damaged entry
    or an unreadable file is ``InvalidArgumentError`` naming it."""
    valid = "valid: a JSON file written by impact-robot teach"
    if not path.is_file():
        raise InvalidArgumentError(f"invalid --poses {path}: not a file; {valid}")
    try:
        poses = json.loads(path.read_text(), object_pairs_hook=_no_repeats)
    except (OSError, ValueError, RecursionError) as exc:  # RecursionError: nested too deep
        why = " ".join(str(exc.strerror if isinstance(exc, OSError) else exc).split())
        raise InvalidArgumentError(f"cannot read taught poses {path}: {why}; {valid}") from None
    if not isinstance(poses, dict):
        raise InvalidArgumentError(f"invalid taught poses {path}: not an object of named "
                                   f"poses; {valid}")
    for name, entry in poses.items():
        check_name(name, f"pose name in {path}:")
        entry_pose(entry, f"pose {name!r} in {path}")
    return poses


def _numbers(value: object, size: int) -> np.ndarray | None:
    """``value`` as a float array if it is a list of ``size`` finite real numbers (no
    booleans, no strings), else None."""
    if not isinstance(value, list) or len(value) != size:
        return None
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return None
    try:
        array = np.array(value, dtype=float)
    except OverflowError:  # an integer beyond float's range
        return None
    return array if np.all(np.isfinite(array)) else None


def entry_pose(entry: object, what: str) -> Pose:
    """The ``Pose`` of a file entry, or ``InvalidArgumentError`` naming what is wrong."""
    valid = ("valid: pos_m (3 finite numbers), quat_wxyz (a unit quaternion) and optionally "
             "q_rad (7 finite numbers), as impact-robot teach writes them")
    if not isinstance(entry, dict) or not {"pos_m", "quat_wxyz"} <= set(entry) <= set(
            ENTRY_SIZES):
        raise InvalidArgumentError(f"invalid {what}: wrong keys; {valid}")
    values = {k: _numbers(v, ENTRY_SIZES[k]) for k, v in entry.items()}
    bad = [k for k, v in values.items() if v is None]
    if bad:
        raise InvalidArgumentError(f"invalid {what}: {bad[0]} {entry[bad[0]]!r}; {valid}")
    quat = values["quat_wxyz"]
    if abs(float(np.linalg.norm(quat)) - 1.0) > 1e-2:  # type: ignore[arg-type]
        raise InvalidArgumentError(f"invalid {what}: quat_wxyz is not a unit quaternion; {valid}")
    pos = check_workspace(values["pos_m"], what)
    return Pose(pos, quat / np.linalg.norm(quat))  # type: ignore[operator]


def save_pose(path: Path, name: str, pose: Pose, q: np.ndarray) -> None:
    """Add (or replace) ``name`` in the file at ``path`` (created if missing), atomically: the
    file is whole before and after. ``FrankaError`` if the pose is outside the workspace or the
    file cannot be written (then it is unchanged)."""
    poses = read_poses(path) if path.exists() else {}
    entry = {"pos_m": [float(v) for v in pose.pos_m],
             "quat_wxyz": [float(v) for v in pose.quat_wxyz], "q_rad": [float(v) for v in q]}
    try:
        entry_pose(entry, f"taught pose {name!r}")
    except InvalidArgumentError as exc:
        raise FrankaError(f"{exc}; not saved to {path}") from None
    poses[name] = entry
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        temporary.write_text(json.dumps(poses, indent=2) + "\n")
        os.replace(temporary, path)
    except OSError as exc:
        temporary.unlink(missing_ok=True)
        raise FrankaError(f"cannot save the taught pose to {path}: {exc.strerror}") from None


def resolve_pose(spec: str, path: Path | None, default_quat: np.ndarray | None,
                 flag: str = "pose") -> Pose:
    """``spec`` is a taught pose's name (in the file at ``path``) or ``X,Y,Z`` [m, base
    frame] (then the orientation is ``default_quat``, the TCP's when the command started;
    None when it is not known yet). Either is checked against the workspace."""
    parts = spec.split(",")
    if len(parts) == 3:
        try:
            pos = np.array([float(p) for p in parts])
        except ValueError:
            raise InvalidArgumentError(f"invalid {flag} {spec!r}; valid: X,Y,Z in metres, or a "
                                       "pose name") from None
        pos = check_workspace(pos, flag)
        return Pose(pos, None if default_quat is None else default_quat.copy())  # type: ignore[arg-type]
    if path is None:
        raise InvalidArgumentError(f"invalid {flag} {spec!r}; valid: X,Y,Z in metres, or a pose "
                                   "name with --poses FILE")
    check_name(spec, flag)
    poses = read_poses(path)
    if spec not in poses:
        raise InvalidArgumentError(f"invalid {flag} {spec!r}; valid: X,Y,Z in metres, or one of "
                                   f"{', '.join(sorted(poses)) or '(none taught)'} in {path}")
    return entry_pose(poses[spec], f"pose {spec!r} in {path}")
