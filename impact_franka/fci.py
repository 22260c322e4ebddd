"""FCI conventions (libfranka 0.21 / pylibfranka), as named structures and pure functions.

- The robot adds its own gravity compensation to a torque command: send ``tau - g(q)``.
- ``tau_J`` is the link-side measured joint torque, gravity included: the controller's
  ``tau_measured``.
- ``O_T_EE`` is a column-major 4x4: the flange composed with ``F_T_EE`` (the end effector set
  in Desk, or by the simulator) and ``EE_T_K``; it is compared with our TCP, never used for
  control (the controller computes its own kinematics from ``q``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from impact_control.config import ControllerConfig, libfranka_limits
from impact_control.errors import ImpactError, check_choice
from impact_control.limits import LimitsConfig

TORQUE_SOURCES: tuple[str, ...] = ("tau_J", "tau_J+g")
"""What the controller reads as the measured joint torque: ``tau_J`` (an FR3: link-side,
gravity included) or ``tau_J+g`` (a simulator whose ``tau_J`` echoes the command, i.e. leaves
gravity out, as franka-sim 1.1.7 does: our g(q) of the previous tick, 1 ms old, is added)."""


def check_torque_source(source: str) -> bool:
    """Validate ``source`` (one of ``TORQUE_SOURCES``); True if g(q) must be added."""
    check_choice("torque source", source, TORQUE_SOURCES)
    return source == "tau_J+g"


class FrankaError(ImpactError):
    """The robot or its client library refused, stopped or could not be reached."""


class FciReading(NamedTuple):
    """One robot state as the controller reads it: ``q`` [rad], ``dq`` [rad/s],
    ``tau_measured`` (= ``tau_J``) [Nm], and ``O_T_EE`` as ``pos_ee`` [m] / ``rot_ee``."""

    q: np.ndarray
    dq: np.ndarray
    tau_measured: np.ndarray
    pos_ee: np.ndarray
    rot_ee: np.ndarray


def pose_from_column_major(matrix16: object) -> tuple[np.ndarray, np.ndarray]:
    """(position [m], rotation matrix) of a column-major 4x4 (libfranka's layout)."""
    m = np.asarray(matrix16, dtype=float).reshape(4, 4).T
    return m[:3, 3].copy(), m[:3, :3].copy()


def reading(state: object) -> FciReading:
    """An ``FciReading`` of a pylibfranka ``RobotState`` (any object with those fields)."""
    pos, rot = pose_from_column_major(state.O_T_EE)  # type: ignore[attr-defined]
    return FciReading(np.array(state.q, dtype=float), np.array(state.dq, dtype=float),  # type: ignore[attr-defined]
                      np.array(state.tau_J, dtype=float), pos, rot)  # type: ignore[attr-defined]


def torque_command(tau_total: np.ndarray, tau_gravity: np.ndarray) -> np.ndarray:
    """The torque to send: ``tau_total - tau_gravity`` (the robot adds gravity itself).

    Raises:
        FrankaError: A non-finite command (libfranka would throw on it).
    """
    cmd = np.asarray(tau_total, dtype=float) - np.asarray(tau_gravity, dtype=float)
    if cmd.shape != (7,) or not np.all(np.isfinite(cmd)):
        raise FrankaError(f"refusing to send a torque command {cmd!r}; valid: 7 finite values")
    return cmd


def _stricter_than_libfranka(limits: LimitsConfig) -> bool:
    """Whether ``limits`` (a ``LimitsConfig``) bound the command without gravity at least as
    tightly as libfranka: rate at most its 999.999 Nm/s, torques at most the FR3's."""
    fr3 = libfranka_limits()
    return (not limits.rate_limit_includes_gravity
            and limits.torque_rate_max_nm_per_s <= fr3.torque_rate_max_nm_per_s
            and all(a <= b for a, b in zip(limits.torque_max_nm, fr3.torque_max_nm,
                                           strict=True)))


def fr3_config(base: ControllerConfig | None = None) -> ControllerConfig:
    """``base`` (default ``ControllerConfig()``) as it must run on an FR3: libfranka's exact
    limits, the in-kernel learner (a bounded tick) and the contact guard.

    A base whose own limits are stricter than libfranka's keeps them (``authors_real``: their
    0.5 Nm per tick on the command without gravity): the runner rate-limits every command it
    sends with libfranka's ``limitRate`` in any case, so the robot's own check always holds."""
    cfg = base or ControllerConfig()
    return replace(cfg, limits=cfg.limits if _stricter_than_libfranka(cfg.limits)
                   else libfranka_limits(),
                   internal_model=replace(cfg.internal_model, learner="numba"),
                   guard=replace(cfg.guard, enabled=True))
