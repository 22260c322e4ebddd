"""Torque saturation and torque-rate limiting (FR3 bounds; libfranka's ``limitRate`` exactly).

libfranka (``rate_limiting.h``, ``command_saturation.cpp``) limits the torque rate of the
command without gravity as ``last + clamp((cmd - last) / kDeltaT, -max, max) * kDeltaT`` with
``kDeltaT = 1e-3`` s and ``kMaxTorqueRate = 1000 - kLimitEps = 999.999`` Nm/s; the robot's own
``controller_torque_discontinuity`` reflex trips at 1000 Nm/s. ``rate_limiter="libfranka"``
reproduces that operation for operation (bit for bit, tests/control/test_limits.py) and is the
default since 2026-11-26; ``"per_tick_clip"`` (``last + clip(cmd - last, +-rate * dt)``, at
1000 Nm/s) is the limiter the tables before that date were computed with, and the one for a
controller period other than 1 ms. docs/controller.md, "Limits on the torque interface".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.kernel_layout import Packed
from impact_control.stage_layout import N_JOINTS, Layout
from impact_control.validation import check_len, check_positive

LIBFRANKA_DELTA_T_S = 1e-3
"""libfranka's ``kDeltaT`` [s]: the period its ``limitRate`` divides and multiplies by."""
LIBFRANKA_MAX_TORQUE_RATE_NM_PER_S = 1000.0 - 1e-3
"""libfranka's ``kMaxTorqueRate`` = 1000 - ``kLimitEps`` [Nm/s] (999.999, every joint)."""
FR3_TORQUE_RATE_REFLEX_NM_PER_S = 1000.0
"""The torque rate [Nm/s] at which the FR3's ``controller_torque_discontinuity`` reflex trips."""
RATE_LIMITERS: tuple[str, ...] = ("per_tick_clip", "libfranka")
"""Valid ``LimitsConfig.rate_limiter`` values."""


@dataclass(frozen=True)
class LimitsConfig:
    """Torque saturation and torque-rate limits (FR3 / libfranka).

    Attributes:
        torque_max_nm: Symmetric per-joint torque bound [Nm] (FR3: 87 x4, 12 x3).
        torque_rate_max_nm_per_s: Bound on |d tau / dt| of the command without gravity
            [Nm/s] (libfranka's ``LIBFRANKA_MAX_TORQUE_RATE_NM_PER_S`` = 999.999; the robot's
            reflex trips at 1000).
        rate_limiter: ``"libfranka"`` (default): libfranka's ``limitRate`` operation for
            operation (requires the controller's dt_s = 1 ms, libfranka's ``kDeltaT``);
            ``"per_tick_clip"``: last + clip(cmd - last, +-rate * dt), any dt.
        rate_limit_includes_gravity: Rate-limit the whole command, gravity included, against
            the previous rate-limited command (the authors' simulation, whose controller
            compensates gravity itself: ``authors_sim``); False (default): the command
            without gravity, as libfranka and the robot's ``tau_J_d``. Only with
            ``"per_tick_clip"``.
    """

    torque_max_nm: tuple[float, ...] = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
    torque_rate_max_nm_per_s: float = LIBFRANKA_MAX_TORQUE_RATE_NM_PER_S
    rate_limiter: str = "libfranka"
    rate_limit_includes_gravity: bool = False

    def __post_init__(self) -> None:
        values = tuple(float(v) for v in self.torque_max_nm)
        check_len("torque_max_nm", values, 7)
        check_positive("torque_max_nm", values)
        object.__setattr__(self, "torque_max_nm", values)
        check_positive("torque_rate_max_nm_per_s", self.torque_rate_max_nm_per_s)
        check_choice("limits.rate_limiter", self.rate_limiter, RATE_LIMITERS)
        if self.rate_limit_includes_gravity and self.rate_limiter != "per_tick_clip":
            raise InvalidArgumentError(
                "invalid limits.rate_limit_includes_gravity True with rate_limiter "
                f"{self.rate_limiter!r}; valid: rate_limiter='per_tick_clip' (libfranka limits "
                "the command without gravity)")


def libfranka_limits() -> LimitsConfig:
    """The limits exactly as libfranka enforces them on an FR3's torque interface (the
    defaults since 2026-11-26, spelled out)."""
    return LimitsConfig(torque_rate_max_nm_per_s=LIBFRANKA_MAX_TORQUE_RATE_NM_PER_S,
                        rate_limiter="libfranka")


def beyond_hardware_limits(limits: LimitsConfig) -> list[str]:
    """The settings of ``limits`` above the FR3's hardware limits (empty when within)."""
    fr3 = LimitsConfig()
    above = [f"limits.torque_max_nm[{i}]={v:g} > {hw:g} Nm"
             for i, (v, hw) in enumerate(zip(limits.torque_max_nm, fr3.torque_max_nm,
                                             strict=True)) if v > hw]
    if limits.torque_rate_max_nm_per_s > FR3_TORQUE_RATE_REFLEX_NM_PER_S:
        above.append(f"limits.torque_rate_max_nm_per_s={limits.torque_rate_max_nm_per_s:g} > "
                     f"{FR3_TORQUE_RATE_REFLEX_NM_PER_S:g} Nm/s")
    return above


# ------------------------------------------------------------------ named state and kernel
class LimiterParams(NamedTuple):
    """The limiter's constants (``make_limiter_state``).

    Attributes:
        max_delta_nm: Largest change of the command without gravity per tick [Nm] (the
            ``"clip"`` limiter).
        libfranka: Whether libfranka's ``limitRate`` is used instead of the per-tick clip.
        max_rate_nm_per_s: Its rate bound [Nm/s].
        tau_max: Saturation per joint (n,) [Nm].
    """

    max_delta_nm: float
    libfranka: bool
    max_rate_nm_per_s: float
    tau_max: np.ndarray


class LimiterState(NamedTuple):
    """Everything ``torque_limiter`` reads and writes.

    Attributes:
        params: ``LimiterParams``.
        last_no_gravity: The previous output minus gravity (n,) [Nm]: what the rate bound is
            measured from (libfranka's last ``tau_J_d``).
        output: The command of the last tick (n,) [Nm].
        extra: (1 + n,) ``GravityRate`` (``unpack_gravity_rate``): the rate limit on the
            command with gravity, named on the ticks that use it.
    """

    params: LimiterParams
    last_no_gravity: np.ndarray
    output: np.ndarray
    extra: np.ndarray


class GravityRate(NamedTuple):
    """The rate limit on the command with gravity (``rate_limit_includes_gravity``), views of
    ``LimiterState.extra``: a flag in the buffer rather than a scalar, so that the limiter
    crosses into numba as cheaply as before it existed.

    Attributes:
        on: (1,) 1 when the per-tick clip acts on the command with gravity.
        last_with_gravity: (n,) the previous rate-limited command, gravity included, before
            saturation [Nm] (the authors' ``tau_previous``; 0 after ``reset``).
    """

    on: np.ndarray
    last_with_gravity: np.ndarray


GRAVITY_RATE_LAYOUT = Layout.of(GravityRate, dict(on=1, last_with_gravity=N_JOINTS),
                                dims={"n": "n_joints"}, args=("ext", "n_joints"))
"""The tail ``LimiterState.extra``."""
unpack_gravity_rate = GRAVITY_RATE_LAYOUT.unpacker("unpack_gravity_rate", __name__,
                                                   returns_length=False)
gravity_rate_on = GRAVITY_RATE_LAYOUT.flag_reader("on", "gravity_rate_on", __name__)


class LimiterScalars(NamedTuple):
    """The scalar parameters (``LimiterParams`` without ``tau_max``) and the joint count."""

    max_delta_nm: float
    libfranka: bool
    max_rate_nm_per_s: float
    n_joints: int


LIMITER_LAYOUT = Layout.of(LimiterState, dict(
    params=Layout.of(LimiterParams, dict(tau_max=N_JOINTS)), last_no_gravity=N_JOINTS,
    output=N_JOINTS, extra=GRAVITY_RATE_LAYOUT.length), dims={"n": "sc.n_joints"})
"""The limiter's buffer; its tail ``extra`` is ``GRAVITY_RATE_LAYOUT``."""
unpack_limiter = LIMITER_LAYOUT.unpacker("unpack_limiter", __name__)


def make_limiter_state(config: LimitsConfig, dt_s: float) -> Packed:
    """``config`` at control period ``dt_s`` [s], packed (``unpack_limiter`` names it)."""
    sc = LimiterScalars(float(config.torque_rate_max_nm_per_s * dt_s),
                        config.rate_limiter == "libfranka",
                        float(config.torque_rate_max_nm_per_s), len(config.torque_max_nm))
    packed = Packed(sc, np.zeros(LIMITER_LAYOUT.size_for(sc)))
    st = unpack_limiter(packed.buffer, sc)[0]
    st.params.tau_max[:] = config.torque_max_nm
    unpack_gravity_rate(st.extra, sc.n_joints).on[0] = config.rate_limit_includes_gravity
    return packed


@njit(cache=True)
def limit_rate_kernel(tau_desired, tau_last, max_delta, out) -> None:
    """out = tau_last + clip(tau_desired - tau_last, -max_delta, max_delta) (NaN propagates)."""
    for j in range(out.shape[0]):
        d = tau_desired[j] - tau_last[j]
        if d > max_delta:
            d = max_delta
        if d < -max_delta:
            d = -max_delta
        out[j] = d + tau_last[j]


@njit(cache=True)
def limit_rate_libfranka_kernel(tau_desired, tau_last, max_rate, out) -> None:
    """libfranka's ``limitRate``: out = last + clamp((cmd - last) / 1e-3, +-max_rate) * 1e-3."""
    for j in range(out.shape[0]):
        rate = (tau_desired[j] - tau_last[j]) / 1e-3
        out[j] = tau_last[j] + max(min(rate, max_rate), -max_rate) * 1e-3


@njit(cache=True)
def saturate_kernel(tau, tau_max, out) -> None:
    """out = clip(tau, -tau_max, tau_max) per joint (NaN propagates)."""
    for j in range(out.shape[0]):
        v = tau[j]
        if v > tau_max[j]:
            v = tau_max[j]
        if v < -tau_max[j]:
            v = -tau_max[j]
        out[j] = v


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def _limit_with_gravity(tau_no_gravity, tau_gravity, st) -> None:
    """Per-tick clip of the whole command (gravity included) against the previous
    rate-limited command, then saturation (the authors' simulation)."""
    par, out = st.params, st.output
    last = unpack_gravity_rate(st.extra, out.shape[0]).last_with_gravity
    for j in range(out.shape[0]):
        d = tau_no_gravity[j] + tau_gravity[j] - last[j]
        if d > par.max_delta_nm:
            d = par.max_delta_nm
        if d < -par.max_delta_nm:
            d = -par.max_delta_nm
        last[j] += d
        out[j] = last[j]
    saturate_kernel(out, par.tau_max, out)
    for j in range(out.shape[0]):
        st.last_no_gravity[j] = out[j] - tau_gravity[j]


@njit(cache=True, inline="always")
def torque_limiter(tau_no_gravity, tau_gravity, st) -> None:
    """Rate-limit without gravity, add gravity, saturate; remember output - gravity.
    With ``with_gravity``: ``_limit_with_gravity`` instead."""
    par, last, out = st.params, st.last_no_gravity, st.output
    if gravity_rate_on(st.extra):  # the rate limit on the command with gravity
        _limit_with_gravity(tau_no_gravity, tau_gravity, st)
        return
    if par.libfranka:
        limit_rate_libfranka_kernel(tau_no_gravity, last, par.max_rate_nm_per_s, out)
    else:
        limit_rate_kernel(tau_no_gravity, last, par.max_delta_nm, out)
    for j in range(out.shape[0]):
        out[j] += tau_gravity[j]
    saturate_kernel(out, par.tau_max, out)
    for j in range(out.shape[0]):
        last[j] = out[j] - tau_gravity[j]


class TorqueLimiter:
    """Stateful torque-rate limiter followed by saturation: ``state`` (``LimiterState``) and
    ``apply`` over the kernel ``torque_limiter``.

    Like libfranka, the rate limit is applied to the torque *without* gravity (libfranka's
    ``tau_J_d`` excludes gravity, which the robot adds itself); gravity is then added and the
    total is saturated. The rate-limited state is re-synchronised with what was actually sent,
    so saturation cannot make the two diverge.
    """

    def __init__(self, config: LimitsConfig, dt_s: float) -> None:
        """Create the limiter.

        Args:
            config: Limits.
            dt_s: Control period [s]; the per-tick bound is ``torque_rate_max_nm_per_s * dt_s``.
        """
        self.packed = make_limiter_state(config, dt_s)
        self.state = st = unpack_limiter(self.packed.buffer, self.packed.scalars)[0]
        self.tau_max, self.output = st.params.tau_max, st.output
        self.max_delta_nm = st.params.max_delta_nm
        self.gravity_rate = unpack_gravity_rate(st.extra, len(config.torque_max_nm))

    def reset(self, tau_no_gravity: np.ndarray | None = None) -> None:
        """Set the previously commanded torque without gravity (default 0) [Nm]; the previous
        command with gravity (``rate_limit_includes_gravity``) is set to 0, as the authors'
        controller starts."""
        if tau_no_gravity is None:
            self.state.last_no_gravity.fill(0.0)
        else:
            self.state.last_no_gravity[:] = tau_no_gravity
        self.gravity_rate.last_with_gravity.fill(0.0)

    def apply(self, tau_no_gravity: np.ndarray, tau_gravity: np.ndarray) -> np.ndarray:
        """Rate-limit ``tau_no_gravity``, add ``tau_gravity``, saturate.

        Args:
            tau_no_gravity: Requested torque excluding gravity compensation (7,) [Nm].
            tau_gravity: Gravity compensation torque (7,) [Nm] (zeros if not compensated).

        Returns:
            The torque to apply (7,) [Nm]; an internal buffer, overwritten on the next call.
        """
        torque_limiter(
            np.asarray(tau_no_gravity, dtype=np.float64),
            np.asarray(tau_gravity, dtype=np.float64),
            self.state,
        )
        return self.output
