"""Task-space impedance law with null-space posture control and model compensation.

tau_no_gravity = J^T (w_imp + w_ff) + N tau_0 + C(q, dq) dq,   g(q) kept separate
w_imp  = K e - D J dq,   e = [p_d - p; Log(R_d R^T)]  (world frame)
tau_0  = k_n (q_null - q) - d_n dq
N      = I - J^T (J^+)^T,   J^+ = J^T (J J^T + lambda_n^2 I)^-1   (Franka's static projector)

w_ff is any extra wrench (internal-model feedforward, commanded wrench). The projection is
evaluated as N tau_0 = tau_0 - J^T w_null with w_null = (J^+)^T tau_0, so all wrenches share one
J^T product: tau = J^T (w_imp + w_ff - w_null) + tau_0 + C dq. Gravity is returned separately
(``tau_gravity``) because the torque-rate limiter acts on the command without gravity, like
libfranka.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.arm_model import ArmDynamics, dynamics_arrays
from impact_control.impedance_config import ImpedanceConfig
from impact_control.impedance_options import (
    IMPEDANCE_EXTRA_LAYOUT,
    ImpedanceExtra,
    clamped_nullspace,
    gains_wrench,
    null_clamp_on,
    options_on,
    unpack_impedance_extra,
    write_impedance_options,
)
from impact_control.kernel_layout import Packed
from impact_control.kernel_math import mat_t_vec, mat_vec, orientation_error
from impact_control.lie import invalid_quaternion
from impact_control.stage_layout import N_JOINTS, Layout

__all__ = ["CartesianImpedance", "ImpedanceConfig", "ImpedanceExtra", "ImpedanceParams",
           "ImpedanceState", "impedance_law", "make_impedance_state", "unpack_impedance"]


# ------------------------------------------------------------------ named state and kernel
class ImpedanceParams(NamedTuple):
    """The law's gains, fixed at construction (``make_impedance_state``).

    Attributes:
        stiffness: Diagonal of K (6,) [N/m; Nm/rad], world frame.
        damping: Diagonal of D (6,) [N s/m; Nm s/rad].
        k_null: Null-space joint stiffness k_n [Nm/rad].
        d_null: Null-space joint damping d_n [Nm s/rad].
        compensate_gravity: Whether ``tau_gravity`` is filled with g(q).
        compensate_coriolis: Whether C(q, dq) dq is added.
    """

    stiffness: np.ndarray
    damping: np.ndarray
    k_null: float
    d_null: float
    compensate_gravity: bool
    compensate_coriolis: bool


class ImpedanceState(NamedTuple):
    """Everything ``impedance_law`` reads and writes (numba takes it as one argument).

    Attributes:
        params: ``ImpedanceParams``.
        q_null: Posture target of the null-space task (n,) [rad] (``set_posture``).
        k_q_null: k_n q_null (n,) [Nm].
        pose_error: e = [p_d - p (3) [m]; Log(R_d R^T) (3) [rad]], world frame.
        twist: TCP velocity J dq (6,) [m/s, rad/s].
        wrench_imp: K e - D J dq (6,) [N, Nm].
        tau_posture: Unprojected posture torque tau_0 (n,) [Nm].
        wrench_null: (J^+)^T tau_0 (6,) [N, Nm], removed by the projector.
        wrench: w_imp - w_null + w_ff (6,) [N, Nm], mapped by J^T.
        tau_coriolis: C dq (n,) [Nm] (zeros if disabled).
        tau_gravity: g(q) (n,) [Nm] (zeros if disabled).
        tau_no_gravity: Full command without gravity (n,) [Nm].
        extra: The options' constants and work arrays (TCP-frame gains, error clip,
            null-space clamp), named by ``impedance_options.unpack_impedance_extra`` on the
            ticks that use them.
    """

    params: ImpedanceParams
    q_null: np.ndarray
    k_q_null: np.ndarray
    pose_error: np.ndarray
    twist: np.ndarray
    wrench_imp: np.ndarray
    tau_posture: np.ndarray
    wrench_null: np.ndarray
    wrench: np.ndarray
    tau_coriolis: np.ndarray
    tau_gravity: np.ndarray
    tau_no_gravity: np.ndarray
    extra: np.ndarray


class ImpedanceScalars(NamedTuple):
    """The scalar gains and the joint count (``ImpedanceParams`` without its arrays)."""

    k_null: float
    d_null: float
    compensate_gravity: bool
    compensate_coriolis: bool
    n_joints: int


IMPEDANCE_LAYOUT = Layout.of(ImpedanceState, dict(
    params=Layout.of(ImpedanceParams, dict(stiffness=6, damping=6)),
    q_null=N_JOINTS, k_q_null=N_JOINTS, pose_error=6, twist=6, wrench_imp=6,
    tau_posture=N_JOINTS, wrench_null=6, wrench=6, tau_coriolis=N_JOINTS,
    tau_gravity=N_JOINTS, tau_no_gravity=N_JOINTS, extra=IMPEDANCE_EXTRA_LAYOUT.length),
    dims={"n": "sc.n_joints"})
"""The law's buffer; its tail ``extra`` is the options' (``IMPEDANCE_EXTRA_LAYOUT``)."""
unpack_impedance = IMPEDANCE_LAYOUT.unpacker("unpack_impedance", __name__)


def make_impedance_state(config: ImpedanceConfig, n_joints: int = 7) -> Packed:
    """``config``'s gains for ``n_joints`` joints, packed (``unpack_impedance`` names it)."""
    sc = ImpedanceScalars(float(config.nullspace_stiffness_nm_per_rad),
                          float(config.nullspace_damping), bool(config.compensate_gravity),
                          bool(config.compensate_coriolis), int(n_joints))
    packed = Packed(sc, np.zeros(IMPEDANCE_LAYOUT.size_for(sc)))
    st = unpack_impedance(packed.buffer, sc)[0]
    write_impedance_options(unpack_impedance_extra(st.extra, n_joints)[0],
                            config.gains_frame, config.pose_error_clip_m,
                            config.pose_error_clip_rad, config.nullspace_torque_max_nm)
    params = st.params
    params.stiffness[:] = (config.stiffness_translational_n_per_m
                           + config.stiffness_rotational_nm_per_rad)
    params.damping[:] = (config.damping_translational_ns_per_m
                         + config.damping_rotational_nms_per_rad)
    return packed


@njit(cache=True, inline="always")
def impedance_law(dyn, q, dq, pos_target, quat_target, wrench_map, wrench_ff, st) -> bool:
    """tau_no_gravity = J^T (K e - D J dq - W_n tau_0 + w_ff) + tau_0 + C dq (impedance.py).

    dyn = (J, M, C, g, p_ee, R_ee); st = ``ImpedanceState``. Returns False (nothing written)
    when the target quaternion is invalid.
    """
    jac, _, cor, grav, pos_ee, rot_ee = dyn
    par = st.params
    e, tau0, out = st.pose_error, st.tau_posture, st.tau_no_gravity
    if not orientation_error(quat_target, rot_ee, e[3:]):
        return False
    for i in range(3):
        e[i] = pos_target[i] - pos_ee[i]
    mat_vec(jac, dq, st.twist)
    if options_on(st.extra):  # TCP-frame gains and the error clip (impedance_options.py)
        gains_wrench(rot_ee, st, unpack_impedance_extra(st.extra, q.shape[0])[0])
    else:
        for i in range(6):
            st.wrench_imp[i] = par.stiffness[i] * e[i] - par.damping[i] * st.twist[i]
    for j in range(tau0.shape[0]):
        tau0[j] = q[j] * -par.k_null + st.k_q_null[j] - dq[j] * par.d_null
    mat_vec(wrench_map, tau0, st.wrench_null)
    tau_null = tau0
    if null_clamp_on(st.extra):
        x = unpack_impedance_extra(st.extra, q.shape[0])[0]
        clamped_nullspace(jac, wrench_ff, st, x, out)  # out = J^T (w_imp + w_ff)
        tau_null = x.tau_null
    else:
        for i in range(6):
            st.wrench[i] = st.wrench_imp[i] - st.wrench_null[i] + wrench_ff[i]
        mat_t_vec(jac, st.wrench, out)
    if par.compensate_coriolis:
        mat_vec(cor, dq, st.tau_coriolis)
    for j in range(out.shape[0]):
        out[j] += tau_null[j]
        if par.compensate_coriolis:
            out[j] += st.tau_coriolis[j]
        if par.compensate_gravity:
            st.tau_gravity[j] = grav[j]
    return True


class CartesianImpedance:
    """The impedance law as a typed object: ``state`` (``ImpedanceState``) and ``compute``.

    The law itself is ``impedance_law`` (also run by ``kernels.controller_tick``); the array
    attributes below are the state's own arrays (written in place every tick).

    Attributes:
        pose_error: e = [p_d - p (3) [m]; Log(R_d R^T) (3) [rad]], world frame.
        twist_world: TCP velocity J dq (6,) [m/s, rad/s].
        wrench_imp_world: K e - D J dq (6,) [N, Nm].
        tau_posture: Unprojected posture torque tau_0 (7,) [Nm].
        wrench_null_world: (J^+)^T tau_0 (6,) [N, Nm], removed by the projector.
        tau_coriolis: C dq (7,) [Nm] (zeros if disabled).
        tau_gravity: g(q) (7,) [Nm] (zeros if disabled).
        tau_no_gravity: Full command without gravity (7,) [Nm].
        q_null: Posture target of the null-space task (7,) [rad].
        stiffness, damping: Diagonals of K and D (6,).
    """

    STATELESS: tuple[str, ...] = ("_zeros6",)
    """Array attributes that carry nothing from one tick to the next (a constant)."""

    def __init__(self, config: ImpedanceConfig, n_joints: int = 7) -> None:
        """Create the law from ``config`` for an arm with ``n_joints`` joints."""
        self.config = config
        self.packed = make_impedance_state(config, n_joints)
        self.state = st = unpack_impedance(self.packed.buffer, self.packed.scalars)[0]
        self.k_null, self.d_null = st.params.k_null, st.params.d_null
        self.stiffness, self.damping = st.params.stiffness, st.params.damping
        self.pose_error, self.twist_world = st.pose_error, st.twist
        self.wrench_imp_world, self.tau_posture = st.wrench_imp, st.tau_posture
        self.wrench_null_world, self.tau_coriolis = st.wrench_null, st.tau_coriolis
        self.tau_gravity, self.tau_no_gravity = st.tau_gravity, st.tau_no_gravity
        self.q_null = st.q_null
        self.extra = unpack_impedance_extra(st.extra, n_joints)[0]  # the options' views
        self._zeros6 = np.zeros(6)

    def set_posture(self, q_null: np.ndarray) -> None:
        """Set the null-space posture target q_null [rad] (the controller does it at reset)."""
        self.q_null[:] = q_null
        np.multiply(self.q_null, self.k_null, out=self.state.k_q_null)

    def compute(
        self,
        dynamics: ArmDynamics,
        q: np.ndarray,
        dq: np.ndarray,
        pos_target_world: np.ndarray,
        quat_target_world: np.ndarray,
        wrench_map: np.ndarray,
        wrench_ff_world: np.ndarray | None = None,
    ) -> np.ndarray:
        """Evaluate the law at the state cached in ``dynamics`` (already ``update``-d).

        Args:
            dynamics: Model updated at (q, dq).
            q: Joint positions (7,) [rad].
            dq: Joint velocities (7,) [rad/s].
            pos_target_world: Desired TCP position (3,) [m].
            quat_target_world: Desired TCP orientation (w, x, y, z).
            wrench_map: (J J^T + lambda_n^2 I)^-1 J (6, 7), see ``regularized_wrench_map``.
            wrench_ff_world: Optional extra wrench added as J^T w_ff (6,) [N, Nm].

        Returns:
            ``tau_no_gravity`` (7,) [Nm]; add ``tau_gravity`` for the full command.

        Raises:
            InvalidArgumentError: If the target quaternion is zero or not finite.
        """
        f64 = np.float64
        w_ff = self._zeros6 if wrench_ff_world is None else np.asarray(wrench_ff_world, f64)
        ok = impedance_law(
            dynamics_arrays(dynamics), np.asarray(q, f64), np.asarray(dq, f64),
            np.asarray(pos_target_world, f64), np.asarray(quat_target_world, f64),
            np.asarray(wrench_map, f64), w_ff, self.state,
        )  # fmt: skip
        if not ok:
            raise invalid_quaternion(quat_target_world)
        return self.tau_no_gravity

    def tau_null(self, jacobian: np.ndarray) -> np.ndarray:
        """Projected posture torque N tau_0 = tau_0 - J^T w_null (7,) [Nm] of the last tick."""
        return self.tau_posture - self.wrench_null_world @ jacobian
