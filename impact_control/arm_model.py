"""Structural interface of the rigid-body model the controller needs (no MuJoCo here)."""

from __future__ import annotations

from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class ArmDynamics(Protocol):
    """Controller-side model of a 7-DoF arm, e.g. ``impact_control.dynamics.PinocchioArm``.

    ``update(q, dq)`` is called once per tick; the attributes then hold the values at (q, dq).

    Attributes:
        pos_ee_world: TCP position (3,) [m], world frame.
        rot_ee_world: TCP orientation (3, 3), columns = TCP axes in world.
        jacobian: (6, 7) world-aligned TCP Jacobian, rows (linear [m/rad]; angular [-]).
        mass_matrix: (7, 7) joint-space inertia incl. rotor armature [kg m^2].
        gravity: (7,) generalized gravity g(q) [Nm] (torque that holds the arm still).
        coriolis_matrix: (7, 7) C(q, dq) with M_dot = C + C^T [Nm s/rad].
    """

    pos_ee_world: np.ndarray
    rot_ee_world: np.ndarray
    jacobian: np.ndarray
    mass_matrix: np.ndarray
    gravity: np.ndarray
    coriolis_matrix: np.ndarray

    def update(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Recompute all cached quantities at joint position q [rad], velocity dq [rad/s]."""
        ...

    def joint_friction(self, dq: np.ndarray) -> np.ndarray:
        """Torque (7,) [Nm] the drives must supply to overcome joint friction (sign of dq)."""
        ...


class DynamicsArrays(NamedTuple):
    """The model quantities the numba kernels read, as one named structure (float64 arrays;
    numba unpacks it by field name at no cost). C-contiguous arrays are expected
    (``PinocchioArm`` provides them); another layout compiles one more specialization."""

    jacobian: np.ndarray
    mass_matrix: np.ndarray
    coriolis_matrix: np.ndarray
    gravity: np.ndarray
    pos_ee_world: np.ndarray
    rot_ee_world: np.ndarray


def dynamics_arrays(dynamics: ArmDynamics) -> DynamicsArrays:
    """``DynamicsArrays`` of a model (the arrays themselves: updates are seen in place)."""
    return DynamicsArrays(
        dynamics.jacobian,
        dynamics.mass_matrix,
        dynamics.coriolis_matrix,
        dynamics.gravity,
        dynamics.pos_ee_world,
        dynamics.rot_ee_world,
    )
