"""Saturated-lift release (issue 37 item 5; on in ``default``, off in ``paper`` and the
authors' presets): stop asking for a lift the arm cannot give.

Why: with a load whose moment about the wrist exceeds the wrist's torque (Hammer, 8.5-10 kg;
joint 6's bound is 12 Nm), the learned feedforward keeps asking for the lift, a joint sits at
its torque bound for seconds, the load never rises and the hand leans on the table
(docs/presets.md, "What it teaches ``default``"). The limiter knows it: its output of the
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

**Lift watch** (``lift_watch_s`` finite; off in ``default``, on in the experimental
``lift_watch`` preset, issue 54): the
load is fed forward only while the arm really carries it. A gripper *close* (the command goes
from open, <= 0, to closed, > 0) arms it and keeps the TCP's lowest height since (``z_low``).
The lift is *seen* once the TCP rises ``lift_min_m`` above ``z_low``. Until then, every tick
on which the unscaled vertical feedforward pushes up with at least ``lift_force_min_n``
counts; after ``lift_watch_s`` of such ticks without the lift seen, the table (or whatever
the load rests on) carries it: the lift is *stalled*, and the scale decays toward 0 as in a
release and stays there until the gripper opens (which disarms the watch) or the TCP rises
``lift_min_m`` above ``z_low`` after all (the lift seen: the scale recovers). With
``tip_hold_s`` finite (off in every preset: it ended every press on the tuning seeds and
lost 13-17 of 28 lifts from 7 kg up, docs/controller.md), some joint at its bound for that long
in all since the close, before the lift is seen, stalls the lift too. With
``spare_carried`` (on in ``default`` from preset revision 2, i.e. ``keep_carried``, issue 54's
preset, and in ``lift_watch``; off in revision 1's ``default``) the
saturation release above does not act once the lift is seen (a load the arm has lifted is
carried, not let go, while the wrist is at its bound); the close arms the bookkeeping and
the lift is seen whatever ``lift_watch_s`` is. Only the
gripper command, the TCP's height and the feedforward are read: what a real FR3 has. An
episode that starts with the gripper closed (a tool already in the hand) never arms it.

``enabled=False`` (``paper``, ``authors_sim``, ``authors_real``): the tick never names this
stage (``optional_stages.py``). ``default``'s values (hold 0.5 s, release 0.25 s, recover 2 s,
margin 0.1 Nm, rise 10 mm) were chosen on tuning seeds and ablated on the reference seeds
(docs/presets.md, "Saturated-lift release").
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
        lift_watch_s: Lift watch (module docstring): how long the vertical feedforward may
            push up with at least ``lift_force_min_n`` after a gripper close before the lift
            must be seen [s] (inf: no lift watch, as in ``default``).
        lift_min_m: The TCP's rise above its lowest height since the close that counts as
            the lift seen [m].
        lift_force_min_n: The upward vertical feedforward [N, world z] from which the lift
            watch counts time.
        spare_carried: The saturation release does not act once the lift is seen since the
            last close (True in ``default`` since preset revision 2, False in revision 1).
        tip_hold_s: Tip test of the lift watch: the lift is stalled once some joint has
            been at its torque bound for this long in all (not necessarily without a break)
            since the close while the lift is not seen [s] (inf: no tip test, as in
            ``default``).
    """

    enabled: bool = True
    hold_s: float = 0.5
    release_tau_s: float = 0.25
    recover_tau_s: float = 2.0
    margin_nm: float = 0.1
    rise_min_m: float = 0.01
    lift_watch_s: float = math.inf
    lift_min_m: float = 0.02
    lift_force_min_n: float = 10.0
    spare_carried: bool = True
    tip_hold_s: float = math.inf

    def __post_init__(self) -> None:
        if not (self.tip_hold_s > 0.0):  # inf allowed: no tip test
            raise InvalidArgumentError(
                f"invalid saturation_release.tip_hold_s {self.tip_hold_s!r}; valid: a time "
                "> 0 [s], or inf (no tip test)")
        if not (self.lift_watch_s > 0.0):  # inf allowed: no lift watch
            raise InvalidArgumentError(
                f"invalid saturation_release.lift_watch_s {self.lift_watch_s!r}; valid: a "
                "time > 0 [s], or inf (no lift watch)")
        check_positive("saturation_release.lift_min_m", self.lift_min_m)
        check_positive("saturation_release.lift_force_min_n", self.lift_force_min_n,
                       allow_zero=True)
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
        watch_ticks: (1,) the lift watch in ticks (round(lift_watch_s / dt); inf: off).
        lift_min_m: (1,) the config's lift threshold [m].
        lift_force_min_n: (1,) the config's force threshold [N].
        spare_carried: (1,) 1 when the saturation release spares a seen lift.
        grip_last: (1,) the gripper command of the last tick (+1 after ``reset``).
        armed: (1,) 1 from a gripper close until it opens.
        lifted: (1,) 1 once the lift is seen since the last close.
        stalled: (1,) 1 while the lift watch releases the feedforward.
        z_low: (1,) the TCP's lowest world z since the last close [m].
        pushing_ticks: (1,) ticks since the close with the upward feedforward at or above
            the threshold and the lift not seen.
        tip_ticks: (1,) the tip test's hold in ticks (round(tip_hold_s / dt); inf: off).
        bound_ticks: (1,) ticks since the close with a joint at its bound and the lift not
            seen.
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
    watch_ticks: np.ndarray
    lift_min_m: np.ndarray
    lift_force_min_n: np.ndarray
    spare_carried: np.ndarray
    grip_last: np.ndarray
    armed: np.ndarray
    lifted: np.ndarray
    stalled: np.ndarray
    z_low: np.ndarray
    pushing_ticks: np.ndarray
    tip_ticks: np.ndarray
    bound_ticks: np.ndarray


SATURATION_RELEASE_LAYOUT = Layout.of(SaturationReleaseState, dict(
    **slots("hold_ticks release_alpha recover_alpha margin_nm rise_min_m z_start "
            "at_bound_ticks scale releases"), ff_unscaled=6,
    **slots("watch_ticks lift_min_m lift_force_min_n spare_carried grip_last armed lifted "
            "stalled z_low pushing_ticks tip_ticks bound_ticks")), args=("buf", "n_joints"))
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
    st.watch_ticks[0] = (math.inf if math.isinf(config.lift_watch_s)
                         else float(round(config.lift_watch_s / dt_s)))
    st.lift_min_m[0] = config.lift_min_m
    st.lift_force_min_n[0] = config.lift_force_min_n
    st.spare_carried[0] = float(config.spare_carried)
    st.grip_last[0] = 1.0
    st.tip_ticks[0] = (math.inf if math.isinf(config.tip_hold_s)
                       else float(round(config.tip_hold_s / dt_s)))
    return packed


@njit(cache=True)  # out of line: the tick's default path stays as small as before
def saturation_release_restore(w_ff, st) -> None:
    """w_ff := the last tick's unscaled feedforward (before the tick computes this one)."""
    for i in range(6):
        w_ff[i] = st.ff_unscaled[i]


@njit(cache=True, inline="always")
def _lift_watch(z_tcp, grip_cmd, ff_up, at_bound, st) -> None:
    """Advance the lift watch (module docstring) by one tick: arm on a close, disarm on an
    open, see the lift or count the upward push and the time at the bound toward a stall."""
    if grip_cmd > 0.0 and st.grip_last[0] <= 0.0:  # a close: arm, from this height
        st.armed[0], st.lifted[0], st.stalled[0] = 1.0, 0.0, 0.0
        st.z_low[0], st.pushing_ticks[0], st.bound_ticks[0] = z_tcp, 0.0, 0.0
    elif grip_cmd <= 0.0:  # open: nothing is carried
        st.armed[0], st.lifted[0], st.stalled[0] = 0.0, 0.0, 0.0
    st.grip_last[0] = grip_cmd
    if st.armed[0] == 0.0 or st.lifted[0] != 0.0:
        return
    st.z_low[0] = min(st.z_low[0], z_tcp)
    if z_tcp - st.z_low[0] >= st.lift_min_m[0]:
        st.lifted[0], st.stalled[0] = 1.0, 0.0
        return
    if ff_up >= st.lift_force_min_n[0]:
        st.pushing_ticks[0] += 1.0
        if st.pushing_ticks[0] >= st.watch_ticks[0]:
            st.stalled[0] = 1.0
    if at_bound:  # the tip test: a load the wrist cannot hold tips the hand
        st.bound_ticks[0] += 1.0
        if st.bound_ticks[0] >= st.tip_ticks[0]:
            st.stalled[0] = 1.0


@njit(cache=True)  # out of line
def saturation_release_step(tau_last, tau_max, z_tcp, grip_cmd, w_ff, w_cmd, w_extra,
                            st) -> None:
    """Advance the hold, the lift watch and the scale from the limiter's last output
    ``tau_last`` and bound ``tau_max`` (n,) [Nm], the TCP's world height ``z_tcp`` [m] and the
    gripper command ``grip_cmd`` (-1 open ... +1 closed); keep ``w_ff`` (6,) unscaled, scale
    it in place and write ``w_extra = w_ff + w_cmd``."""
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
    _lift_watch(z_tcp, grip_cmd, w_ff[2], at_bound, st)
    spared = st.spare_carried[0] != 0.0 and st.lifted[0] != 0.0
    s = st.scale[0]
    if (st.at_bound_ticks[0] >= st.hold_ticks[0] and not spared) or st.stalled[0] != 0.0:
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
             w_cmd: np.ndarray | None = None, z_tcp_m: float = 0.0,
             gripper_cmd: float = 1.0) -> np.ndarray:
        """One tick (``saturation_release_step``) with the TCP at world height ``z_tcp_m``
        [m] and gripper command ``gripper_cmd`` (-1 open ... +1 closed): returns ``w_ff``
        scaled (a new array)."""
        w = np.array(w_ff, dtype=np.float64)
        cmd = np.zeros(6) if w_cmd is None else np.asarray(w_cmd, dtype=np.float64)
        saturation_release_step(np.asarray(tau_last, dtype=np.float64),
                                np.asarray(tau_max, dtype=np.float64), float(z_tcp_m),
                                float(gripper_cmd), w, cmd, np.zeros(6), self.state)
        return w

    def reset(self) -> None:
        """Scale 1, no time at the bound, no feedforward kept."""
        st = self.state
        st.at_bound_ticks[0], st.scale[0], st.releases[0], st.z_start[0] = 0.0, 1.0, 0.0, 0.0
        st.ff_unscaled.fill(0.0)
        st.grip_last[0], st.armed[0], st.lifted[0], st.stalled[0] = 1.0, 0.0, 0.0, 0.0
        st.z_low[0], st.pushing_ticks[0], st.bound_ticks[0] = 0.0, 0.0, 0.0
