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

import numpy as np
from numba import njit

from impact_envs.control.kernel_layout import _next
from impact_envs.control.validation import check_positive
from impact_envs.errors import InvalidArgumentError

GUARD_SIZE = 13 + 33 + 6
"""Length of the guard's float64 buffer (``guard_views``)."""
OPEN, WINDOW, WAIT, HOLD = 0.0, 1.0, 2.0, 3.0
"""Phases (state[0]): no window yet, window open, growth seen (waiting), holding."""


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


def guard_parameters(cfg: ContactGuardConfig, dt_s: float, stiffness_n_per_m: float) -> tuple:
    """The guard's ``par`` slots for ``cfg`` at control period ``dt_s`` and translational
    stiffness ``stiffness_n_per_m`` (the smallest diagonal entry: the most the TCP gives)."""
    return (float(cfg.enabled), cfg.growth_step_n, round(cfg.follow_delay_s / dt_s),
            cfg.give_fraction, cfg.follow_fraction, cfg.upward_cos, cfg.release_move_m,
            1.0 / stiffness_n_per_m, cfg.force_max_n, cfg.torque_max_nm,
            cfg.force_rate_max_n_per_s * dt_s, cfg.torque_rate_max_nm_per_s * dt_s,
            cfg.horizontal_force_max_n)


@njit(cache=True)
def guard_views(buf):
    """(par (13), state (33), target (6)) of the guard buffer.

    par = ``guard_parameters``; state = [phase, ticks waited, holds started, f0 (3), p0 (3),
    e0 (3), hold force (3), hold position (3), blocked direction u (3), previous feedforward (6),
    this tick's tracking offset (3), TCP position at the window's start (3)]; p0 is a
    tracking offset (TCP - target);
    target = this tick's training target (the slow wrench, force axes replaced by the hold).
    """
    par, o = _next(buf, 0, 13)
    state, o = _next(buf, o, 33)
    target, o = _next(buf, o, 6)
    return par, state, target


@njit(cache=True)
def _start_window(state, pred, offset, w_est, pos) -> None:
    state[0] = WINDOW
    for i in range(3):
        state[3 + i], state[6 + i], state[9 + i] = pred[i], offset[i], w_est[i]
        state[30 + i] = pos[i]


@njit(cache=True)
def _growth(state, pred, mask):
    """(g_x, g_y, g_z, |g|): growth of the predicted force since the window began, on the
    axes the model learns (a masked axis carries a commanded force, not a learned one)."""
    gx = (pred[0] - state[3]) if mask[0] != 0.0 else 0.0
    gy = (pred[1] - state[4]) if mask[1] != 0.0 else 0.0
    gz = (pred[2] - state[5]) if mask[2] != 0.0 else 0.0
    return gx, gy, gz, math.sqrt(gx * gx + gy * gy + gz * gz)


@njit(cache=True)
def _along(a, b, off, gx, gy, gz, size) -> float:
    """(a - b[off:off+3]) . g / |g|."""
    return ((a[0] - b[off]) * gx + (a[1] - b[off + 1]) * gy + (a[2] - b[off + 2]) * gz) / size


@njit(cache=True)
def _exempt(par, state, gx, gy, gz, size) -> bool:
    """Growth never held: upward (the lift ratchet), or mostly a decrease of the force the
    window began with (g against f0: the press it could build only gets smaller)."""
    if gz >= par[5] * size:
        return True
    f0x, f0y, f0z = state[3], state[4], state[5]
    f0 = math.sqrt(f0x * f0x + f0y * f0y + f0z * f0z)
    return gx * f0x + gy * f0y + gz * f0z <= -par[5] * size * f0


@njit(cache=True)
def _blocked(par, state, gx, gy, gz, size, offset, w_est, pos) -> bool:
    """Whether the TCP did not give along g (relative to its target), did not retreat
    against it either (an external force that just changed), while the estimate followed."""
    give = par[3] * size * par[7]
    moved = _along(offset, state, 6, gx, gy, gz, size)
    retreat = -_along(pos, state, 30, gx, gy, gz, size)
    follow = _along(w_est, state, 9, gx, gy, gz, size)
    return moved < give and retreat < give and follow >= par[4] * size


@njit(cache=True)
def _start_hold(state, ux, uy, uz, pos) -> None:
    """Hold f0 without any push along the blocked direction u: f0 - max(0, f0 . u) u."""
    state[0], state[1], state[2] = HOLD, 0.0, state[2] + 1.0
    push = max(0.0, state[3] * ux + state[4] * uy + state[5] * uz)
    state[12] = state[3] - push * ux
    state[13] = state[4] - push * uy
    state[14] = state[5] - push * uz
    state[15], state[16], state[17] = pos[0], pos[1], pos[2]
    state[18], state[19], state[20] = ux, uy, uz


@njit(cache=True)
def _held(w, state, mask) -> None:
    """w[:3] := the hold on learned axes, plus any rise of w_z above it (upward stays free)."""
    for i in range(3):
        if mask[i] != 0.0:
            w[i] = state[12 + i] + (max(0.0, w[i] - state[12 + i]) if i == 2 else 0.0)


@njit(cache=True)
def contact_guard_step(pred, pos, pos_target, w_slow, mask, buf) -> None:
    """Advance the blocked test; write the training target (``guard_views``).

    ``pos`` / ``pos_target``: TCP position and its target [m]: the give is measured on the
    tracking offset ``pos - pos_target``, so a moving target is not read as a give. ``mask``:
    the learning mask; masked force axes are neither tested nor held. ``w_slow``: the slow
    estimate (whose rise the test reads, and the training target it passes on).
    """
    par, state, target = guard_views(buf)
    for i in range(6):
        target[i] = w_slow[i]
    if par[0] == 0.0:
        return
    offset = state[27:30]
    for i in range(3):
        offset[i] = pos[i] - pos_target[i]
    if state[0] == OPEN:
        _start_window(state, pred, offset, w_slow, pos)
    gx, gy, gz, size = _growth(state, pred, mask)
    if state[0] == WINDOW and size >= par[1]:
        if _exempt(par, state, gx, gy, gz, size):
            _start_window(state, pred, offset, w_slow, pos)
        else:
            state[0], state[1] = WAIT, 0.0
    elif state[0] == WAIT:
        state[1] += 1.0
        if size < par[1]:
            state[0] = WINDOW  # the growth went away again: keep the window
        elif state[1] >= par[2]:
            exempt = _exempt(par, state, gx, gy, gz, size)  # re-checked: g may have turned
            if not exempt and _blocked(par, state, gx, gy, gz, size, offset, w_slow, pos):
                _start_hold(state, gx / size, gy / size, gz / size, pos)
            else:
                _start_window(state, pred, offset, w_slow, pos)
    elif state[0] == HOLD:
        moved_sq = fall = 0.0
        for i in range(3):
            d = pos[i] - state[15 + i]
            moved_sq += d * d
            fall += (state[12 + i] - pred[i]) * state[18 + i]
        if moved_sq > par[6] * par[6] or fall > par[1]:
            _start_window(state, pred, offset, w_slow, pos)
    if state[0] == HOLD:
        _held(target, state, mask)


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


@njit(cache=True)
def guard_feedforward(w_ff, mask, buf) -> None:
    """Apply the hold (learned force axes) and the bounds to this tick's feedforward ``w_ff``
    (6,) in place."""
    par, state, _ = guard_views(buf)
    if par[0] == 0.0:
        return
    if state[0] == HOLD:
        _held(w_ff, state, mask)
    prev = state[21:27]
    _bound_rate_and_norm(w_ff, prev, 0, par[10], par[8])
    h_sq = w_ff[0] * w_ff[0] + w_ff[1] * w_ff[1]
    if h_sq > par[12] * par[12]:
        s = par[12] / math.sqrt(h_sq)
        w_ff[0] *= s
        w_ff[1] *= s
    _bound_rate_and_norm(w_ff, prev, 3, par[11], par[9])
    for i in range(6):
        prev[i] = w_ff[i]


class ContactGuard:
    """The guard's buffer (``guard_views``) filled from its config; ``reset`` per episode."""

    def __init__(self, config: ContactGuardConfig, dt_s: float, stiffness_n_per_m: float) -> None:
        self.config = config
        self.buffer = np.zeros(GUARD_SIZE)
        self._par, self._state, self.target = guard_views(self.buffer)
        self._par[:] = guard_parameters(config, dt_s, stiffness_n_per_m)

    @property
    def holding(self) -> bool:
        """Whether the force feedforward is held on this tick."""
        return bool(self._state[0] == HOLD)

    @property
    def holds_started(self) -> int:
        """Holds started since the last ``reset``."""
        return int(self._state[2])

    def reset(self) -> None:
        """Forget the window, any hold and the previous feedforward."""
        self._state.fill(0.0)
        self.target.fill(0.0)
