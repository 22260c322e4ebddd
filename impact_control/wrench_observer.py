"""Wrench observer with the low-pass after the solve (the authors' released controller; off in
``default`` and ``paper``, which run ``estimators.py``). When enabled it takes the residual
estimator's place in the tick (``estimator.kind`` must be "residual"):

    w_raw = (J J^T + lambda^2 I)^-1 J (tau_meas - C dq - g)      no M ddq term, no friction
    w_f  <- (1 - alpha) w_f + alpha w_raw                           per tick, in ``frame``
    |w_f force| <= force_norm_max_n,  |w_f torque| <= torque_norm_max_nm   (w_f itself clamped)

For the first ``warmup_ticks`` ticks after ``reset`` the output is 0 and nothing is updated
(the authors' ``observer_warmup_cycles``). lambda is the estimator's (``EstimatorConfig.
regularization``: the tick's one solve serves both). ``frame="tcp"`` filters and clamps the
TCP-frame wrench (their local Jacobian); the output ``wrench`` is in the world frame either
way. Sign: the wrench the robot applies to the environment (docs/controller.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.kernel_layout import Packed
from impact_control.kernel_math import clamp_norm3, mat_vec, rotate, rotate_back
from impact_control.stage_layout import N_JOINTS, Layout, slots
from impact_control.validation import FRAMES, check_optional_positive


@dataclass(frozen=True)
class WrenchObserverConfig:
    """The observer with the low-pass after the solve.

    Attributes:
        enabled: Use it instead of the estimator (default False).
        lowpass_alpha_per_tick: Per-tick gain of the low-pass on the solved wrench, in (0, 1]
            (the authors: 0.02).
        force_norm_max_n: Bound on the filtered force's norm [N] (None: none; the authors:
            120 in simulation, 80 on the robot).
        torque_norm_max_nm: Bound on the filtered torque's norm [Nm] (None; 50 / 15).
        warmup_ticks: Ticks after ``reset`` whose output is 0 (the authors: 100).
        frame: ``"tcp"`` (the authors) or ``"world"``: the frame the filter and the clamps
            act in.
    """

    enabled: bool = False
    lowpass_alpha_per_tick: float = 0.02
    force_norm_max_n: float | None = None
    torque_norm_max_nm: float | None = None
    warmup_ticks: int = 100
    frame: str = "tcp"

    def __post_init__(self) -> None:
        if not 0.0 < self.lowpass_alpha_per_tick <= 1.0:
            raise InvalidArgumentError(
                f"invalid observer.lowpass_alpha_per_tick {self.lowpass_alpha_per_tick!r}; "
                "valid: (0, 1]")
        check_optional_positive("force_norm_max_n", self.force_norm_max_n)
        check_optional_positive("torque_norm_max_nm", self.torque_norm_max_nm)
        if isinstance(self.warmup_ticks, bool) or not isinstance(self.warmup_ticks, int) \
                or self.warmup_ticks < 0:
            raise InvalidArgumentError(
                f"invalid observer.warmup_ticks {self.warmup_ticks!r}; valid: an int >= 0")
        check_choice("observer.frame", self.frame, FRAMES)


class ObserverParams(NamedTuple):
    """The observer's constants (``WrenchObserverConfig``; inf: no clamp) as (1,) views of
    its buffer (flags 0 or 1; no crossing cost, ``optional_stages.py``)."""

    alpha: np.ndarray
    force_norm_max_n: np.ndarray
    torque_norm_max_nm: np.ndarray
    warmup_ticks: np.ndarray
    tcp_frame: np.ndarray


class ObserverState(NamedTuple):
    """Everything ``observer_update`` reads and writes.

    Attributes:
        params: ``ObserverParams``.
        ticks: (1,) ticks since ``reset``, counted up to ``warmup_ticks``.
        tau_residual: (n,) tau_meas - C dq - g [Nm].
        wrench_raw: (6,) the solved wrench of this tick, world frame [N, Nm].
        wrench_filtered: (6,) w_f in the observer's frame [N, Nm].
        wrench: (6,) w_f in the world frame [N, Nm]: the output.
        scratch: (6,) this tick's solve in the observer's frame.
    """

    params: ObserverParams
    ticks: np.ndarray
    tau_residual: np.ndarray
    wrench_raw: np.ndarray
    wrench_filtered: np.ndarray
    wrench: np.ndarray
    scratch: np.ndarray


OBSERVER_LAYOUT = Layout.of(ObserverState, dict(
    params=Layout.of(ObserverParams, slots(
        "alpha force_norm_max_n torque_norm_max_nm warmup_ticks tcp_frame")),
    ticks=1, tau_residual=N_JOINTS, wrench_raw=6, wrench_filtered=6, wrench=6, scratch=6),
    dims={"n": "n_joints"}, args=("buf", "n_joints"))
"""The wrench observer's part of the optional stages' buffer."""
unpack_observer = OBSERVER_LAYOUT.unpacker("unpack_observer", __name__)


def make_observer_state(config: WrenchObserverConfig, n_joints: int = 7) -> Packed:
    """``config`` for ``n_joints`` joints, packed (``unpack_observer`` names it)."""
    packed = Packed(n_joints, np.zeros(OBSERVER_LAYOUT.size_for(n_joints)))
    par, inf = unpack_observer(packed.buffer, n_joints)[0].params, float("inf")
    par.alpha[0] = config.lowpass_alpha_per_tick
    par.force_norm_max_n[0] = (inf if config.force_norm_max_n is None
                               else config.force_norm_max_n)
    par.torque_norm_max_nm[0] = (inf if config.torque_norm_max_nm is None
                                 else config.torque_norm_max_nm)
    par.warmup_ticks[0], par.tcp_frame[0] = config.warmup_ticks, config.frame == "tcp"
    return packed


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def observer_update(dq, tau_meas, dyn, wrench_map, st) -> None:
    """One tick (module docstring); ``wrench_map`` = (J J^T + lambda^2 I)^-1 J (6, n)."""
    par = st.params
    if st.ticks[0] < par.warmup_ticks[0]:
        st.ticks[0] += 1.0
        for i in range(6):
            st.wrench_raw[i] = 0.0
            st.wrench_filtered[i] = 0.0
            st.wrench[i] = 0.0
        return
    _, _, cor, grav, _, rot = dyn
    tau_res, w_f, s = st.tau_residual, st.wrench_filtered, st.scratch
    mat_vec(cor, dq, tau_res)  # scratch: C dq
    for j in range(tau_res.shape[0]):
        tau_res[j] = tau_meas[j] - tau_res[j] - grav[j]
    mat_vec(wrench_map, tau_res, st.wrench_raw)
    tcp, a = par.tcp_frame[0] != 0.0, par.alpha[0]
    if tcp:
        rotate_back(rot, st.wrench_raw, s)
    else:
        for i in range(6):
            s[i] = st.wrench_raw[i]
    for i in range(6):
        w_f[i] = (1.0 - a) * w_f[i] + a * s[i]
    clamp_norm3(w_f, 0, par.force_norm_max_n[0])
    clamp_norm3(w_f, 3, par.torque_norm_max_nm[0])
    if tcp:
        rotate(rot, w_f, st.wrench)
    else:
        for i in range(6):
            st.wrench[i] = w_f[i]


class WrenchObserver:
    """The observer as a typed object: ``state`` (``ObserverState``), ``update``, ``reset``.

    Attributes:
        wrench_world: The filtered estimate (6,) [N, Nm], world frame.
    """

    def __init__(self, config: WrenchObserverConfig, n_joints: int = 7,
                 buffer: np.ndarray | None = None) -> None:
        """Create the observer; ``buffer`` (optional) is the float64 view to keep the state
        in (the controller's shared buffer of optional stages)."""
        self.config = config
        self.packed = make_observer_state(config, n_joints)
        if buffer is not None:
            buffer[:] = self.packed.buffer
            self.packed = Packed(self.packed.scalars, buffer)
        self.state = unpack_observer(self.packed.buffer, self.packed.scalars)[0]
        self.wrench_world = self.state.wrench

    def reset(self) -> None:
        """Zero the filter and restart the warm-up."""
        for value in self.state[1:]:
            value.fill(0.0)

    def update(self, dq: np.ndarray, tau_meas: np.ndarray, dyn: object,
               wrench_map: np.ndarray) -> np.ndarray:
        """Advance one tick; ``dyn`` is a ``DynamicsArrays`` at (q, dq). Returns the world
        wrench (6,) [N, Nm]."""
        f64 = np.float64
        observer_update(np.asarray(dq, f64), np.asarray(tau_meas, f64), dyn,
                        np.ascontiguousarray(wrench_map, f64), self.state)
        return self.wrench_world
