"""Options of the impedance law that the authors' released controller uses (off in ``default``
and ``paper``): gains in the TCP frame, a per-axis pose-error clip, a clamp on the projected
null-space torque. ``impedance.py::impedance_law`` calls these kernels only when
``ImpedanceOptions.on``; otherwise it runs its plain law, unchanged.

TCP frame (the authors' ``use_local_jacobian: true``): with R = R_ee (world from TCP),

    e_tcp = (R^T e_p, R^T e_R),   v_tcp = (R^T v, R^T w),   w_tcp = K clip(e_tcp) - D v_tcp
    w_imp (world) = (R w_tcp_force, R w_tcp_torque)

R^T Log(R_d R^T) = Log(R^T R_d), the authors' local orientation error. With isotropic K and D
and no clip this equals the world-frame law (up to round-off); the clip and anisotropic gains
act on TCP axes. Clamped null space: tau_null = clip(N tau_0, -max, max) per joint, with
N tau_0 = tau_0 - J^T w_null (``impedance.py``), the authors' ``nullspace.max_tau``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.kernel_math import mat_t_vec, rotate, rotate_back
from impact_control.stage_layout import N_JOINTS, Layout


class ImpedanceExtra(NamedTuple):
    """The options' constants and work arrays (``unpack_impedance_extra``), views of the
    tail of the law's buffer (``ImpedanceState.extra``). Constants are (1,) views (flags 0 or
    1), not scalars, so that the law crosses into numba as cheaply as before they existed; the
    views are built only on ticks that use an option (a view costs its reference count).

    Attributes:
        on: Whether any option is on (else the plain law runs).
        tcp_frame: K and D act on TCP-frame axes.
        clip_m: Per-axis bound on the position error in the gains frame [m] (inf: none).
        clip_rad: Per-axis bound on the orientation error [rad] (inf: none).
        null_clamp: Whether the projected null-space torque is clamped.
        null_max_nm: Its per-joint bound [Nm].
        error_gains, twist_gains, wrench_gains: (6,) e (clipped), J dq and K e - D J dq in
            the gains frame.
        tau_null: (n,) the projected, clamped null-space torque [Nm].
    """

    on: np.ndarray
    tcp_frame: np.ndarray
    clip_m: np.ndarray
    clip_rad: np.ndarray
    null_clamp: np.ndarray
    null_max_nm: np.ndarray
    error_gains: np.ndarray
    twist_gains: np.ndarray
    wrench_gains: np.ndarray
    tau_null: np.ndarray


IMPEDANCE_EXTRA_LAYOUT = Layout.of(ImpedanceExtra, dict(
    on=1, tcp_frame=1, clip_m=1, clip_rad=1, null_clamp=1, null_max_nm=1, error_gains=6,
    twist_gains=6, wrench_gains=6, tau_null=N_JOINTS),
    dims={"n": "n_joints"}, args=("ext", "n_joints"))
"""The options' tail of the law's buffer."""
unpack_impedance_extra = IMPEDANCE_EXTRA_LAYOUT.unpacker("unpack_impedance_extra", __name__)
options_on = IMPEDANCE_EXTRA_LAYOUT.flag_reader("on", "options_on", __name__)
null_clamp_on = IMPEDANCE_EXTRA_LAYOUT.flag_reader("null_clamp", "null_clamp_on", __name__)


def write_impedance_options(x: ImpedanceExtra, gains_frame: str, clip_m: float | None,
                            clip_rad: float | None, null_max_nm: float | None) -> None:
    """Write the config's fields into the option views ``x`` (None: that option off)."""
    tcp = gains_frame == "tcp"
    on = tcp or clip_m is not None or clip_rad is not None or null_max_nm is not None
    x.on[0], x.tcp_frame[0], x.null_clamp[0] = on, tcp, null_max_nm is not None
    x.clip_m[0] = math.inf if clip_m is None else float(clip_m)
    x.clip_rad[0] = math.inf if clip_rad is None else float(clip_rad)
    x.null_max_nm[0] = math.inf if null_max_nm is None else float(null_max_nm)


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def gains_wrench(rot_ee, st, x) -> None:
    """st.wrench_imp = K clip(e) - D twist with both in the gains frame, then in the world
    frame (``st``: ``ImpedanceState``, whose ``pose_error`` and ``twist`` are world-frame
    inputs; ``x``: its ``ImpedanceExtra``)."""
    par = st.params
    e, v, w = x.error_gains, x.twist_gains, x.wrench_gains
    tcp = x.tcp_frame[0] != 0.0
    if tcp:
        rotate_back(rot_ee, st.pose_error, e)
        rotate_back(rot_ee, st.twist, v)
    else:
        for i in range(6):
            e[i] = st.pose_error[i]
            v[i] = st.twist[i]
    for i in range(6):
        c = x.clip_m[0] if i < 3 else x.clip_rad[0]
        e[i] = min(max(e[i], -c), c)
        w[i] = par.stiffness[i] * e[i] - par.damping[i] * v[i]
    if tcp:
        rotate(rot_ee, w, st.wrench_imp)
    else:
        for i in range(6):
            st.wrench_imp[i] = w[i]


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def clamped_nullspace(jac, wrench_ff, st, x, out) -> None:
    """out = J^T (w_imp + w_ff); x.tau_null = clip(tau_0 - J^T w_null, +-max) per joint
    (``st.wrench_null`` already holds (J^+)^T tau_0)."""
    mat_t_vec(jac, st.wrench_null, x.tau_null)
    m = x.null_max_nm[0]
    for j in range(x.tau_null.shape[0]):
        x.tau_null[j] = min(max(st.tau_posture[j] - x.tau_null[j], -m), m)
    for i in range(6):
        st.wrench[i] = st.wrench_imp[i] + wrench_ff[i]
    mat_t_vec(jac, st.wrench, out)
