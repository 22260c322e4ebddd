"""The optional stages, off in ``default`` and ``paper`` (the authors' released controller
uses them: ``authors_sim``, ``authors_real``): target filter (``target_filter.py``), wrench
observer (``wrench_observer.py``), payload model (``payload_model.py``) and joint-limit
repulsion (``joint_limits.py``); and the saturated-lift release (``saturation_release.py``,
issue 37 item 5: on in ``default``, off in the others).

Each is a stage like the others (config, named state, layout, step, class), with two
differences. Its constants live in its float64 buffer as (1,) views, not in a scalar
NamedTuple: a controller crosses its state into numba on every ``compute`` and numba
unboxes every scalar of it each time (measured: nested scalar tuples for these stages cost
microseconds per call). And the five share one packed buffer, one field of
``kernels.ControllerState`` (``opt``, scalars ``()``), whose header (``HEADER``) holds the
layout (the joint count, where each stage ends) and whether each runs: the tick reads a flag
(``observer_on``) and names a stage (``optional_observer``) only in the branch that runs it,
since every view costs its reference count. ``unpack_optional`` names all five (tests,
Python); the stage objects keep views of the same buffer, so snapshots
(``ImpactController.state_arrays``) cover them with no code of their own.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.joint_limits import (
    JointLimitConfig,
    JointLimitRepulsion,
    JointLimitState,
    make_joint_limit_state,
    unpack_joint_limits,
)
from impact_control.kernel_layout import Packed
from impact_control.payload_model import (
    PayloadModel,
    PayloadModelConfig,
    PayloadState,
    make_payload_state,
    unpack_payload,
)
from impact_control.saturation_release import (
    SaturationRelease,
    SaturationReleaseConfig,
    SaturationReleaseState,
    make_saturation_release_state,
    unpack_saturation_release,
)
from impact_control.stage_layout import Layout, slots
from impact_control.target_filter import (
    TargetFilter,
    TargetFilterConfig,
    TargetFilterState,
    make_target_filter_state,
    unpack_target_filter,
)
from impact_control.wrench_observer import (
    ObserverState,
    WrenchObserver,
    WrenchObserverConfig,
    make_observer_state,
    unpack_observer,
)


class OptionalHeader(NamedTuple):
    """The shared buffer's header, (1,) slots: the joint count; where the target filter, the
    observer, the payload model, the joint limits and the saturation release end (offsets
    into the buffer); whether the target filter, the observer, the joint limits and the
    saturation release run (0 or 1; the payload model's flag is the tick's,
    ``TickState.payload_feedforward``, since it depends on the mode)."""

    n_joints: np.ndarray
    target_filter_end: np.ndarray
    observer_end: np.ndarray
    payload_end: np.ndarray
    joint_limits_end: np.ndarray
    saturation_release_end: np.ndarray
    target_filter_on: np.ndarray
    observer_on: np.ndarray
    joint_limits_on: np.ndarray
    saturation_release_on: np.ndarray


HEADER_LAYOUT = Layout.of(OptionalHeader, slots(" ".join(OptionalHeader._fields)),
                          args=("buf",))
"""The header's slots, in ``OptionalHeader``'s order."""
HEADER = HEADER_LAYOUT.size()
"""Length of the shared buffer's header."""
_N, _TF_END, _OBS_END, _PAY_END, _JL_END, _SR_END = (
    HEADER_LAYOUT.offset(name) for name in OptionalHeader._fields[:6])
target_filter_on = HEADER_LAYOUT.flag_reader("target_filter_on", "target_filter_on", __name__)
observer_on = HEADER_LAYOUT.flag_reader("observer_on", "observer_on", __name__)
joint_limits_on = HEADER_LAYOUT.flag_reader("joint_limits_on", "joint_limits_on", __name__)
saturation_release_on = HEADER_LAYOUT.flag_reader("saturation_release_on",
                                                  "saturation_release_on", __name__)


class OptionalState(NamedTuple):
    """The five named states (views of the shared buffer)."""

    tf: TargetFilterState
    obs: ObserverState
    pay: PayloadState
    jl: JointLimitState
    sr: SaturationReleaseState


@njit(cache=True, inline="always")
def _header(buf):
    """(n_joints, tf_end, obs_end, pay_end, jl_end, sr_end) (``OptionalHeader``)."""
    return (int(buf[_N]), int(buf[_TF_END]), int(buf[_OBS_END]), int(buf[_PAY_END]),
            int(buf[_JL_END]), int(buf[_SR_END]))


@njit(cache=True, inline="always")
def optional_target_filter(buf):
    """The target filter's named state in the shared buffer."""
    n, e_tf, _, _, _, _ = _header(buf)
    return unpack_target_filter(buf[HEADER:e_tf], n)[0]


@njit(cache=True, inline="always")
def optional_observer(buf):
    """The observer's named state in the shared buffer."""
    n, e_tf, e_obs, _, _, _ = _header(buf)
    return unpack_observer(buf[e_tf:e_obs], n)[0]


@njit(cache=True, inline="always")
def optional_payload(buf):
    """The payload model's named state in the shared buffer."""
    n, _, e_obs, e_pay, _, _ = _header(buf)
    return unpack_payload(buf[e_obs:e_pay], n)[0]


@njit(cache=True, inline="always")
def optional_joint_limits(buf):
    """The joint-limit repulsion's named state in the shared buffer."""
    n, _, _, e_pay, e_jl, _ = _header(buf)
    return unpack_joint_limits(buf[e_pay:e_jl], n)[0]


@njit(cache=True, inline="always")
def optional_saturation_release(buf):
    """The saturation release's named state in the shared buffer."""
    n, _, _, _, e_jl, e_sr = _header(buf)
    return unpack_saturation_release(buf[e_jl:e_sr], n)[0]


@njit(cache=True)
def unpack_optional(buf, sc):  # noqa: ARG001 - sc is (): the layout is in the header
    """(``OptionalState`` as named views of ``buf``, the layout's length). The tick names
    each stage only on the ticks it runs (``optional_*``): a view costs its reference
    count."""
    state = OptionalState(optional_target_filter(buf), optional_observer(buf),
                          optional_payload(buf), optional_joint_limits(buf),
                          optional_saturation_release(buf))
    return state, _header(buf)[5]


class OptionalStages:
    """The five stage objects over one buffer (``packed``, ``kernels.ControllerState.opt``).

    Attributes:
        target_filter: ``TargetFilter``.
        observer: ``WrenchObserver``.
        payload: ``PayloadModel``.
        joint_limits: ``JointLimitRepulsion``.
        saturation_release: ``SaturationRelease``.
    """

    def __init__(self, target_filter: TargetFilterConfig, observer: WrenchObserverConfig,
                 payload: PayloadModelConfig, joint_limits: JointLimitConfig, dt_s: float,
                 n_joints: int = 7,
                 saturation_release: SaturationReleaseConfig | None = None) -> None:
        """Build the five stages from their configs at control period ``dt_s`` [s]
        (``saturation_release`` None: off, as the other four stages' defaults are)."""
        saturation_release = saturation_release or SaturationReleaseConfig(enabled=False)
        sizes = (make_target_filter_state(target_filter, n_joints).buffer.shape[0],
                 make_observer_state(observer, n_joints).buffer.shape[0],
                 make_payload_state(payload, dt_s, n_joints).buffer.shape[0],
                 make_joint_limit_state(joint_limits).buffer.shape[0],
                 make_saturation_release_state(saturation_release, dt_s,
                                               n_joints).buffer.shape[0])
        ends = (HEADER + np.cumsum(sizes)).tolist()
        buf = np.zeros(ends[-1])
        flags = (target_filter.enabled, observer.enabled, joint_limits.torque_max_nm > 0.0,
                 saturation_release.enabled)
        for name, value in zip(OptionalHeader._fields, (n_joints, *ends, *flags), strict=True):
            buf[HEADER_LAYOUT.offset(name)] = value
        views = [buf[a:b] for a, b in zip([HEADER, *ends[:-1]], ends, strict=True)]
        self.target_filter = TargetFilter(target_filter, buffer=views[0])
        self.observer = WrenchObserver(observer, n_joints, buffer=views[1])
        self.payload = PayloadModel(payload, dt_s, buffer=views[2])
        self.joint_limits = JointLimitRepulsion(joint_limits, buffer=views[3])
        self.saturation_release = SaturationRelease(saturation_release, dt_s, n_joints,
                                                    buffer=views[4])
        self.packed = Packed((), buf)

    def reset(self) -> None:
        """Reset the stages that carry state from tick to tick (the joint limits do not)."""
        self.target_filter.reset()
        self.observer.reset()
        self.payload.reset()
        self.saturation_release.reset()
