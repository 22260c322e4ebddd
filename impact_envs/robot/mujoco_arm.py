"""``MujocoArm``: the controller's arm model computed by MuJoCo itself (no Pinocchio).

For arms that have a MuJoCo model but no Pinocchio one (robosuite's Panda, say): FK and the
site Jacobian from ``mj_kinematics`` / ``mj_jacSite``, the joint-space inertia from ``mj_makeM``
/ ``mj_fullM`` (armature included, as MuJoCo simulates it), gravity and the velocity terms
from ``mj_rne``. It works on a private ``MjData`` of the given model, so the simulation it may
sit beside is never touched; the joints that are not the arm's (fingers, objects) stay at the
configuration given at construction (``qpos_fixed``; default: the model's ``qpos0``).

The controller forms only ``C dq`` and ``C^T dq`` (docs/controller.md). MuJoCo gives
``C dq`` exactly (``mj_rne`` at ``dq`` minus gravity); ``C^T dq = M_dot dq - C dq`` uses
``M_dot dq``, a central difference of M along dq. ``coriolis_matrix`` is the smallest-rank
matrix with exactly these two products at the last ``update`` (C is not unique; the
Pinocchio model builds another one with the same products).
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from impact_control.errors import InvalidArgumentError

FD_STEP = 1e-6
"""Step [s] of the central difference of M along dq (M_dot dq); error ~1e-10 relative."""


def full_mass_matrix(model: mujoco.MjModel, data: mujoco.MjData, out: np.ndarray) -> None:
    """Dense M into ``out`` (nv, nv) after ``mj_makeM``, across MuJoCo's API change (3.x took
    ``mj_fullM(m, dst, qM)``; 4.0 takes ``mj_fullM(m, d, dst)``)."""
    if hasattr(data, "qM"):
        mujoco.mj_fullM(model, out, data.qM)
    else:
        mujoco.mj_fullM(model, data, out)


class MujocoArm:
    """``ArmDynamics`` of a 7-joint arm in a MuJoCo model, at a site (the TCP).

    Args:
        model: The MuJoCo model (e.g. the simulation's own).
        joints: Names of the 7 arm joints (hinges), base to wrist.
        site: Name of the TCP site the controller tracks.
        qpos_fixed: Positions of every other joint (nq,), held while the arm moves.
    """

    n: int = 7

    def __init__(self, model: mujoco.MjModel, joints: Sequence[str], site: str,
                 qpos_fixed: np.ndarray | None = None) -> None:
        if len(joints) != self.n:
            raise InvalidArgumentError(f"MujocoArm needs 7 arm joints, got {len(joints)}")
        self.model = model
        self.data = mujoco.MjData(model)
        try:
            ids = [model.joint(name).id for name in joints]
            self._site = model.site(site).id
        except KeyError as exc:
            raise InvalidArgumentError(f"not in the MuJoCo model: {exc}") from None
        if any(model.jnt_type[i] != mujoco.mjtJoint.mjJNT_HINGE for i in ids):
            raise InvalidArgumentError(f"arm joints must be hinges: {list(joints)}")
        self._qpos = np.array([model.jnt_qposadr[i] for i in ids])
        self._dof = np.array([model.jnt_dofadr[i] for i in ids])
        self.data.qpos[:] = model.qpos0 if qpos_fixed is None else qpos_fixed
        self.q_lower = model.jnt_range[ids, 0].copy()
        self.q_upper = model.jnt_range[ids, 1].copy()
        self.pos_ee_world, self.rot_ee_world = np.zeros(3), np.eye(3)
        self.jacobian = np.zeros((6, 7))
        self.mass_matrix, self.gravity = np.eye(7), np.zeros(7)
        self.coriolis_matrix = np.zeros((7, 7))
        self.need_coriolis = True
        self.joint_friction_is_zero = True
        nv = model.nv
        self._full, self._jac = np.zeros((nv, nv)), np.zeros((6, nv))
        self._rne = np.zeros(nv)

    def _kinematics(self, q: np.ndarray) -> None:
        """Positions-dependent quantities at ``q`` (zero velocity)."""
        d = self.data
        d.qpos[self._qpos] = q
        d.qvel[:] = 0.0
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_comPos(self.model, d)
        mujoco.mj_makeM(self.model, d)  # composite rigid body + armature (mj_crb alone left
        # MuJoCo 3.9's qM empty)

    def _arm_mass(self) -> np.ndarray:
        full_mass_matrix(self.model, self.data, self._full)
        return self._full[np.ix_(self._dof, self._dof)]

    def _bias(self, dq: np.ndarray) -> np.ndarray:
        """``mj_rne`` without acceleration at the current positions and velocity ``dq``:
        gravity plus C dq on the arm's dofs [Nm]."""
        d = self.data
        d.qvel[self._dof] = dq
        mujoco.mj_comVel(self.model, d)
        mujoco.mj_rne(self.model, d, 0, self._rne)
        return self._rne[self._dof].copy()

    def update(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Recompute every cached quantity at joint positions ``q`` [rad], velocities ``dq``."""
        q, dq = np.asarray(q, float), np.asarray(dq, float)
        self._kinematics(q)
        d, s = self.data, self._site
        self.pos_ee_world[:] = d.site_xpos[s]
        self.rot_ee_world[:] = d.site_xmat[s].reshape(3, 3)
        mujoco.mj_jacSite(self.model, d, self._jac[:3], self._jac[3:], s)
        self.jacobian[:] = self._jac[:, self._dof]
        self.mass_matrix[:] = self._arm_mass()
        self.gravity[:] = self._bias(np.zeros(7))
        if self.need_coriolis:
            self.coriolis_matrix[:] = self._coriolis(q, dq)

    def _coriolis(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """A C with C dq and C^T dq exact at (q, dq) (see the module docstring)."""
        vv = float(dq @ dq)
        if vv == 0.0:
            return np.zeros((7, 7))
        c_dq = self._bias(dq) - self.gravity
        self._kinematics(q + FD_STEP * dq)
        m_plus = self._arm_mass()
        self._kinematics(q - FD_STEP * dq)
        m_dot_dq = (m_plus - self._arm_mass()) @ dq / (2.0 * FD_STEP)
        self._kinematics(q)  # leave the private data at q
        ct_dq = m_dot_dq - c_dq
        return (np.outer(c_dq, dq) + np.outer(dq, ct_dq)) / vv - np.outer(dq, dq) * (
            float(dq @ c_dq) / (vv * vv))

    def joint_friction(self, dq: np.ndarray) -> np.ndarray:
        """Zero: the emulated torque sensor is link-side, after the joints' friction."""
        return np.zeros(len(dq))
