"""Target-pose filter: an exponential moving average of the TCP target, once per tick (the
authors' released controller, ``filter.target_pose``; off in ``default`` and ``paper``).

``space="se3_log"`` (as the authors coded it): the average of the two poses' SE(3) logs,

    xi_f = (1 - w_new) Log(T_f) + w_new Log(T_target),   T_f <- Exp(xi_f)

(their ``exponential_moving_average(log6(target_pose_), log6(new), 0.1)``: weight 0.9 on the
new target). The log of a rotation by pi has no unique sign, so two targets on either side of
pi (a hand pointing straight down turned a little) average to a rotation far from both: at
w_new = 0.9, +pi n and -pi n give 0.8 pi n. ``space="geodesic"`` is the average along the
path between the poses instead, T_f <- T_f Exp(w_new Log(T_f^-1 T_target)), the same for
poses away from pi and continuous through it. Before the first tick after ``reset`` the
filtered target is the TCP's own pose (the authors set it at activation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.kernel_layout import Packed
from impact_control.kernel_math import matrix_to_quat, quat_normalized
from impact_control.se3 import quat_mul, quat_rotate, se3_exp, se3_log
from impact_control.stage_layout import Layout, slots

SPACES: tuple[str, ...] = ("se3_log", "geodesic")
"""Valid ``TargetFilterConfig.space`` values."""


@dataclass(frozen=True)
class TargetFilterConfig:
    """EMA of the TCP target pose, per tick.

    Attributes:
        enabled: Filter the target (default False: the target as given).
        weight_new: Weight of the new target per tick (the authors: 0.9, i.e. their
            ``filter.target_pose`` 0.1 on the previous value), in (0, 1].
        space: ``"se3_log"`` (the authors' code: average of SE(3) logs) or ``"geodesic"``.
    """

    enabled: bool = False
    weight_new: float = 0.9
    space: str = "se3_log"

    def __post_init__(self) -> None:
        if not 0.0 < self.weight_new <= 1.0:
            raise InvalidArgumentError(
                f"invalid target_filter.weight_new {self.weight_new!r}; valid: (0, 1]")
        check_choice("target_filter.space", self.space, SPACES)


class TargetFilterParams(NamedTuple):
    """The filter's constants as (1,) views of its buffer (flags 0 or 1): the new target's
    weight, whether it averages geodesically. In the buffer rather than scalars: an optional
    stage costs a controller that does not run it nothing (``optional_stages.py``)."""

    weight_new: np.ndarray
    geodesic: np.ndarray


class TargetFilterState(NamedTuple):
    """Everything ``target_filter_step`` reads and writes (world frame).

    Attributes:
        params: ``TargetFilterParams``.
        started: (1,) 1 once the filtered target exists.
        pos: (3,) filtered target position [m].
        quat: (4,) filtered target orientation (w, x, y, z), unit.
        xi_filtered, xi_target: (6,) twist coordinates (scratch).
        rel_pos, rel_quat: (3,), (4,) a relative pose (scratch of ``"geodesic"``).
    """

    params: TargetFilterParams
    started: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    xi_filtered: np.ndarray
    xi_target: np.ndarray
    rel_pos: np.ndarray
    rel_quat: np.ndarray


TARGET_FILTER_LAYOUT = Layout.of(TargetFilterState, dict(
    params=Layout.of(TargetFilterParams, slots("weight_new geodesic")), started=1, pos=3,
    quat=4, xi_filtered=6, xi_target=6, rel_pos=3, rel_quat=4), args=("buf", "n_joints"))
"""The target filter's part of the optional stages' buffer."""
unpack_target_filter = TARGET_FILTER_LAYOUT.unpacker("unpack_target_filter", __name__)


def make_target_filter_state(config: TargetFilterConfig, n_joints: int = 7) -> Packed:
    """``config``, packed (``unpack_target_filter`` names it; ``n_joints`` its scalars)."""
    packed = Packed(n_joints, np.zeros(TARGET_FILTER_LAYOUT.size()))
    par = unpack_target_filter(packed.buffer, n_joints)[0].params
    par.weight_new[0] = config.weight_new
    par.geodesic[0] = config.space == "geodesic"
    return packed


@njit(cache=True)
def _geodesic_step(pos_target, dw, dx, dy, dz, st) -> None:
    """T_f <- T_f Exp(w_new Log(T_f^-1 T_target))."""
    fw, fx, fy, fz = st.quat[0], st.quat[1], st.quat[2], st.quat[3]
    rw, rx, ry, rz = quat_mul(fw, -fx, -fy, -fz, dw, dx, dy, dz)  # R_f^T R_target
    p, q = st.rel_pos, st.rel_quat
    p[0], p[1], p[2] = quat_rotate(fw, -fx, -fy, -fz, pos_target[0] - st.pos[0],
                                   pos_target[1] - st.pos[1], pos_target[2] - st.pos[2])
    se3_log(p, rw, rx, ry, rz, st.xi_target)
    for i in range(6):
        st.xi_target[i] *= st.params.weight_new[0]
    se3_exp(st.xi_target, p, q)
    p0, p1, p2 = quat_rotate(fw, fx, fy, fz, p[0], p[1], p[2])
    st.pos[0] += p0
    st.pos[1] += p1
    st.pos[2] += p2
    w, x, y, z = quat_mul(fw, fx, fy, fz, q[0], q[1], q[2], q[3])
    n = math.sqrt(w * w + x * x + y * y + z * z)
    st.quat[0], st.quat[1], st.quat[2], st.quat[3] = w / n, x / n, y / n, z / n


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def target_filter_step(pos_target, quat_target, pos_ee, rot_ee, st) -> None:
    """One tick: move the filtered target (``st.pos``, ``st.quat``) toward the target. The
    first tick after ``reset`` starts from the TCP pose (``pos_ee``, ``rot_ee``)."""
    if st.started[0] == 0.0:
        w, x, y, z = matrix_to_quat(rot_ee)
        st.quat[0], st.quat[1], st.quat[2], st.quat[3] = w, x, y, z
        for i in range(3):
            st.pos[i] = pos_ee[i]
        st.started[0] = 1.0
    _, dw, dx, dy, dz = quat_normalized(quat_target)
    if st.params.geodesic[0] != 0.0:
        _geodesic_step(pos_target, dw, dx, dy, dz, st)
        return
    a = st.params.weight_new[0]
    se3_log(st.pos, st.quat[0], st.quat[1], st.quat[2], st.quat[3], st.xi_filtered)
    se3_log(pos_target, dw, dx, dy, dz, st.xi_target)
    for i in range(6):
        st.xi_filtered[i] = (1.0 - a) * st.xi_filtered[i] + a * st.xi_target[i]
    se3_exp(st.xi_filtered, st.pos, st.quat)


class TargetFilter:
    """The target-pose EMA as a typed object: ``state`` (``TargetFilterState``), ``step`` and
    ``reset``.

    Attributes:
        pos_target_world: Filtered target position (3,) [m].
        quat_target_world: Filtered target orientation (w, x, y, z).
    """

    def __init__(self, config: TargetFilterConfig, buffer: np.ndarray | None = None) -> None:
        """Create the filter; ``buffer`` (optional) is the float64 view to keep the state in
        (the controller's shared buffer of optional stages)."""
        self.config = config
        self.packed = make_target_filter_state(config)
        if buffer is not None:
            buffer[:] = self.packed.buffer
            self.packed = Packed(self.packed.scalars, buffer)
        self.state = unpack_target_filter(self.packed.buffer, self.packed.scalars)[0]
        self.pos_target_world, self.quat_target_world = self.state.pos, self.state.quat

    def reset(self) -> None:
        """Forget the filtered target (the next step starts from the TCP pose)."""
        for value in self.state[1:]:
            value.fill(0.0)

    def step(self, pos_target_world: np.ndarray, quat_target_world: np.ndarray,
             pos_ee_world: np.ndarray, rot_ee_world: np.ndarray) -> None:
        """Advance one tick toward the target (position [m], quaternion (w, x, y, z)), from
        the TCP pose (position [m], rotation (3, 3)) on the first tick after ``reset``."""
        f64 = np.float64
        target_filter_step(np.asarray(pos_target_world, f64), np.asarray(quat_target_world, f64),
                           np.asarray(pos_ee_world, f64),
                           np.ascontiguousarray(rot_ee_world, f64), self.state)
