"""Franka's own dynamics model (pylibfranka ``Model``) beside ours.

``compare_models`` reports how far our Pinocchio FR3 model is from the robot's at the current
configuration: TCP Jacobian, gravity torque, joint-space inertia, and both gravity torques
against the measured ``tau_J`` when the arm is at rest. ``FrankaModelArm`` is the controller's
``ArmDynamics`` with the robot's Jacobian, inertia and gravity (``impact-robot hold --model
franka``); Franka's ``Model`` gives Coriolis only as the vector C(q, dq) dq and no TCP pose,
so the Coriolis matrix, the TCP pose and joint friction stay ours.

``Model.gravity(state)`` uses the state's ``O_ddP_O`` as the gravity vector; a simulator that
reports zero there gives zero gravity, so the state used here always carries
``GRAVITY_EARTH``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from impact_control.arm_model import ArmDynamics

GRAVITY_EARTH = (0.0, 0.0, -9.81)
"""Gravity [m/s^2] in the robot's base frame, written to the state's ``O_ddP_O``."""
TOLERANCE = {"jacobian": 1e-3, "gravity_nm": 1.0, "inertia_kgm2": 0.5}
"""Largest differences accepted without a flag: Jacobian 1e-3 (1 mm of TCP motion per rad: the
TCP frames agree), gravity 1 Nm (about 0.1 kg at arm's length; the internal model takes up
the rest as a load), inertia 0.5 kg m^2 (rotor armature and the hand's inertia are modelled
differently: 0.2 kg m^2 against franky-sim)."""


class ModelAgreement(NamedTuple):
    """Largest absolute differences, ours minus Franka's, at one configuration.

    Attributes:
        jacobian: TCP Jacobian [m/rad and -].
        gravity_nm: Gravity torque [Nm].
        inertia_kgm2: Joint-space inertia matrix [kg m^2].
        ours_vs_tau_j_nm: Our gravity torque minus the measured ``tau_J`` [Nm] (at rest
            this is our model's error as the robot sees it).
        franka_vs_tau_j_nm: Franka's gravity torque minus ``tau_J`` [Nm].
    """

    jacobian: float
    gravity_nm: float
    inertia_kgm2: float
    ours_vs_tau_j_nm: float
    franka_vs_tau_j_nm: float

    def mismatches(self) -> list[str]:
        """The quantities beyond ``TOLERANCE``, each as ``name difference > tolerance``."""
        return [f"{name} {getattr(self, name):.3g} > {limit:g}"
                for name, limit in TOLERANCE.items() if getattr(self, name) > limit]

    def line(self) -> str:
        """One line for ``impact-robot check``."""
        return (f"model (ours - Franka's): Jacobian {self.jacobian:.2e}, gravity "
                f"{self.gravity_nm:.3f} Nm, inertia {self.inertia_kgm2:.3f} kg m^2; gravity vs "
                f"tau_J at rest: ours {self.ours_vs_tau_j_nm:.3f} Nm, Franka's "
                f"{self.franka_vs_tau_j_nm:.3f} Nm")


def _with_gravity(state: object) -> object:
    state.O_ddP_O = list(GRAVITY_EARTH)  # type: ignore[attr-defined]
    return state


def franka_terms(model: object, state: object) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Jacobian (6, 7), inertia (7, 7), gravity (7,)) of Franka's ``Model`` at ``state``
    (libfranka's column-major arrays reshaped)."""
    s = _with_gravity(state)
    jac = np.asarray(model.zero_jacobian(s), dtype=float).reshape(7, 6).T  # type: ignore[attr-defined]
    inertia = np.asarray(model.mass(s), dtype=float).reshape(7, 7).T  # type: ignore[attr-defined]
    gravity = np.asarray(model.gravity(s), dtype=float)  # type: ignore[attr-defined]
    return jac, inertia, gravity


def compare_models(model: object, state: object, ours: ArmDynamics) -> ModelAgreement:
    """``ModelAgreement`` of ``ours`` and Franka's ``model`` at ``state`` (a ``RobotState``)."""
    q = np.asarray(state.q, dtype=float)  # type: ignore[attr-defined]
    tau_j = np.asarray(state.tau_J, dtype=float)  # type: ignore[attr-defined]
    ours.update(q, np.zeros(7))
    jac, inertia, gravity = franka_terms(model, state)
    return ModelAgreement(
        jacobian=float(np.abs(ours.jacobian - jac).max()),
        gravity_nm=float(np.abs(ours.gravity - gravity).max()),
        inertia_kgm2=float(np.abs(ours.mass_matrix - inertia).max()),
        ours_vs_tau_j_nm=float(np.abs(ours.gravity - tau_j).max()),
        franka_vs_tau_j_nm=float(np.abs(gravity - tau_j).max()))


class FrankaModelArm:
    """``ArmDynamics`` from Franka's ``Model``: Jacobian, inertia and gravity are the robot's;
    TCP pose, Coriolis matrix and joint friction come from ``kinematics`` (ours).

    Args:
        model: ``pylibfranka.Robot.load_model()``.
        state: A ``RobotState`` of this robot (its load and frames are used; ``q``, ``dq``
            and ``O_ddP_O`` are overwritten on every ``update``).
        kinematics: Our model (``impact_control.dynamics.PinocchioArm``).
    """

    def __init__(self, model: object, state: object, kinematics: ArmDynamics) -> None:
        self._model, self._state, self._kin = model, _with_gravity(state), kinematics
        self.pos_ee_world = kinematics.pos_ee_world
        self.rot_ee_world = kinematics.rot_ee_world
        self.coriolis_matrix = kinematics.coriolis_matrix
        self.jacobian = np.zeros((6, 7))
        self.mass_matrix = np.zeros((7, 7))
        self.gravity = np.zeros(7)

    def update(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Both models at (q, dq); the arrays are written in place (the kernels hold them)."""
        self._kin.update(q, dq)
        s = self._state
        s.q, s.dq = list(map(float, q)), list(map(float, dq))  # type: ignore[attr-defined]
        jac, inertia, gravity = franka_terms(self._model, s)
        np.copyto(self.jacobian, jac)
        np.copyto(self.mass_matrix, inertia)
        np.copyto(self.gravity, gravity)

    def joint_friction(self, dq: np.ndarray) -> np.ndarray:
        """Our joint-friction model (Franka's ``Model`` has none)."""
        return self._kin.joint_friction(dq)
