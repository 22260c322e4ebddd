"""Taught TCP poses: a small JSON file of named poses (``impact-robot teach`` writes it).

    {"pick": {"pos_m": [x, y, z], "quat_wxyz": [w, x, y, z], "q_rad": [7 joints]}, ...}

A pose is the controller's TCP (our model's forward kinematics of the measured ``q``), the
frame the controller tracks, not the robot's ``O_T_EE``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from impact_franka.fci import FrankaError
from impact_franka.pick_place import Pose

SHOULDER_M = np.array([0.0, 0.0, 0.333])
"""The FR3's shoulder (joint 2's axis) in the base frame [m]."""
REACH_M = 0.95
"""Farthest TCP position accepted from the shoulder [m]: the FR3's 855 mm reach to the
flange plus the Franka Hand's 103 mm, rounded down."""


def check_reach(pos_m: np.ndarray, what: str) -> None:
    """``FrankaError`` (one line) unless ``pos_m`` is finite and within ``REACH_M`` of the
    shoulder."""
    distance = float(np.linalg.norm(pos_m - SHOULDER_M))
    if not distance <= REACH_M:
        raise FrankaError(f"invalid {what} {np.round(pos_m, 4).tolist()}: {distance:.3f} m from "
                          f"the shoulder; valid: within {REACH_M} m of (0, 0, 0.333) m")


def check_writable(path: Path) -> None:
    """Before anything moves: ``path`` can be written (its directory exists and is writable)
    and, if it exists, holds taught poses (a pose recorded at the end is then not lost)."""
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir() or not os.access(folder, os.W_OK):
        raise FrankaError(f"invalid --poses {path}: its directory is missing or not writable; "
                          "valid: a file in a writable directory")
    if path.exists():
        _read(path)


def save_pose(path: Path, name: str, pose: Pose, q: np.ndarray) -> None:
    """Add (or replace) ``name`` in the file at ``path`` (created if missing)."""
    poses = _read(path) if path.exists() else {}
    poses[name] = {"pos_m": [float(v) for v in pose.pos_m],
                   "quat_wxyz": [float(v) for v in pose.quat_wxyz],
                   "q_rad": [float(v) for v in q]}
    path.write_text(json.dumps(poses, indent=2) + "\n")


def _read(path: Path) -> dict:
    try:
        poses = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise FrankaError(f"cannot read taught poses {path}: {exc}; valid: a file written by "
                          "impact-robot teach") from None
    if not isinstance(poses, dict):
        raise FrankaError(f"invalid taught poses {path}; valid: a file written by impact-robot "
                          "teach")
    return poses


def resolve_pose(spec: str, path: Path | None, default_quat: np.ndarray) -> Pose:
    """``spec`` is a taught pose's name (in the file at ``path``) or ``X,Y,Z`` [m, base
    frame] (then the orientation is ``default_quat``, the TCP's when the command started)."""
    parts = spec.split(",")
    if len(parts) == 3:
        try:
            pos = np.array([float(p) for p in parts])
        except ValueError:
            pos = None
        if pos is not None:
            check_reach(pos, "pose")
            return Pose(pos, default_quat.copy())
    if path is None:
        raise FrankaError(f"invalid pose {spec!r}; valid: X,Y,Z in metres, or a name taught "
                          "into --poses FILE")
    poses = _read(path)
    if spec not in poses:
        raise FrankaError(f"invalid pose {spec!r}; valid: X,Y,Z in metres, or one of "
                          f"{', '.join(sorted(poses)) or '(none taught)'} in {path}")
    return _entry_pose(poses[spec], f"pose {spec!r} in {path}")


def _entry_pose(entry: object, what: str) -> Pose:
    """The ``Pose`` of a file entry, or ``FrankaError`` naming what is wrong with it."""
    try:
        pos = np.array(entry["pos_m"], dtype=float)  # type: ignore[index]
        quat = np.array(entry["quat_wxyz"], dtype=float)  # type: ignore[index]
    except (KeyError, TypeError, ValueError):
        pos, quat = np.zeros(0), np.zeros(0)
    if (pos.shape != (3,) or quat.shape != (4,) or not np.all(np.isfinite(pos))
            or not np.all(np.isfinite(quat)) or not np.linalg.norm(quat) > 0.5):
        raise FrankaError(f"invalid {what}; valid: pos_m (3 finite numbers) and quat_wxyz (a "
                          "unit quaternion), as impact-robot teach writes them")
    return Pose(pos, quat / np.linalg.norm(quat))
