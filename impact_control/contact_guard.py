"""Contact guard and feedforward bounds: the learned feedforward may not build force into a
contact that does not give.

Why: the internal model learns the slow external wrench and feeds it forward. Against a rigid
contact the estimate is the impedance press plus the feedforward itself, so each learned
increment raises the estimate by as much: a ratchet that presses harder and harder (issue 26;
docs/controller.md, "Contact guard"). In free space the same increment moves the TCP by
increment / K and the estimate stays (the load does not change): that difference is the test.

Force part, as vectors in the world frame, every tick (``contact_guard_step``):

1. A window starts with the current prediction ``f0``, tracking offset ``p0`` (TCP minus its
   target, so that a moving target is not read as the TCP giving) and slow estimate ``e0``.
2. When the prediction has grown by ``growth_step_n`` (``g = f - f0``) in a direction that is not
   upward (``g_z < upward_cos * |g|``: lifting a load that still rests on something is how
   heavy objects are lifted, the lift ratchet) and not mostly a decrease of ``f0`` (``g . f0 <=
   -upward_cos |g| |f0|``: it only makes a press smaller), both checked again after the wait,
   the guard waits ``follow_delay_s``, then calls the contact **blocked** if the offset moved
   less than ``give_fraction * |g| / K`` along ``g``, the TCP did not retreat against ``g`` by
   as much either (that is an external force that just changed, e.g. a push, not a contact
   that does not give), **and** the slow estimate rose by at least ``follow_fraction * |g|``
   along ``g`` (it follows the feedforward: the contact pushes back). Otherwise the growth is
   accepted and a new window starts.
3. Blocked: the force feedforward is held at ``f0`` (the value before the growth) less any
   push it had along ``u = g / |g|`` (learned before the contact, e.g. while the hand moved
   toward it): no learned force may press into a contact that does not give. Only a rise of
   the vertical force above the hold stays free (the lift ratchet again: a sideways hold must
   not stop a lift). The training target is held the same way, so the prediction does not
   climb behind the hold. The hold ends when the TCP has moved ``release_move_m`` from where
   it started (the contact is gone) or the prediction has fallen ``growth_step_n`` below the
   hold along ``u``.

Then the applied feedforward is bounded: its rate (force ``force_rate_max_n_per_s``, torque
``torque_rate_max_nm_per_s``) and its size (``force_max_n``, ``torque_max_nm``), both as
vector norms. The torque axes are bounded only (no blocked test). ``enabled=False`` (the
``paper`` preset) leaves the feedforward exactly as predicted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.errors import InvalidArgumentError
from impact_control.kernel_layout import Packed
from impact_control.stage_layout import Layout
from impact_control.validation import check_positive

OPEN, WINDOW, WAIT, HOLD = 0.0, 1.0, 2.0, 3.0
"""Phases (``GuardState.phase``): no window yet, window open, growth seen (waiting),
holding."""


@dataclass(frozen=True)
class ContactGuardConfig:
    """Contact guard and bounds on the feedforward wrench (world frame).

    Attributes:
        enabled: Run the guard and the bounds (default True; the ``paper`` preset: False,
            the feedforward exactly as predicted).
        growth_step_n: Growth of the predicted force [N] that triggers the blocked test, and
            the fall below the hold that releases it.
        follow_delay_s: Wait after the growth before testing [s] (lets a free load move:
            the arm's translational time constant with a 5 kg load is about 0.1 s).
        give_fraction: Blocked if the TCP moved less than this fraction of |g| / K along g.
        follow_fraction: ... and the slow estimate rose by at least this fraction of |g|.
        upward_cos: Growth with g_z >= upward_cos |g| is never blocked (the lift ratchet),
            nor growth with g . f0 <= -upward_cos |g| |f0| (a decrease of the force).
        release_move_m: A hold ends when the TCP moved this far from where it began [m].
        force_max_n: Bound on the norm of the force feedforward [N].
        horizontal_force_max_n: Bound on the norm of its horizontal (x, y) part [N].
        torque_max_nm: Bound on the norm of the torque feedforward [Nm].
        force_rate_max_n_per_s: Bound on the rate of the force feedforward [N/s].
        torque_rate_max_nm_per_s: Bound on the rate of the torque feedforward [Nm/s].
    """

    enabled: bool = True
    growth_step_n: float = 2.0
    follow_delay_s: float = 0.1
    give_fraction: float = 0.5
    follow_fraction: float = 0.25
    upward_cos: float = 0.15
    release_move_m: float = 0.002
    force_max_n: float = 150.0
    horizontal_force_max_n: float = 60.0
    torque_max_nm: float = 20.0
    force_rate_max_n_per_s: float = 1000.0
    torque_rate_max_nm_per_s: float = 100.0

    def __post_init__(self) -> None:
        for name in ("growth_step_n", "follow_delay_s", "give_fraction", "release_move_m",
                     "force_max_n", "horizontal_force_max_n", "torque_max_nm",
                     "force_rate_max_n_per_s",
                     "torque_rate_max_nm_per_s"):
            check_positive(name, getattr(self, name))
        check_positive("follow_fraction", self.follow_fraction, allow_zero=True)
        if not -1.0 <= self.upward_cos <= 1.0:
            raise InvalidArgumentError(f"invalid upward_cos {self.upward_cos!r}; valid: [-1, 1]")


class GuardParams(NamedTuple):
    """The guard's constants (``make_guard_state``; the config's names and units).

    Attributes:
        enabled: Whether the guard and the bounds act at all.
        growth_step_n: Growth of the predicted force that starts the test [N].
        follow_delay_ticks: Ticks waited before the test (float, compared with a counter).
        give_fraction, follow_fraction: Shares of the growth the TCP must give / the estimate
            must follow.
        upward_cos: Cosine above which a growth counts as upward (never held).
        release_move_m: TCP move that releases a hold [m].
        compliance_m_per_n: 1 / K of the stiffest-giving axis [m/N].
        force_max_n, torque_max_nm: Norm bounds of the feedforward [N], [Nm].
        force_step_max_n, torque_step_max_nm: Change bounds per tick [N], [Nm].
        horizontal_force_max_n: Bound of the horizontal force part [N].
    """

    enabled: bool
    growth_step_n: float
    follow_delay_ticks: float
    give_fraction: float
    follow_fraction: float
    upward_cos: float
    release_move_m: float
    compliance_m_per_n: float
    force_max_n: float
    torque_max_nm: float
    force_step_max_n: float
    torque_step_max_nm: float
    horizontal_force_max_n: float


class GuardState(NamedTuple):
    """Everything the guard's kernels read and write (world frame).

    Attributes:
        params: ``GuardParams``.
        phase: (1,) OPEN, WINDOW, WAIT or HOLD.
        ticks_waited: (1,) ticks in WAIT.
        holds_started: (1,) holds since ``reset``.
        f0: Predicted force when the window began (3,) [N].
        p0: Tracking offset (TCP - target) when the window began (3,) [m].
        e0: Slow estimate when the window began (3,) [N].
        hold_force: The force held (3,) [N].
        hold_pos: TCP position when the hold began (3,) [m].
        blocked_dir: Unit direction the TCP did not give along (3,).
        prev_ff: The previous tick's feedforward (6,) [N, Nm].
        offset: This tick's tracking offset (3,) [m].
        window_pos: TCP position when the window began (3,) [m].
        target: This tick's training target (6,): the slow wrench, force axes replaced by
            the hold.
    """

    params: GuardParams
    phase: np.ndarray
    ticks_waited: np.ndarray
    holds_started: np.ndarray
    f0: np.ndarray
    p0: np.ndarray
    e0: np.ndarray
    hold_force: np.ndarray
    hold_pos: np.ndarray
    blocked_dir: np.ndarray
    prev_ff: np.ndarray
    offset: np.ndarray
    window_pos: np.ndarray
    target: np.ndarray


GUARD_LAYOUT = Layout.of(GuardState, dict(
    phase=1, ticks_waited=1, holds_started=1, f0=3, p0=3, e0=3, hold_force=3, hold_pos=3,
    blocked_dir=3, prev_ff=6, offset=3, window_pos=3, target=6), args=("buf", "params"))
"""The guard's buffer (``params`` are all scalars)."""
unpack_guard = GUARD_LAYOUT.unpacker("unpack_guard", __name__)


def make_guard_state(cfg: ContactGuardConfig, dt_s: float, stiffness_n_per_m: float) -> Packed:
    """``cfg`` at control period ``dt_s`` and translational stiffness ``stiffness_n_per_m``
    (the smallest diagonal entry: the most the TCP gives), packed (``unpack_guard``)."""
    params = GuardParams(
        enabled=bool(cfg.enabled), growth_step_n=float(cfg.growth_step_n),
        follow_delay_ticks=float(round(cfg.follow_delay_s / dt_s)),
        give_fraction=float(cfg.give_fraction), follow_fraction=float(cfg.follow_fraction),
        upward_cos=float(cfg.upward_cos), release_move_m=float(cfg.release_move_m),
        compliance_m_per_n=1.0 / stiffness_n_per_m, force_max_n=float(cfg.force_max_n),
        torque_max_nm=float(cfg.torque_max_nm),
        force_step_max_n=float(cfg.force_rate_max_n_per_s * dt_s),
        torque_step_max_nm=float(cfg.torque_rate_max_nm_per_s * dt_s),
        horizontal_force_max_n=float(cfg.horizontal_force_max_n))
    return Packed(params, np.zeros(GUARD_LAYOUT.size_for(params)))


@njit(cache=True)
def _start_window(st, pred, offset, w_est, pos) -> None:
    st.phase[0] = WINDOW
    for i in range(3):
        st.f0[i], st.p0[i], st.e0[i] = pred[i], offset[i], w_est[i]
        st.window_pos[i] = pos[i]


@njit(cache=True)
def _growth(st, pred, mask):
    """(g_x, g_y, g_z, |g|): growth of the predicted force since the window began, on the
    axes the model learns (a masked axis carries a commanded force, not a learned one)."""
    gx = (pred[0] - st.f0[0]) if mask[0] != 0.0 else 0.0
    gy = (pred[1] - st.f0[1]) if mask[1] != 0.0 else 0.0
    gz = (pred[2] - st.f0[2]) if mask[2] != 0.0 else 0.0
    return gx, gy, gz, math.sqrt(gx * gx + gy * gy + gz * gz)


@njit(cache=True)
def _along(a, b, gx, gy, gz, size) -> float:
    """(a - b) . g / |g| (3-vectors)."""
    return ((a[0] - b[0]) * gx + (a[1] - b[1]) * gy + (a[2] - b[2]) * gz) / size


@njit(cache=True)
def _exempt(par, st, gx, gy, gz, size) -> bool:
    """Growth never held: upward (the lift ratchet), or mostly a decrease of the force the
    window began with (g against f0: the press it could build only gets smaller)."""
    if gz >= par.upward_cos * size:
        return True
    f0x, f0y, f0z = st.f0[0], st.f0[1], st.f0[2]
    f0 = math.sqrt(f0x * f0x + f0y * f0y + f0z * f0z)
    return gx * f0x + gy * f0y + gz * f0z <= -par.upward_cos * size * f0


@njit(cache=True)
def _blocked(par, st, gx, gy, gz, size, offset, w_est, pos) -> bool:
    """Whether the TCP did not give along g (relative to its target), did not retreat
    against it either (an external force that just changed), while the estimate followed."""
    give = par.give_fraction * size * par.compliance_m_per_n
    moved = _along(offset, st.p0, gx, gy, gz, size)
    retreat = -_along(pos, st.window_pos, gx, gy, gz, size)
    follow = _along(w_est, st.e0, gx, gy, gz, size)
    return moved < give and retreat < give and follow >= par.follow_fraction * size


@njit(cache=True)
def _start_hold(st, ux, uy, uz, pos) -> None:
    """Hold f0 without any push along the blocked direction u: f0 - max(0, f0 . u) u."""
    st.phase[0], st.ticks_waited[0], st.holds_started[0] = HOLD, 0.0, st.holds_started[0] + 1.0
    push = max(0.0, st.f0[0] * ux + st.f0[1] * uy + st.f0[2] * uz)
    st.hold_force[0] = st.f0[0] - push * ux
    st.hold_force[1] = st.f0[1] - push * uy
    st.hold_force[2] = st.f0[2] - push * uz
    st.hold_pos[0], st.hold_pos[1], st.hold_pos[2] = pos[0], pos[1], pos[2]
    st.blocked_dir[0], st.blocked_dir[1], st.blocked_dir[2] = ux, uy, uz


@njit(cache=True)
def _held(w, st, mask) -> None:
    """w[:3] := the hold on learned axes, plus any rise of w_z above it (upward stays free)."""
    for i in range(3):
        if mask[i] != 0.0:
            w[i] = st.hold_force[i] + (max(0.0, w[i] - st.hold_force[i]) if i == 2 else 0.0)


@njit(cache=True, inline="always")
def contact_guard_step(pred, pos, pos_target, w_slow, mask, st) -> None:
    """Advance the blocked test; write the training target ``st.target``.

    ``pos`` / ``pos_target``: TCP position and its target [m]: the give is measured on the
    tracking offset ``pos - pos_target``, so a moving target is not read as a give. ``mask``:
    the learning mask; masked force axes are neither tested nor held. ``w_slow``: the slow
    estimate (whose rise the test reads, and the training target it passes on).
    """
    par, phase, target = st.params, st.phase, st.target
    for i in range(6):
        target[i] = w_slow[i]
    if not par.enabled:
        return
    offset = st.offset
    for i in range(3):
        offset[i] = pos[i] - pos_target[i]
    if phase[0] == OPEN:
        _start_window(st, pred, offset, w_slow, pos)
    gx, gy, gz, size = _growth(st, pred, mask)
    if phase[0] == WINDOW and size >= par.growth_step_n:
        if _exempt(par, st, gx, gy, gz, size):
            _start_window(st, pred, offset, w_slow, pos)
        else:
            phase[0], st.ticks_waited[0] = WAIT, 0.0
    elif phase[0] == WAIT:
        st.ticks_waited[0] += 1.0
        if size < par.growth_step_n:
            phase[0] = WINDOW  # the growth went away again: keep the window
        elif st.ticks_waited[0] >= par.follow_delay_ticks:
            exempt = _exempt(par, st, gx, gy, gz, size)  # re-checked: g may have turned
            if not exempt and _blocked(par, st, gx, gy, gz, size, offset, w_slow, pos):
                _start_hold(st, gx / size, gy / size, gz / size, pos)
            else:
                _start_window(st, pred, offset, w_slow, pos)
    elif phase[0] == HOLD:
        moved_sq = fall = 0.0
        for i in range(3):
            d = pos[i] - st.hold_pos[i]
            moved_sq += d * d
            fall += (st.hold_force[i] - pred[i]) * st.blocked_dir[i]
        if moved_sq > par.release_move_m * par.release_move_m or fall > par.growth_step_n:
            _start_window(st, pred, offset, w_slow, pos)
    if phase[0] == HOLD:
        _held(target, st, mask)


@njit(cache=True)
def _bound_rate_and_norm(w_ff, prev, lo, rate_max, norm_max) -> None:
    """w_ff[lo:lo+3]: change per tick at most rate_max, then norm at most norm_max."""
    d_sq = 0.0
    for i in range(lo, lo + 3):
        d_sq += (w_ff[i] - prev[i]) ** 2
    if d_sq > rate_max * rate_max:
        s = rate_max / math.sqrt(d_sq)
        for i in range(lo, lo + 3):
            w_ff[i] = prev[i] + (w_ff[i] - prev[i]) * s
    n_sq = w_ff[lo] ** 2 + w_ff[lo + 1] ** 2 + w_ff[lo + 2] ** 2
    if n_sq > norm_max * norm_max:
        s = norm_max / math.sqrt(n_sq)
        for i in range(lo, lo + 3):
            w_ff[i] *= s


@njit(cache=True, inline="always")
def guard_feedforward(w_ff, mask, st) -> None:
    """Apply the hold (learned force axes) and the bounds to this tick's feedforward ``w_ff``
    (6,) in place."""
    par = st.params
    if not par.enabled:
        return
    if st.phase[0] == HOLD:
        _held(w_ff, st, mask)
    prev = st.prev_ff
    _bound_rate_and_norm(w_ff, prev, 0, par.force_step_max_n, par.force_max_n)
    h_sq = w_ff[0] * w_ff[0] + w_ff[1] * w_ff[1]
    h_max = par.horizontal_force_max_n
    if h_sq > h_max * h_max:
        s = h_max / math.sqrt(h_sq)
        w_ff[0] *= s
        w_ff[1] *= s
    _bound_rate_and_norm(w_ff, prev, 3, par.torque_step_max_nm, par.torque_max_nm)
    for i in range(6):
        prev[i] = w_ff[i]


class ContactGuard:
    """The guard as a typed object: ``state`` (``GuardState``) from its config; ``reset`` per
    episode."""

    def __init__(self, config: ContactGuardConfig, dt_s: float, stiffness_n_per_m: float) -> None:
        self.config = config
        self.packed = make_guard_state(config, dt_s, stiffness_n_per_m)
        self.state = unpack_guard(self.packed.buffer, self.packed.scalars)[0]
        self.target = self.state.target

    @property
    def holding(self) -> bool:
        """Whether the force feedforward is held on this tick."""
        return bool(self.state.phase[0] == HOLD)

    @property
    def holds_started(self) -> int:
        """Holds started since the last ``reset``."""
        return int(self.state.holds_started[0])

    def reset(self) -> None:
        """Forget the window, any hold and the previous feedforward."""
        for value in self.state[1:]:
            value.fill(0.0)
