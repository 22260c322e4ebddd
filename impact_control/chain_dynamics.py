"""numba kinematics and dynamics of a serial chain of revolute-z joints (no MuJoCo here).

The arm model runs at 1 kHz inside the control loop. Five Pinocchio calls cost about 10 us
per tick, mostly binding overhead and array copies; ``chain_terms`` computes the same
quantities (TCP pose, world-aligned TCP Jacobian, M(q) with armature, g(q), and a Coriolis
matrix with M' = C + C^T) in about 3 us, and the closed loop (``impact_envs/loop``) runs it
inside its one call per tick. The parameters are read once from a (possibly perturbed) ``pin.Model``
(``ChainParams.from_pinocchio``), so Pinocchio stays the single source of the controller's
model; tests/robot/test_chain_dynamics.py checks every output against Pinocchio.

Algorithm (world frame, per link i with COM c_i, world inertia I_i = R_i I_i^body R_i^T):
    J_v,i[:, j] = z_j x (c_i - o_j),  J_w,i[:, j] = z_j          (j <= i)
    M = sum_i m_i J_v,i^T J_v,i + J_w,i^T I_i J_w,i + diag(armature)
    g = -sum_i m_i J_v,i^T g_world
    C = sum_i m_i J_v,i^T J_v,i' + J_w,i^T I_i J_w,i' + J_w,i^T [w_i]x I_i J_w,i
with z_j' = w_j x z_j and the point velocities from the joint rates. C + C^T = M' follows from
I_i' = [w_i]x I_i - I_i [w_i]x; C q' is the Coriolis/centrifugal torque.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError


class ModelArrays(NamedTuple):
    """Outputs of ``chain_terms``, written in place (``PinocchioArm``'s cached attributes)."""

    pos_ee_world: np.ndarray
    rot_ee_world: np.ndarray
    jacobian: np.ndarray
    mass_matrix: np.ndarray
    gravity: np.ndarray
    coriolis_matrix: np.ndarray


class ChainParams(NamedTuple):
    """Constant model parameters of an n-joint revolute-z chain (joint frames, parent first);
    a named tuple of arrays, which is what ``chain_terms`` reads.

    Attributes:
        rot_joint_parent: (n, 3, 3) rotation of joint i's frame in its parent's at q = 0.
        pos_joint_parent: (n, 3) origin of joint i's frame in its parent's frame [m].
        mass: (n,) link masses [kg].
        com_joint: (n, 3) link COM in the joint frame [m].
        inertia_com_joint: (n, 3, 3) rotational inertia about the COM, joint axes [kg m^2].
        armature: (n,) rotor inertia added to the diagonal of M [kg m^2].
        rot_tcp_last: (3, 3) TCP frame rotation in the last joint's frame.
        pos_tcp_last: (3,) TCP origin in the last joint's frame [m].
        gravity_world: (3,) gravitational acceleration [m/s^2].
    """

    rot_joint_parent: np.ndarray
    pos_joint_parent: np.ndarray
    mass: np.ndarray
    com_joint: np.ndarray
    inertia_com_joint: np.ndarray
    armature: np.ndarray
    rot_tcp_last: np.ndarray
    pos_tcp_last: np.ndarray
    gravity_world: np.ndarray

    @classmethod
    def from_pinocchio(cls, model: Any, tcp_frame_id: int) -> ChainParams:
        """Read a ``pin.Model`` chain of ``JointModelRZ`` joints and a TCP frame on the last."""
        n = model.njoints - 1
        kinds = [model.joints[i].shortname() for i in range(1, n + 1)]
        parents = [int(model.parents[i]) for i in range(1, n + 1)]
        frame = model.frames[tcp_frame_id]
        if any(k != "JointModelRZ" for k in kinds) or parents != list(range(n)):
            raise InvalidArgumentError(f"chain kernel needs a serial RZ chain, got {kinds}")
        if int(frame.parentJoint) != n:
            raise InvalidArgumentError("the TCP frame must hang on the last joint")
        f64 = np.float64
        inertias = [model.inertias[i] for i in range(1, n + 1)]
        placements = [model.jointPlacements[i] for i in range(1, n + 1)]
        return cls(
            rot_joint_parent=np.array([p.rotation for p in placements], f64),
            pos_joint_parent=np.array([p.translation for p in placements], f64),
            mass=np.array([x.mass for x in inertias], f64),
            com_joint=np.array([x.lever for x in inertias], f64),
            inertia_com_joint=np.array([x.inertia for x in inertias], f64),
            armature=np.asarray(model.armature, f64).copy(),
            rot_tcp_last=np.array(frame.placement.rotation, f64),
            pos_tcp_last=np.array(frame.placement.translation, f64),
            gravity_world=np.array(model.gravity.linear, f64),
        )


def make_workspace(n: int) -> np.ndarray:
    """Scratch buffer of ``chain_terms`` for an n-joint arm."""
    return np.zeros((n, 12, 3))


@njit(cache=True)
def _cross(a, b, out) -> None:
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def _cross_diff(a, p, o, out) -> None:
    """out = a x (p - o) without a temporary."""
    d0, d1, d2 = p[0] - o[0], p[1] - o[1], p[2] - o[2]
    out[0] = a[1] * d2 - a[2] * d1
    out[1] = a[2] * d0 - a[0] * d2
    out[2] = a[0] * d1 - a[1] * d0


@njit(cache=True)
def _matmul3(a, b, out) -> None:
    for r in range(3):
        for c in range(3):
            out[r, c] = a[r, 0] * b[0, c] + a[r, 1] * b[1, c] + a[r, 2] * b[2, c]


@njit(cache=True)
def _matvec3(a, v, out) -> None:
    for r in range(3):
        out[r] = a[r, 0] * v[0] + a[r, 1] * v[1] + a[r, 2] * v[2]


@njit(cache=True)
def _forward(rot_jp, pos_jp, com_j, inertia_j, q, dq, work) -> None:
    """Per link: world rotation, inertia, origin, axis, COM, angular and point velocities.

    ``work[i]`` rows: 0-2 rotation, 3-5 world inertia about the COM, 6 origin, 7 axis, 8 COM,
    9 angular velocity, 10 origin velocity, 11 COM velocity.
    """
    n = q.shape[0]
    tmp = np.empty((3, 3))
    rz = np.zeros((3, 3))
    rz[2, 2] = 1.0
    v = np.empty(3)
    for i in range(n):
        w = work[i]
        c, s = np.cos(q[i]), np.sin(q[i])
        rz[0, 0], rz[0, 1], rz[1, 0], rz[1, 1] = c, -s, s, c
        if i == 0:
            tmp[:, :] = rot_jp[0]
            for r in range(3):
                w[6, r] = pos_jp[0, r]
        else:
            prev = work[i - 1]
            _matmul3(prev[0:3], rot_jp[i], tmp)
            _matvec3(prev[0:3], pos_jp[i], v)
            for r in range(3):
                w[6, r] = prev[6, r] + v[r]
        _matmul3(tmp, rz, w[0:3])
        _matvec3(w[0:3], com_j[i], v)
        for r in range(3):
            w[7, r] = w[r, 2]
            w[8, r] = w[6, r] + v[r]
        _matmul3(w[0:3], inertia_j[i], tmp)
        for r in range(3):  # R I R^T
            for col in range(3):
                w[3 + r, col] = (tmp[r, 0] * w[col, 0] + tmp[r, 1] * w[col, 1]
                                 + tmp[r, 2] * w[col, 2])
        for r in range(3):
            w[9, r] = (work[i - 1, 9, r] if i > 0 else 0.0) + w[7, r] * dq[i]
    for i in range(n):  # v(point) = sum_{k <= joint} (z_k x (point - o_k)) dq_k
        w = work[i]
        for r in range(3):
            w[10, r] = 0.0
            w[11, r] = 0.0
        for k in range(i + 1):
            if k < i:
                _cross_diff(work[k, 7], w[6], work[k, 6], v)
                for r in range(3):
                    w[10, r] += v[r] * dq[k]
            _cross_diff(work[k, 7], w[8], work[k, 6], v)
            for r in range(3):
                w[11, r] += v[r] * dq[k]


@njit(cache=True)
def _tcp_terms(work, rot_tcp, pos_tcp, pos_ee, rot_ee, jac) -> None:
    """TCP pose from the last link's frame and the world-aligned TCP Jacobian."""
    n = work.shape[0]
    last = work[n - 1]
    _matmul3(last[0:3], rot_tcp, rot_ee)
    col = np.empty(3)
    _matvec3(last[0:3], pos_tcp, col)
    for r in range(3):
        pos_ee[r] = last[6, r] + col[r]
    for j in range(n):
        _cross_diff(work[j, 7], pos_ee, work[j, 6], col)
        for r in range(3):
            jac[r, j] = col[r]
            jac[3 + r, j] = work[j, 7, r]


@njit(cache=True)
def _add_products(out, cols, m, jv, lin, work, rot) -> None:
    """out[j, k] += m J_v[:, j] . lin[k] + z_j . rot[k] for j, k < cols (one link's share of
    M with lin = J_v, rot = I z; of C with lin = J_v', rot = I z' + w x I z)."""
    for j in range(cols):
        zj = work[j, 7]
        for k in range(cols):
            out[j, k] += m * (jv[j, 0] * lin[k, 0] + jv[j, 1] * lin[k, 1]
                              + jv[j, 2] * lin[k, 2]) + (
                zj[0] * rot[k, 0] + zj[1] * rot[k, 1] + zj[2] * rot[k, 2])


@njit(cache=True)
def chain_terms(chain, q, dq, need_coriolis, work, out) -> None:
    """Fill TCP pose, world-aligned TCP Jacobian (linear rows first), M, g and (optionally) C.

    ``chain`` is a ``ChainParams``, ``work`` comes from ``make_workspace``, ``out`` is a
    ``ModelArrays`` (all written in place).
    """
    rot_jp, pos_jp, mass, com_j, inertia_j, armature, rot_tcp, pos_tcp, gravity = chain
    pos_ee, rot_ee, jac, mass_matrix, grav, coriolis = out
    n = q.shape[0]
    _forward(rot_jp, pos_jp, com_j, inertia_j, q, dq, work)
    _tcp_terms(work, rot_tcp, pos_tcp, pos_ee, rot_ee, jac)
    mass_matrix[:, :] = 0.0
    grav[:] = 0.0
    if need_coriolis:
        coriolis[:, :] = 0.0
    scratch = np.empty((4 * n + 2, 3))
    jv = scratch[0:n]  # rows: columns of J_v,i
    iw = scratch[n:2 * n]  # rows: I_i z_j
    djv = scratch[2 * n:3 * n]
    djw = scratch[3 * n:4 * n]
    a = scratch[4 * n]
    b = scratch[4 * n + 1]
    for i in range(n):
        li = work[i]
        m = mass[i]
        for j in range(i + 1):
            _cross_diff(work[j, 7], li[8], work[j, 6], jv[j])
            _matvec3(li[3:6], work[j, 7], iw[j])
            grav[j] -= m * (jv[j, 0] * gravity[0] + jv[j, 1] * gravity[1]
                            + jv[j, 2] * gravity[2])
            if need_coriolis:
                _cross(work[j, 9], work[j, 7], djw[j])  # z_j' = w_j x z_j
                _cross_diff(djw[j], li[8], work[j, 6], a)
                _cross_diff(work[j, 7], li[11], work[j, 10], b)
                for r in range(3):
                    djv[j, r] = a[r] + b[r]
        _add_products(mass_matrix, i + 1, m, jv, jv, work, iw)
        if need_coriolis:
            w = li[9]
            for k in range(i + 1):  # a = I dz_k + w x (I z_k)
                _matvec3(li[3:6], djw[k], a)
                _cross(w, iw[k], b)
                for r in range(3):
                    djw[k, r] = a[r] + b[r]  # reuse: rotational part of column k
            _add_products(coriolis, i + 1, m, jv, djv, work, djw)
    for j in range(n):
        mass_matrix[j, j] += armature[j]
