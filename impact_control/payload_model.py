"""Scalar payload ("weight") model along the TCP z axis and its feedforward (the authors'
released controller, ``cereb_weight_model_enable``; off in ``default`` and ``paper``).

Per tick, with f = -w_hat_z and s = w_slow in the TCP frame (the TCP's z axis is the
approach direction, pointing down in a top grasp, so a held load of mass m gives f = m g):

1. measured weight W = max(0, f); slow-wrench rate |s - s_prev| / dt (6-D norm, N/s and
   Nm/s mixed, as coded);
2. holding while W >= ``hold_on_n``, re-tested every tick (no hysteresis), forced off while
   the gripper is commanded open (opening command > ``gripper_open_above``, 0 closed ... 1
   open) when ``gripper_holdoff``;
3. the hold's clock: 0 when not holding, + dt per holding tick (the first holding tick
   reads dt); on the first tick it reaches ``feedforward_holdoff_s`` the estimate E is set to
   0 if W < ``reset_ratio`` E;
4. surprise |W - E| low-passed with ``surprise_lowpass_alpha`` per tick while holding, 0
   otherwise;
5. E += ``learning_rate`` (max(0, -s_z) - E), clamped to [0, ``estimate_max_n``], only while
   holding, the low-passed surprise >= ``surprise_threshold_n``, W >= ``update_min_force_n``
   and the rate <= ``slow_rate_max``;
6. feedforward along TCP z, only while holding and the clock has reached the hold-off:
   -E (``feedforward="estimate"``, the authors' robot) or s_z (``"slow_wrench"``, their
   simulation); 0 otherwise. In the world frame: (R_ee e_z f_ff, 0).

The gripper command is an input of the stage (``gripper_cmd``, this package's convention:
-1 open ... +1 closed, opening = (1 - cmd) / 2), written by the caller before the tick
(``ImpactController.compute(gripper_cmd=...)``, ``ClosedLoop.run``); +1 after ``reset``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.kernel_layout import Packed
from impact_control.stage_layout import Layout, slots
from impact_control.validation import check_positive, checked_gripper_command

FEEDFORWARDS: tuple[str, ...] = ("estimate", "slow_wrench")
"""Valid ``PayloadModelConfig.feedforward`` values."""


@dataclass(frozen=True)
class PayloadModelConfig:
    """The scalar payload model (module docstring; the authors' values as defaults).

    Attributes:
        enabled: Run it, and feed forward its output instead of the internal model's
            (default False).
        hold_on_n: Measured weight at which a hold is detected [N].
        update_min_force_n: Smallest measured weight at which the estimate learns [N].
        feedforward_holdoff_s: Hold time before the feedforward starts and the reset test
            runs [s].
        reset_ratio: The estimate is reset to 0 if the weight measured at the hold-off is
            below this fraction of it.
        surprise_lowpass_alpha: Per-tick gain of the surprise low-pass, in (0, 1].
        surprise_threshold_n: Low-passed surprise at which the estimate learns [N].
        learning_rate: Per-tick step of the estimate toward the slow wrench, in (0, 1].
        estimate_max_n: Upper clamp of the estimate [N].
        slow_rate_max: Largest |d w_slow / dt| (6-D norm) at which the estimate learns.
        gripper_holdoff: Force the hold off while the gripper is commanded open.
        gripper_open_above: Opening command (0 closed ... 1 open) above which it is "open".
        feedforward: ``"estimate"`` (-E along TCP z) or ``"slow_wrench"`` (w_slow's TCP z).
    """

    enabled: bool = False
    hold_on_n: float = 2.0
    update_min_force_n: float = 1.0
    feedforward_holdoff_s: float = 0.5
    reset_ratio: float = 0.8
    surprise_lowpass_alpha: float = 1e-4
    surprise_threshold_n: float = 5.0
    learning_rate: float = 0.01
    estimate_max_n: float = 100.0
    slow_rate_max: float = 0.2
    gripper_holdoff: bool = True
    gripper_open_above: float = 0.1
    feedforward: str = "estimate"

    def __post_init__(self) -> None:
        for name in ("hold_on_n", "update_min_force_n", "feedforward_holdoff_s",
                     "reset_ratio", "surprise_threshold_n", "estimate_max_n",
                     "slow_rate_max"):
            check_positive(name, getattr(self, name), allow_zero=True)
        for name in ("surprise_lowpass_alpha", "learning_rate", "gripper_open_above"):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise InvalidArgumentError(f"invalid payload.{name} {value!r}; valid: (0, 1]")
        check_choice("payload.feedforward", self.feedforward, FEEDFORWARDS)


class PayloadParams(NamedTuple):
    """The model's constants (``PayloadModelConfig``; ``dt_s`` the control period [s]) as
    (1,) views of its buffer (flags 0 or 1; no crossing cost, ``optional_stages.py``)."""

    hold_on_n: np.ndarray
    update_min_force_n: np.ndarray
    holdoff_s: np.ndarray
    reset_ratio: np.ndarray
    surprise_alpha: np.ndarray
    surprise_threshold_n: np.ndarray
    learning_rate: np.ndarray
    estimate_max_n: np.ndarray
    slow_rate_max: np.ndarray
    gripper_holdoff: np.ndarray
    gripper_open_above: np.ndarray
    feedforward_estimate: np.ndarray
    dt_s: np.ndarray


class PayloadState(NamedTuple):
    """Everything ``payload_step`` reads and writes (scalars as (1,) arrays).

    Attributes:
        params: ``PayloadParams``.
        gripper_cmd: The gripper command (-1 open ... +1 closed), written by the caller.
        holding: 1 while a hold is detected.
        hold_time_s: The hold's clock [s].
        reset_checked: 1 once this hold's reset test ran.
        estimate_n: The payload estimate E [N].
        surprise_n: |W - E| of this tick [N]; surprise_filtered_n: its low-pass [N].
        weight_n: The measured weight W [N].
        slow_rate: |d w_slow / dt| of this tick (6-D norm).
        feedforward_n: The force fed forward along TCP z [N].
        slow_prev_tcp: (6,) w_slow in the TCP frame at the previous tick.
        slow_tcp: (6,) w_slow in the TCP frame (scratch).
        wrench_ff: (6,) the feedforward wrench, world frame [N, Nm].
    """

    params: PayloadParams
    gripper_cmd: np.ndarray
    holding: np.ndarray
    hold_time_s: np.ndarray
    reset_checked: np.ndarray
    estimate_n: np.ndarray
    surprise_n: np.ndarray
    surprise_filtered_n: np.ndarray
    weight_n: np.ndarray
    slow_rate: np.ndarray
    feedforward_n: np.ndarray
    slow_prev_tcp: np.ndarray
    slow_tcp: np.ndarray
    wrench_ff: np.ndarray


PAYLOAD_LAYOUT = Layout.of(PayloadState, dict(
    params=Layout.of(PayloadParams, slots(
        "hold_on_n update_min_force_n holdoff_s reset_ratio surprise_alpha "
        "surprise_threshold_n learning_rate estimate_max_n slow_rate_max gripper_holdoff "
        "gripper_open_above feedforward_estimate dt_s")),
    **slots("gripper_cmd holding hold_time_s reset_checked estimate_n surprise_n "
            "surprise_filtered_n weight_n slow_rate feedforward_n"),
    slow_prev_tcp=6, slow_tcp=6, wrench_ff=6), args=("buf", "n_joints"))
"""The payload model's part of the optional stages' buffer."""
unpack_payload = PAYLOAD_LAYOUT.unpacker("unpack_payload", __name__)


def make_payload_state(config: PayloadModelConfig, dt_s: float, n_joints: int = 7) -> Packed:
    """``config`` at control period ``dt_s`` [s], packed (``unpack_payload`` names it)."""
    c = config
    packed = Packed(n_joints, np.zeros(PAYLOAD_LAYOUT.size()))
    st = unpack_payload(packed.buffer, n_joints)[0]
    values = (c.hold_on_n, c.update_min_force_n, c.feedforward_holdoff_s,
              c.reset_ratio, c.surprise_lowpass_alpha, c.surprise_threshold_n,
              c.learning_rate, c.estimate_max_n, c.slow_rate_max, c.gripper_holdoff,
              c.gripper_open_above, c.feedforward == "estimate", dt_s)
    for view, value in zip(st.params, values, strict=True):
        view[0] = float(value)
    st.gripper_cmd[0] = 1.0
    return packed


@njit(cache=True, inline="always")
def _hold(weight, st) -> bool:
    """Steps 2-3: hold detection, the hold's clock and the reset test; returns holding."""
    par = st.params
    was = st.holding[0] != 0.0
    holding = weight >= par.hold_on_n[0]
    opening = 0.5 * (1.0 - st.gripper_cmd[0])  # 0 closed ... 1 open (theirs)
    if par.gripper_holdoff[0] != 0.0 and opening > par.gripper_open_above[0]:
        holding = False
    if holding:
        if not was:
            st.hold_time_s[0] = 0.0
            st.reset_checked[0] = 0.0
        st.hold_time_s[0] += par.dt_s[0]
    else:
        st.hold_time_s[0] = 0.0
        st.reset_checked[0] = 0.0
    st.holding[0] = 1.0 if holding else 0.0
    if holding and st.reset_checked[0] == 0.0 and st.hold_time_s[0] >= par.holdoff_s[0]:
        if weight < par.reset_ratio[0] * st.estimate_n[0]:
            st.estimate_n[0] = 0.0
        st.reset_checked[0] = 1.0
    return holding


@njit(cache=True, inline="always")
def _learn(weight, holding, st) -> None:
    """Steps 4-5: the surprise low-pass and the estimate's update."""
    par = st.params
    if holding:
        st.surprise_n[0] = abs(weight - st.estimate_n[0])
        st.surprise_filtered_n[0] = ((1.0 - par.surprise_alpha[0]) * st.surprise_filtered_n[0]
                                     + par.surprise_alpha[0] * st.surprise_n[0])
    else:
        st.surprise_n[0] = 0.0
        st.surprise_filtered_n[0] = 0.0
    if (st.slow_rate[0] <= par.slow_rate_max[0] and weight >= par.update_min_force_n[0]
            and st.surprise_filtered_n[0] >= par.surprise_threshold_n[0] and holding):
        target = max(0.0, -st.slow_tcp[2])
        e = st.estimate_n[0] + par.learning_rate[0] * (target - st.estimate_n[0])
        st.estimate_n[0] = min(max(e, 0.0), par.estimate_max_n[0])


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def payload_step(wrench_ext, wrench_slow, rot_ee, st) -> None:
    """One tick (module docstring): ``wrench_ext`` and ``wrench_slow`` (6,) world frame,
    ``rot_ee`` the TCP rotation (world from TCP); writes ``st.wrench_ff`` (world)."""
    par, s, prev = st.params, st.slow_tcp, st.slow_prev_tcp
    for i in range(3):  # s = w_slow in the TCP frame
        s[i] = rot_ee[0, i] * wrench_slow[0] + rot_ee[1, i] * wrench_slow[1] \
            + rot_ee[2, i] * wrench_slow[2]
        s[3 + i] = rot_ee[0, i] * wrench_slow[3] + rot_ee[1, i] * wrench_slow[4] \
            + rot_ee[2, i] * wrench_slow[5]
    rate_sq = 0.0
    for i in range(6):
        r = (s[i] - prev[i]) / par.dt_s[0]
        rate_sq += r * r
    st.slow_rate[0] = math.sqrt(rate_sq)
    f_z = rot_ee[0, 2] * wrench_ext[0] + rot_ee[1, 2] * wrench_ext[1] \
        + rot_ee[2, 2] * wrench_ext[2]
    weight = max(0.0, -f_z)
    st.weight_n[0] = weight
    holding = _hold(weight, st)
    _learn(weight, holding, st)
    for i in range(6):
        prev[i] = s[i]
    ff = 0.0
    if holding and st.hold_time_s[0] >= par.holdoff_s[0]:
        ff = -st.estimate_n[0] if par.feedforward_estimate[0] != 0.0 else s[2]
    st.feedforward_n[0] = ff
    for i in range(3):
        st.wrench_ff[i] = rot_ee[i, 2] * ff
        st.wrench_ff[3 + i] = 0.0


class PayloadModel:
    """The payload model as a typed object: ``state`` (``PayloadState``), ``step``, ``reset``.

    Attributes:
        wrench_ff_world: The feedforward of the last tick (6,) [N, Nm], world frame.
    """

    def __init__(self, config: PayloadModelConfig, dt_s: float,
                 buffer: np.ndarray | None = None) -> None:
        """Create the model for control period ``dt_s`` [s]; ``buffer`` (optional) is the
        float64 view to keep the state in (the controller's shared buffer of optional
        stages)."""
        self.config = config
        self.packed = make_payload_state(config, dt_s)
        if buffer is not None:
            buffer[:] = self.packed.buffer
            self.packed = Packed(self.packed.scalars, buffer)
        self.state = unpack_payload(self.packed.buffer, self.packed.scalars)[0]
        self.wrench_ff_world = self.state.wrench_ff

    @property
    def holding(self) -> bool:
        """Whether a hold was detected on the last tick."""
        return bool(self.state.holding[0] != 0.0)

    @property
    def estimate_n(self) -> float:
        """The payload estimate E [N]."""
        return float(self.state.estimate_n[0])

    def set_gripper_command(self, gripper_cmd: float) -> None:
        """The gripper command for the next ticks (-1 open ... +1 closed)."""
        self.state.gripper_cmd[0] = checked_gripper_command(gripper_cmd)

    def reset(self) -> None:
        """Forget the hold, the estimate and the surprise; gripper command +1 (closed)."""
        for value in self.state[1:]:
            value.fill(0.0)
        self.state.gripper_cmd[0] = 1.0

    def step(self, wrench_ext_world: np.ndarray, wrench_slow_world: np.ndarray,
             rot_ee_world: np.ndarray) -> np.ndarray:
        """Advance one tick; returns the feedforward wrench (6,) [N, Nm], world frame."""
        f64 = np.float64
        payload_step(np.asarray(wrench_ext_world, f64), np.asarray(wrench_slow_world, f64),
                     np.ascontiguousarray(rot_ee_world, f64), self.state)
        return self.wrench_ff_world
