"""Joint-limit repulsion: a joint torque pushing away from a limit the joint comes within
``range_rad`` of (the authors' released controller, ``get_joint_limit_torque``; off in
``default`` and ``paper``). Per joint, with d_lo = q - q_min and d_hi = q_max - q:

    tau = torque_max (clip((r - d_lo) / r, 0, 1) if d_lo < r)  -  torque_max (clip((r - d_hi)
          / r, 0, 1) if d_hi < r)

i.e. 0 farther than r from both limits, rising linearly to ``torque_max_nm`` at the limit
and beyond. It is added to the command as it is: not projected into the null space, not
clamped with the null-space torque (as the authors add it). The limits default to the FR3's
(franka_description ``joint_limits.yaml``, ../shared/reference/fr3.md; our MJCF's ranges).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError
from impact_control.kernel_layout import Packed
from impact_control.stage_layout import N_JOINTS, Layout, slots
from impact_control.validation import check_len, check_positive

FR3_Q_MIN_RAD = (-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159)
"""FR3 lower joint limits [rad] (franka_description, ``fr3_hand.xml``)."""
FR3_Q_MAX_RAD = (2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159)
"""FR3 upper joint limits [rad]."""


@dataclass(frozen=True)
class JointLimitConfig:
    """Joint-limit repulsion.

    Attributes:
        torque_max_nm: Repulsion at the limit [Nm] (0: off, the default; the authors: 5).
        range_rad: Distance from a limit within which it acts [rad] (the authors: 0.3).
        q_min_rad, q_max_rad: The joint limits [rad] (default: the FR3's).
    """

    torque_max_nm: float = 0.0
    range_rad: float = 0.3
    q_min_rad: tuple[float, ...] = FR3_Q_MIN_RAD
    q_max_rad: tuple[float, ...] = FR3_Q_MAX_RAD

    def __post_init__(self) -> None:
        check_positive("joint_limits.torque_max_nm", self.torque_max_nm, allow_zero=True)
        check_positive("joint_limits.range_rad", self.range_rad)
        for name in ("q_min_rad", "q_max_rad"):
            values = tuple(float(v) for v in getattr(self, name))
            check_len(name, values, 7)
            object.__setattr__(self, name, values)
        if any(not lo < hi for lo, hi in zip(self.q_min_rad, self.q_max_rad, strict=True)):
            raise InvalidArgumentError(
                f"invalid joint limits {self.q_min_rad!r}, {self.q_max_rad!r}; valid: "
                "q_min_rad < q_max_rad on every joint")


class JointLimitParams(NamedTuple):
    """The torque at the limit [Nm] and the range [rad]: (1,) views of its buffer (no
    crossing cost, ``optional_stages.py``)."""

    torque_max_nm: np.ndarray
    range_rad: np.ndarray


class JointLimitState(NamedTuple):
    """Everything ``joint_limit_torque`` reads and writes.

    Attributes:
        params: ``JointLimitParams``.
        q_min, q_max: (n,) the limits [rad].
        tau: (n,) the repulsion of the last tick [Nm].
    """

    params: JointLimitParams
    q_min: np.ndarray
    q_max: np.ndarray
    tau: np.ndarray


JOINT_LIMITS_LAYOUT = Layout.of(JointLimitState, dict(
    params=Layout.of(JointLimitParams, slots("torque_max_nm range_rad")), q_min=N_JOINTS,
    q_max=N_JOINTS, tau=N_JOINTS), dims={"n": "n_joints"}, args=("buf", "n_joints"))
"""The joint-limit repulsion's part of the optional stages' buffer."""
unpack_joint_limits = JOINT_LIMITS_LAYOUT.unpacker("unpack_joint_limits", __name__)


def make_joint_limit_state(config: JointLimitConfig) -> Packed:
    """``config``, packed (``unpack_joint_limits`` names it; its joint count the scalars)."""
    n = len(config.q_min_rad)
    packed = Packed(n, np.zeros(JOINT_LIMITS_LAYOUT.size_for(n)))
    st = unpack_joint_limits(packed.buffer, n)[0]
    st.params.torque_max_nm[0], st.params.range_rad[0] = config.torque_max_nm, config.range_rad
    st.q_min[:], st.q_max[:] = config.q_min_rad, config.q_max_rad
    return packed


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def joint_limit_torque(q, st) -> None:
    """st.tau = the repulsion at ``q`` (module docstring)."""
    par = st.params
    r, m = par.range_rad[0], par.torque_max_nm[0]
    for j in range(st.tau.shape[0]):
        t = 0.0
        d_lo = q[j] - st.q_min[j]
        d_hi = st.q_max[j] - q[j]
        if d_lo < r:
            t += m * min(max((r - d_lo) / r, 0.0), 1.0)
        if d_hi < r:
            t -= m * min(max((r - d_hi) / r, 0.0), 1.0)
        st.tau[j] = t


class JointLimitRepulsion:
    """The repulsion as a typed object: ``state`` (``JointLimitState``) and ``torque``.

    Attributes:
        tau: The repulsion of the last call (7,) [Nm].
    """

    def __init__(self, config: JointLimitConfig, buffer: np.ndarray | None = None) -> None:
        """Create it; ``buffer`` (optional) is the float64 view to keep the state in (the
        controller's shared buffer of optional stages)."""
        self.config = config
        self.packed = make_joint_limit_state(config)
        if buffer is not None:
            buffer[:] = self.packed.buffer
            self.packed = Packed(self.packed.scalars, buffer)
        self.state = unpack_joint_limits(self.packed.buffer, self.packed.scalars)[0]
        self.tau = self.state.tau

    def torque(self, q: np.ndarray) -> np.ndarray:
        """The repulsion at joint positions ``q`` (7,) [rad], [Nm]."""
        joint_limit_torque(np.asarray(q, dtype=np.float64), self.state)
        return self.tau
