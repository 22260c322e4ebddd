"""Taught TCP poses: a small JSON file of named poses (``impact-robot teach`` writes it).

    {"pick": {"pos_m": [x, y, z], "quat_wxyz": [w, x, y, z], "q_rad": [7 joints]}, ...}

A pose is the controller's TCP (our model's forward kinematics of the measured ``q``), the
frame the controller tracks, not the robot's ``O_T_EE``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from impact_franka.fci import FrankaError
from impact_franka.pick_place import Pose


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
            return Pose(np.array([float(p) for p in parts]), default_quat.copy())
        except ValueError:
            pass
    if path is None:
        raise FrankaError(f"invalid pose {spec!r}; valid: X,Y,Z in metres, or a name taught "
                          "into --poses FILE")
    poses = _read(path)
    if spec not in poses:
        raise FrankaError(f"invalid pose {spec!r}; valid: X,Y,Z in metres, or one of "
                          f"{', '.join(sorted(poses)) or '(none taught)'} in {path}")
    entry = poses[spec]
    return Pose(np.array(entry["pos_m"], dtype=float), np.array(entry["quat_wxyz"], dtype=float))
