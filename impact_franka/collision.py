"""The FR3's collision reflex thresholds (``set_collision_behavior``) for a load not declared.

The robot compares its own external-torque and external-force estimates with these thresholds
and stops (reflex ``cartesian_reflex`` / ``joint_reflex``) above the upper ones. Its estimate
is what its model does not explain, so **a payload not declared with ``set_load`` reads as an
external load**: 5 kg at the TCP is 49 N on the force axes and ``J^T (0, 0, -m g)`` on the
joints. IMPACT is what one uses precisely when the load is not declared, so thresholds copied
from libfranka's examples (20 N, 12–20 Nm: ``EXAMPLE_FORCE``, ``EXAMPLE_TORQUE_NM``) trip the
reflex as soon as a load above about 2 kg is handed over.

``collision_thresholds(max_payload_kg, jacobian)`` keeps the examples' thresholds as the
margin for real contacts and adds ``PAYLOAD_MARGIN`` (1.5) times what the largest undeclared
payload reads at the current pose: its weight on the three force axes (the robot's force
frame is not the world's, so every axis), its moment about a ``PAYLOAD_LEVER_M`` (0.1 m)
offset from the TCP on the three moment axes, and ``|J^T (0, 0, -m g, 0, 0, 0)|`` on the
joints (a hold does not change the pose). Lower and upper thresholds are set equal, as the
examples do. docs/franka.md, "Collision thresholds".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from impact_control.errors import InvalidArgumentError

EXAMPLE_TORQUE_NM: tuple[float, ...] = (20.0, 20.0, 18.0, 18.0, 16.0, 14.0, 12.0)
"""Joint thresholds [Nm] of libfranka's examples (``setDefaultBehavior``)."""
EXAMPLE_FORCE: tuple[float, ...] = (20.0, 20.0, 20.0, 25.0, 25.0, 25.0)
"""Cartesian thresholds of libfranka's examples: x, y, z [N], then R, P, Y [Nm]."""
PAYLOAD_MARGIN = 1.5
"""Factor on what the largest undeclared payload reads (its swing and the learning transient
add to its weight)."""
PAYLOAD_LEVER_M = 0.1
"""Offset [m] of an undeclared payload's centre of mass from the TCP, for the moment axes."""
GRAVITY_M_PER_S2 = 9.81


class CollisionThresholds(NamedTuple):
    """Thresholds for ``Robot.set_collision_behavior`` (lower = upper).

    Attributes:
        torque_nm: Joint external-torque thresholds (7,) [Nm].
        force: Cartesian external-wrench thresholds (6,): x, y, z [N], R, P, Y [Nm].
        max_payload_kg: The undeclared payload they leave room for [kg].
    """

    torque_nm: tuple[float, ...]
    force: tuple[float, ...]
    max_payload_kg: float

    def apply(self, robot: object) -> None:
        """Set them on a ``pylibfranka.Robot``."""
        torque, force = list(self.torque_nm), list(self.force)
        robot.set_collision_behavior(torque, torque, force, force)  # type: ignore[attr-defined]


def collision_thresholds(max_payload_kg: float, jacobian: np.ndarray,
                         margin: float = PAYLOAD_MARGIN) -> CollisionThresholds:
    """The examples' thresholds plus ``margin`` times what an undeclared ``max_payload_kg`` at
    the TCP reads, at the pose of ``jacobian`` ((6, 7), world-aligned TCP Jacobian)."""
    if not (math.isfinite(max_payload_kg) and max_payload_kg >= 0.0):
        raise InvalidArgumentError(
            f"invalid max payload {max_payload_kg!r} kg; valid: a finite number >= 0")
    jac = np.asarray(jacobian, dtype=float)
    if jac.shape != (6, 7) or not np.all(np.isfinite(jac)):
        raise InvalidArgumentError("invalid jacobian; valid: a finite (6, 7) array")
    weight = max_payload_kg * GRAVITY_M_PER_S2
    joints = np.abs(jac.T @ np.array([0.0, 0.0, -weight, 0.0, 0.0, 0.0]))
    torque = np.asarray(EXAMPLE_TORQUE_NM) + margin * joints
    extra = margin * np.array([weight] * 3 + [weight * PAYLOAD_LEVER_M] * 3)
    force = np.asarray(EXAMPLE_FORCE) + extra
    return CollisionThresholds(tuple(round(float(v), 3) for v in torque),
                               tuple(round(float(v), 3) for v in force), float(max_payload_kg))
