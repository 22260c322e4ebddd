"""Saturated-lift release (issue 37 item 5; on in ``default``, off in ``paper`` and the
authors' presets): stop asking for a lift the arm cannot give.

Why: with a load whose moment about the wrist exceeds the wrist's torque (Hammer, 8.5-10 kg;
joint 6's bound is 12 Nm), the learned feedforward keeps asking for the lift, a joint sits at
its torque bound for seconds, the load never rises and the hand leans on the table
(docs/controller.md, "What it teaches ``default``"). The limiter knows it: its output of the
previous tick equals the bound.

Per tick (``saturation_release_step``), with ``tau`` the limiter's output of the previous tick
and ``tau_max`` its bound:

1. A joint is **at its bound** when ``|tau_j| >= tau_max_j - margin_nm``.
   ``at_bound_ticks`` counts the ticks some joint has been at its bound without a break (0 on
   the first tick with none); the TCP height ``z`` at the start of that window is kept
   (``z_start``).
2. **Progress test.** When ``at_bound_ticks`` reaches ``round(hold_s / dt)``, the lift is
   still progressing if the TCP rose at least ``rise_min_m`` since ``z_start``: then the
   window starts again from here (``at_bound_ticks`` 0, ``z_start = z``), so a slow lift that
   keeps rising is never released. Otherwise the lift is stalled.
3. While ``at_bound_ticks >= round(hold_s / dt)`` (stalled and still at the bound) the scale
   ``s`` decays toward 0 with time constant ``release_tau_s``; otherwise it returns toward 1
   with ``recover_tau_s``, exactly (``s <- s + (goal - s) (1 - exp(-dt / tau))``; ``s``
   starts at 1).
4. The applied feedforward is ``s * w_ff`` (all six axes; the commanded wrench ``w_cmd`` is
   not scaled). The unscaled feedforward is kept (``ff_unscaled``) and handed back to the
   tick before it computes the next one (``saturation_release_restore``): a masked axis keeps
   its last unmasked value, which must not be scaled twice.

``enabled=False`` (``paper``, ``authors_sim``, ``authors_real``): the tick never names this
stage (``optional_stages.py``). ``default``'s values (hold 0.5 s, release 0.25 s, recover 2 s,
margin 0.1 Nm, rise 10 mm) were chosen on tuning seeds and ablated on the reference seeds
(docs/controller.md, "Saturated-lift release").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError
from impact_control.kernel_layout import Packed
from impact_control.stage_layout import Layout, slots
from impact_control.validation import check_positive


@dataclass(frozen=True)
class SaturationReleaseConfig:
    """Saturated-lift release: scale the feedforward down while a joint stays at its torque
    bound.

    Attributes:
        enabled: Run it (True in ``default``; ``paper`` and the authors' presets: False).
        hold_s: Time a joint must stay at its bound, without a break, before the release
            starts [s].
        release_tau_s: Time constant of the scale's decay toward 0 while released [s].
        recover_tau_s: Time constant of its return toward 1 once no joint is at its bound
            for ``hold_s`` [s].
        margin_nm: A joint counts as at its bound when |tau_cmd| >= tau_max - margin_nm [Nm]
            (0: only when the limiter clipped it).
        rise_min_m: The TCP (world z) must rise at least this much over a hold window at the
            bound for the lift to count as progressing, which restarts the window instead of
            releasing [m] (0: never released while the TCP does not fall).
    """

    enabled: bool = True
    hold_s: float = 0.5
    release_tau_s: float = 0.25
    recover_tau_s: float = 2.0
    margin_nm: float = 0.1
    rise_min_m: float = 0.01

    def __post_init__(self) -> None:
        check_positive("saturation_release.hold_s", self.hold_s, allow_zero=True)
        check_positive("saturation_release.release_tau_s", self.release_tau_s)
        check_positive("saturation_release.recover_tau_s", self.recover_tau_s)
        check_positive("saturation_release.margin_nm", self.margin_nm, allow_zero=True)
        if not math.isfinite(self.rise_min_m):
            raise InvalidArgumentError(
                f"saturation_release.rise_min_m must be finite, got {self.rise_min_m}")


class SaturationReleaseState(NamedTuple):
    """Everything ``saturation_release_step`` reads and writes ((1,) views for scalars: no
    crossing cost, ``optional_stages.py``).

    Attributes:
        hold_ticks: (1,) the config's hold in ticks (round(hold_s / dt)).
        release_alpha: (1,) 1 - exp(-dt / release_tau_s).
        recover_alpha: (1,) 1 - exp(-dt / recover_tau_s).
        margin_nm: (1,) the config's margin [Nm].
        rise_min_m: (1,) the config's progress threshold [m].
        z_start: (1,) TCP world z when the current window at the bound began [m].
        at_bound_ticks: (1,) ticks some joint has been at its bound without a break.
        scale: (1,) the scale s applied to the feedforward (1 after ``reset``).
        releases: (1,) ticks on which the release acted (at_bound_ticks >= hold_ticks)
            since reset.
        ff_unscaled: (6,) the feedforward of the last tick before scaling [N, Nm].
    """

    hold_ticks: np.ndarray
    release_alpha: np.ndarray
    recover_alpha: np.ndarray
    margin_nm: np.ndarray
    rise_min_m: np.ndarray
    z_start: np.ndarray
    at_bound_ticks: np.ndarray
    scale: np.ndarray
    releases: np.ndarray
    ff_unscaled: np.ndarray


SATURATION_RELEASE_LAYOUT = Layout.of(SaturationReleaseState, dict(
    **slots("hold_ticks release_alpha recover_alpha margin_nm rise_min_m z_start "
            "at_bound_ticks scale releases"), ff_unscaled=6), args=("buf", "n_joints"))
"""The saturated-lift release's part of the optional stages' buffer."""
unpack_saturation_release = SATURATION_RELEASE_LAYOUT.unpacker("unpack_saturation_release",
                                                               __name__)


def make_saturation_release_state(config: SaturationReleaseConfig, dt_s: float,
                                  n_joints: int = 7) -> Packed:
    """``config`` at control period ``dt_s`` [s], packed (``unpack_saturation_release``)."""
    packed = Packed(n_joints, np.zeros(SATURATION_RELEASE_LAYOUT.size()))
    st = unpack_saturation_release(packed.buffer, n_joints)[0]
    st.hold_ticks[0] = float(round(config.hold_s / dt_s))
    st.margin_nm[0] = config.margin_nm
    st.rise_min_m[0] = config.rise_min_m
    st.release_alpha[0] = -math.expm1(-dt_s / config.release_tau_s)
    st.recover_alpha[0] = -math.expm1(-dt_s / config.recover_tau_s)
    st.scale[0] = 1.0
    return packed


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def saturation_release_restore(w_ff, st) -> None:
    """w_ff := the last tick's unscaled feedforward (before the tick computes this one)."""
    for i in range(6):
        w_ff[i] = st.ff_unscaled[i]


@njit(cache=True)  # out of line
def saturation_release_step(tau_last, tau_max, z_tcp, w_ff, w_cmd, w_extra, st) -> None:
    """Advance the hold and the scale from the limiter's last output ``tau_last`` and bound
    ``tau_max`` (n,) [Nm] and the TCP's world height ``z_tcp`` [m]; keep ``w_ff`` (6,)
    unscaled, scale it in place and write ``w_extra = w_ff + w_cmd``."""
    at_bound = False
    for j in range(tau_last.shape[0]):
        if abs(tau_last[j]) >= tau_max[j] - st.margin_nm[0]:
            at_bound = True
    if not at_bound:
        st.at_bound_ticks[0] = 0.0
    else:
        if st.at_bound_ticks[0] == 0.0:
            st.z_start[0] = z_tcp
        st.at_bound_ticks[0] += 1.0
        if (st.at_bound_ticks[0] == st.hold_ticks[0]
                and z_tcp - st.z_start[0] >= st.rise_min_m[0]):
            st.at_bound_ticks[0] = 0.0  # still rising: a new window from here
    s = st.scale[0]
    if st.at_bound_ticks[0] >= st.hold_ticks[0]:
        s -= s * st.release_alpha[0]
        st.releases[0] += 1.0
    else:
        s += (1.0 - s) * st.recover_alpha[0]
    st.scale[0] = s
    for i in range(6):
        st.ff_unscaled[i] = w_ff[i]
        w_ff[i] *= s
        w_extra[i] = w_ff[i] + w_cmd[i]


class SaturationRelease:
    """The release as a typed object: ``state`` (``SaturationReleaseState``), ``step`` and
    ``reset``."""

    def __init__(self, config: SaturationReleaseConfig, dt_s: float, n_joints: int = 7,
                 buffer: np.ndarray | None = None) -> None:
        """Create it; ``buffer`` (optional) is the float64 view to keep the state in (the
        controller's shared buffer of optional stages)."""
        self.config = config
        self.packed = make_saturation_release_state(config, dt_s, n_joints)
        if buffer is not None:
            buffer[:] = self.packed.buffer
            self.packed = Packed(self.packed.scalars, buffer)
        self.state = unpack_saturation_release(self.packed.buffer, self.packed.scalars)[0]

    @property
    def scale(self) -> float:
        """The scale applied to the feedforward on the last tick."""
        return float(self.state.scale[0])

    def step(self, tau_last: np.ndarray, tau_max: np.ndarray, w_ff: np.ndarray,
             w_cmd: np.ndarray | None = None, z_tcp_m: float = 0.0) -> np.ndarray:
        """One tick (``saturation_release_step``) with the TCP at world height ``z_tcp_m``
        [m]: returns ``w_ff`` scaled (a new array)."""
        w = np.array(w_ff, dtype=np.float64)
        cmd = np.zeros(6) if w_cmd is None else np.asarray(w_cmd, dtype=np.float64)
        saturation_release_step(np.asarray(tau_last, dtype=np.float64),
                                np.asarray(tau_max, dtype=np.float64), float(z_tcp_m), w,
                                cmd, np.zeros(6),
                                self.state)
        return w

    def reset(self) -> None:
        """Scale 1, no time at the bound, no feedforward kept."""
        st = self.state
        st.at_bound_ticks[0], st.scale[0], st.releases[0], st.z_start[0] = 0.0, 1.0, 0.0, 0.0
        st.ff_unscaled.fill(0.0)
