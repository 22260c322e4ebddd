"""Clipped first-order filter of the external wrench (the internal model's training target).

Paper: w_slow <- w_slow + eta clip(w_ext - w_slow). The table gives eta in 1/s (force 2.0,
torque 1.0), so per 1 ms tick the gain is eta * dt:

    w_slow[k+1] = w_slow[k] + eta * dt * clip(w_ext[k] - w_slow[k], -c, c)   (per axis)

For a step of size A > c on one axis this is a ramp at the maximum slew eta * c (20 N/s for
force) until the gap reaches c, then an exponential with time constant ~1/eta (0.5 s force).

Options off in ``default`` and ``paper`` (the authors' released controller uses them,
``authors_sim`` / ``authors_real``; ``slow_filter_tick`` runs the plain update above when all
are off): the filter in the TCP frame (per-axis clip on TCP axes), then a leak
w_slow *= max(0, 1 - leak dt), then norm clamps on its force and torque parts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.kernel_layout import Packed
from impact_control.slow_filter_options import (
    SLOW_FILTER_EXTRA_LAYOUT,
    options_on,
    unpack_slow_filter_extra,
    update_with_options,
    write_slow_filter_options,
)
from impact_control.stage_layout import Layout
from impact_control.validation import FRAMES, check_optional_positive, check_positive

_EYE3 = np.eye(3)


@dataclass(frozen=True)
class SlowWrenchConfig:
    """Clipped first-order filter producing w_slow, the internal model's training target.

    Attributes:
        rate_force_per_s: eta of the force axes [1/s]; per-tick gain eta * dt (default 20,
            a 50 ms time constant; paper: 2.0, docs/presets.md "Presets").
        rate_torque_per_s: eta of the torque axes [1/s] (paper: 1.0).
        clip_force_n: Per-axis clip of (w_ext - w_slow) on force axes [N] (paper: 10).
        clip_torque_nm: Per-axis clip on torque axes [Nm] (paper: 1).
        frame: ``"world"`` (default) or ``"tcp"``: the frame w_slow is kept and clipped in
            (the authors' controller works in the TCP frame, ``use_local_jacobian``);
            ``wrench_slow`` is reported in the world frame either way.
        leak_per_s: Leak rate [1/s]: w_slow *= max(0, 1 - leak dt) after each update
            (0: none; the authors: 0.01).
        force_norm_max_n: Bound on |w_slow force| [N] after the leak (None: none; the
            authors: 120 in simulation, 50 on the robot).
        torque_norm_max_nm: Bound on |w_slow torque| [Nm] (None: none; 50 / 8).
    """

    rate_force_per_s: float = 20.0
    rate_torque_per_s: float = 1.0
    clip_force_n: float = 10.0
    clip_torque_nm: float = 1.0
    frame: str = "world"
    leak_per_s: float = 0.0
    force_norm_max_n: float | None = None
    torque_norm_max_nm: float | None = None

    def __post_init__(self) -> None:
        check_positive("rate_force_per_s", self.rate_force_per_s)
        check_positive("rate_torque_per_s", self.rate_torque_per_s)
        check_positive("clip_force_n", self.clip_force_n)
        check_positive("clip_torque_nm", self.clip_torque_nm)
        check_choice("slow_wrench.frame", self.frame, FRAMES)
        check_positive("leak_per_s", self.leak_per_s, allow_zero=True)
        check_optional_positive("force_norm_max_n", self.force_norm_max_n)
        check_optional_positive("torque_norm_max_nm", self.torque_norm_max_nm)

    @property
    def options_on(self) -> bool:
        """Whether any option beyond the paper's filter is on (TCP frame, leak, clamps)."""
        return (self.frame != "world" or self.leak_per_s > 0.0
                or self.force_norm_max_n is not None or self.torque_norm_max_nm is not None)

    @property
    def max_force_slew_n_per_s(self) -> float:
        """Largest per-axis force rate of w_slow, eta_f * clip_f [N/s] (default 200, paper 20)."""
        return self.rate_force_per_s * self.clip_force_n


# ------------------------------------------------------------------ named state and kernel
class SlowFilterParams(NamedTuple):
    """The filter's constants (``make_slow_filter_state``).

    Attributes:
        eta_per_s: eta per axis (6,) [1/s].
        gain: eta dt per axis (6,) [1 per tick].
        clip: Clip c per axis (6,) [N, Nm].
        inv_max_force_slew: 1 / (eta_f c_f) [s/N]: normalizes the slow rate.
    """

    eta_per_s: np.ndarray
    gain: np.ndarray
    clip: np.ndarray
    inv_max_force_slew: float


class SlowFilterState(NamedTuple):
    """Everything ``slow_filter_update`` reads and writes.

    Attributes:
        params: ``SlowFilterParams``.
        wrench_slow: w_slow (6,) [N, Nm], world frame.
        rate: dw_slow/dt of the last update before leak and clamps (6,) [N/s, Nm/s], in the
            filter's frame.
        slow_rate: (1,) the dimensionless slow-wrench rate of the last update.
        extra: The options' constants and arrays (frame, leak, clamps), named by
            ``slow_filter_options.unpack_slow_filter_extra`` on the ticks that use them.
    """

    params: SlowFilterParams
    wrench_slow: np.ndarray
    rate: np.ndarray
    slow_rate: np.ndarray
    extra: np.ndarray


class SlowFilterScalars(NamedTuple):
    """The scalar parameter: 1 / (eta_f c_f) [s/N], which normalizes the slow rate."""

    inv_max_force_slew: float


SLOW_FILTER_LAYOUT = Layout.of(SlowFilterState, dict(
    params=Layout.of(SlowFilterParams, dict(eta_per_s=6, gain=6, clip=6)), wrench_slow=6,
    rate=6, slow_rate=1, extra=SLOW_FILTER_EXTRA_LAYOUT.length))
"""The filter's buffer; its tail ``extra`` is ``SLOW_FILTER_EXTRA_LAYOUT``."""
unpack_slow_filter = SLOW_FILTER_LAYOUT.unpacker("unpack_slow_filter", __name__)


def make_slow_filter_state(config: SlowWrenchConfig, dt_s: float) -> Packed:
    """``config`` at control period ``dt_s`` [s], packed (``unpack_slow_filter`` names it)."""
    f, t = config.rate_force_per_s, config.rate_torque_per_s
    cf, ct = config.clip_force_n, config.clip_torque_nm
    sc = SlowFilterScalars(1.0 / config.max_force_slew_n_per_s)
    packed = Packed(sc, np.zeros(SLOW_FILTER_LAYOUT.size()))
    st = unpack_slow_filter(packed.buffer, sc)[0]
    write_slow_filter_options(unpack_slow_filter_extra(st.extra), config.options_on,
                              config.frame == "tcp", config.leak_per_s * dt_s,
                              config.force_norm_max_n, config.torque_norm_max_nm)
    params = st.params
    params.eta_per_s[:] = (f, f, f, t, t, t)
    params.gain[:] = params.eta_per_s * dt_s
    params.clip[:] = (cf, cf, cf, ct, ct, ct)
    return packed


@njit(cache=True, inline="always")
def slow_filter_update(wrench_ext, st) -> float:
    """w_slow += eta dt clip(w_ext - w_slow, -c, c); returns (and stores) the slow rate."""
    par, w_slow, rate = st.params, st.wrench_slow, st.rate
    for i in range(6):
        d = wrench_ext[i] - w_slow[i]
        if d > par.clip[i]:
            d = par.clip[i]
        if d < -par.clip[i]:
            d = -par.clip[i]
        rate[i] = par.eta_per_s[i] * d
        w_slow[i] += d * par.gain[i]
    fx, fy, fz = rate[0], rate[1], rate[2]
    st.slow_rate[0] = math.sqrt(fx * fx + fy * fy + fz * fz) * par.inv_max_force_slew
    return st.slow_rate[0]


@njit(cache=True, inline="always")
def slow_filter_tick(wrench_ext, rot_ee, st) -> float:
    """One tick of the filter: ``slow_filter_update`` when no option is on, else the update
    in the filter's frame (``rot_ee``: the TCP's rotation, world from TCP) with leak and
    clamps. Returns the slow rate."""
    if options_on(st.extra):
        return update_with_options(wrench_ext, rot_ee, st, unpack_slow_filter_extra(st.extra))
    return slow_filter_update(wrench_ext, st)


class SlowWrenchFilter:
    """Per-axis clipped low-pass and slow-wrench rate: ``state`` (``SlowFilterState``) and
    ``update`` over the kernel ``slow_filter_update``.

    Attributes:
        wrench_slow_world: w_slow (6,) [N, Nm], world frame, robot-on-environment sign.
        rate_world: dw_slow/dt of the last update (6,) [N/s, Nm/s].
        slow_rate: |dw_slow/dt|_force (Euclidean norm of the three force components) divided by
            the largest per-axis force slew eta_f * c_f; dimensionless, 0 when settled, 1 when
            one force axis slews at its maximum (up to sqrt(3) if all three do).
    """

    def __init__(self, config: SlowWrenchConfig, dt_s: float) -> None:
        """Create the filter for control period ``dt_s`` [s]."""
        self.config = config
        self.dt_s = dt_s
        self.packed = make_slow_filter_state(config, dt_s)
        self.state = st = unpack_slow_filter(self.packed.buffer, self.packed.scalars)[0]
        self.eta_per_s, self.gain, self.clip = st.params[:3]
        self.wrench_slow_world, self.rate_world = st.wrench_slow, st.rate
        self.extra = unpack_slow_filter_extra(st.extra)  # the options' views
        self.wrench_slow_kept = self.extra.wrench_kept

    @property
    def slow_rate(self) -> float:
        """Dimensionless slow-wrench rate of the last update (see the class docstring)."""
        return float(self.state.slow_rate[0])

    def reset(self, wrench_slow_world: np.ndarray | None = None) -> None:
        """Set w_slow (default 0) and zero the rate."""
        if wrench_slow_world is None:
            self.wrench_slow_world.fill(0.0)
        else:
            self.wrench_slow_world[:] = wrench_slow_world
        self.rate_world.fill(0.0)
        self.state.slow_rate[0] = 0.0
        self.wrench_slow_kept.fill(0.0)  # the TCP-frame copy (frame="tcp": starts from 0)

    def update(self, wrench_ext_world: np.ndarray,
               rot_ee_world: np.ndarray | None = None) -> np.ndarray:
        """Advance one tick toward ``wrench_ext_world`` (6,) and return w_slow (6,), world
        frame; ``rot_ee_world`` (3, 3), the TCP's rotation, is needed with ``frame="tcp"``."""
        w_ext = np.asarray(wrench_ext_world, dtype=np.float64)
        if rot_ee_world is None:
            if self.extra.tcp_frame[0] != 0.0:
                raise InvalidArgumentError(
                    "invalid rot_ee_world None; valid: the TCP rotation (3, 3) with frame='tcp'")
            rot_ee_world = _EYE3
        slow_filter_tick(w_ext, np.ascontiguousarray(rot_ee_world, dtype=np.float64),
                         self.state)
        return self.wrench_slow_world


def step_response_time_s(step_n: float, target_fraction: float, config: SlowWrenchConfig) -> float:
    """Continuous-time time for a force-axis step of ``step_n`` [N] to reach a fraction of it.

    Ramp at eta c until the gap equals c, then exponential: gap(t) = c exp(-eta (t - t_ramp)).

    Args:
        step_n: Step size A [N] (> 0).
        target_fraction: Fraction of A to reach, in (0, 1).
        config: Filter settings (force axis).

    Returns:
        Time [s] (analytic, continuous-time approximation of the 1 ms recursion).
    """
    eta, c = config.rate_force_per_s, config.clip_force_n
    gap = (1.0 - target_fraction) * step_n
    ramp_end_gap = min(step_n, c)
    t_ramp = (step_n - ramp_end_gap) / (eta * c)
    if gap >= ramp_end_gap:
        return (step_n - gap) / (eta * c)
    return t_ramp + math.log(ramp_end_gap / gap) / eta
