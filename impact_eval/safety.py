"""Contact with the scene as a safety measure: what counts, and how long and how hard.

What counts (``scene_contact``): the robot's contact force with the scene in full, and the
object's in excess of the weight the task declares as normal support
(``Task.supported_weight_n``: an object resting on the table or set down in the basket),
i.e. impacts, pressing and dragging. The env reports both raw; this module judges them.

The peak contact force of an episode is dominated by one instant (a hammer set down, a hand
striking an object); the measures here read the whole contact-force trace instead, sampled
every few ticks by the closed loop: the 95th percentile of the force and the time spent above
10 N and above 20 N. A press that ratchets shows in all three; setting a heavy object down
shows in the peak only. They are ``episodes.csv`` columns (``metrics.SUSTAINED_COLUMNS``),
computed from the env's per-tick contact traces (``info["contact_robot_trace_n"]`` /
``info["contact_object_trace_n"]``, one value per 1 ms tick: the closed loop samples the
contacts every ``CONTACT_EVERY`` = 4 ticks and on a step's last, each sample held over the
ticks since the previous one).

The sustained peak (``sustained_peak``, column ``peak_contact_sustained_n``) replaces the raw
peak as the safety measure of the summaries and plots: the highest force the contact stays at
or above for ``SUSTAINED_PEAK_WINDOW_S`` (50 ms) without a break, i.e. the maximum over t of
the minimum of the trace over [t, t + 50 ms]. It is in newtons like the peak, so the two read
side by side; an impact spike of a few ms does not reach it (one held-out 9.8 kg Hammer
episode peaked at 9.3 kN with 0.06 s above 20 N in all, and a rerun on another CPU moved such
peaks by up to 7 kN with the same outcomes), while a press or a drag held for 50 ms or more
shows in full. An impulse measure (the force integrated over a window) was not chosen: it
mixes force and duration, so a short hard hit and a long soft press read alike, and its unit
(N s) cannot be set beside the peak or a force threshold such as the reflex's 20 N.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

SUSTAINED_THRESHOLDS_N: tuple[float, ...] = (10.0, 20.0)
"""Force levels [N] whose time above is reported (``contact_over_10n_s``, ...)."""

SUSTAINED_PEAK_WINDOW_S = 0.05
"""How long [s] the contact must stay at a force level for ``sustained_peak`` to count it."""


def scene_contact(info: Mapping[str, object], object_trace: str = "contact_object_trace_n"
                  ) -> tuple[float | None, np.ndarray | None]:
    """``(peak [N], per-tick trace [N])`` of one env step's contact with the scene that
    counts (module docstring), from the step's ``info``: ``peak_robot_contact_force_n``,
    ``peak_object_contact_force_n``, their traces ``contact_robot_trace_n`` /
    ``object_trace`` and ``supported_weight_n`` (0 when absent). None for what the env does
    not report. ``object_trace="contact_object_net_trace_n"`` reads the object's net contact
    force in place of its normal sum (``NET_CONTACT_COLUMNS``)."""
    allowance = float(info.get("supported_weight_n", 0.0))  # type: ignore[arg-type]
    peak = trace = None
    if "peak_robot_contact_force_n" in info and "peak_object_contact_force_n" in info:
        peak = max(float(info["peak_robot_contact_force_n"]),  # type: ignore[arg-type]
                   float(info["peak_object_contact_force_n"]) - allowance, 0.0)  # type: ignore[arg-type]
    if "contact_robot_trace_n" in info and object_trace in info:
        robot = np.asarray(info["contact_robot_trace_n"], dtype=float)
        obj = np.asarray(info[object_trace], dtype=float)
        trace = np.maximum(np.maximum(robot, obj - allowance), 0.0)
    return peak, trace


def sustained_contact(samples_n: np.ndarray, period_s: float) -> dict[str, float]:
    """``contact_p95_n`` and ``contact_over_<X>n_s`` of a contact-force trace.

    Args:
        samples_n: Contact force [N] at equally spaced instants (any length; NaN-free).
        period_s: Time between samples [s] (> 0).

    Returns:
        The 95th percentile [N] (NaN for an empty trace) and the time [s] above each of
        ``SUSTAINED_THRESHOLDS_N`` (samples above the level times ``period_s``).
    """
    samples = _checked(samples_n, period_s)
    out = {"contact_p95_n": float(np.percentile(samples, 95)) if samples.size else math.nan}
    for level in SUSTAINED_THRESHOLDS_N:
        out[f"contact_over_{level:g}n_s"] = float(np.count_nonzero(samples > level) * period_s)
    return out


def window_samples(period_s: float, window_s: float = SUSTAINED_PEAK_WINDOW_S) -> int:
    """Samples that cover at least ``window_s`` when each is held for ``period_s``:
    ``ceil(window_s / period_s)`` (1e-9 of slack against rounding: 0.05 s at 1 ms is 50)."""
    if not period_s > 0.0:
        raise ValueError(f"period_s={period_s!r}; valid: > 0")
    return max(1, math.ceil(window_s / period_s - 1e-9))


def sustained_peak(samples_n: np.ndarray, period_s: float,
                   window_s: float = SUSTAINED_PEAK_WINDOW_S) -> float:
    """``peak_contact_sustained_n``: the highest force [N] the trace stays at or above for
    ``window_s`` without a break (module docstring).

    The maximum over the trace of its sliding-window minimum, the window being
    ``window_samples(period_s, window_s)`` samples (each sample held for ``period_s``, so the
    window spans at least ``window_s``). A trace shorter than the window gives its minimum (the
    force held over the whole episode); an empty trace gives NaN, as ``contact_p95_n`` does.

    Args:
        samples_n: Contact force [N] at equally spaced instants (any length; NaN-free).
        period_s: Time between samples [s] (> 0): 1 ms for the env's per-tick traces.
        window_s: The duration [s] the force must be held.
    """
    samples = _checked(samples_n, period_s)
    if not samples.size:
        return math.nan
    k = window_samples(period_s, window_s)
    if samples.size <= k:
        return float(samples.min())
    return float(sliding_window_view(samples, k).min(axis=1).max())


def _checked(samples_n: np.ndarray, period_s: float) -> np.ndarray:
    """``samples_n`` as a flat float array; ``ValueError`` for ``period_s <= 0`` or a
    non-finite sample."""
    samples = np.asarray(samples_n, dtype=float).ravel()
    if not period_s > 0.0:
        raise ValueError(f"period_s={period_s!r}; valid: > 0")
    if samples.size and not np.all(np.isfinite(samples)):
        raise ValueError("contact-force samples must be finite")
    return samples


NET_CONTACT_COLUMNS: tuple[str, ...] = ("contact_net_p95_n", "contact_net_over_20n_s")
"""``contact_p95_n`` and ``contact_over_20n_s`` with the object's **net** contact force (its
normals and friction summed as vectors, ``FrankaSim.object_net_contact``) in place of the sum
of its normals, less the same supported weight (issue 54's diagnostic columns, not in
``episodes.csv``): a body wedged in the basket, whose kilonewtons of normals cancel against
their friction, counts what it transmits, its weight, i.e. nothing beyond the support."""


def net_contact(scene_net_n: np.ndarray, period_s: float) -> dict[str, float]:
    """``NET_CONTACT_COLUMNS`` of an episode's scene-contact trace built with the object's
    net force (``scene_contact(info, "contact_object_net_trace_n")``)."""
    out = sustained_contact(scene_net_n, period_s)
    return {"contact_net_p95_n": out["contact_p95_n"],
            "contact_net_over_20n_s": out["contact_over_20n_s"]}


FF_PRESS_CONTACT_N = 20.0
"""Robot-environment normal force [N] above which a feedforward push counts (``ff_press``)."""

FF_PRESS_PUSH_N = 2.0
"""The feedforward's push toward the environment along the contact normal [N] above which
the controller counts as pressing (``ff_press``)."""

FF_PRESS_COLUMNS: tuple[str, ...] = ("ff_press_over_20n_s", "ff_press_mean_n")
"""The controller-attributed press (issue 54): its time [s] and its mean robot contact [N]."""


def ff_press(robot_n: np.ndarray, ff_into_n: np.ndarray, period_s: float) -> dict[str, float]:
    """The press the controller's feedforward takes part in: the time [s] during which the
    robot-environment normal force exceeds ``FF_PRESS_CONTACT_N`` **and** the force
    feedforward pushes more than ``FF_PRESS_PUSH_N`` toward the environment along that
    contact's normal (``info["ff_into_contact_trace_n"]``), and the mean robot contact force
    [N] over that time (NaN when there is none). Unlike ``contact_over_20n_s`` it does not
    count a press the impedance or the policy makes alone."""
    robot = _checked(robot_n, period_s)
    push = np.asarray(ff_into_n, dtype=float)
    if push.shape != robot.shape:
        raise ValueError(f"ff_press: traces of {robot.shape} and {push.shape} samples")
    pressing = (robot > FF_PRESS_CONTACT_N) & (push > FF_PRESS_PUSH_N)
    count = int(np.count_nonzero(pressing))
    return {"ff_press_over_20n_s": float(count * period_s),
            "ff_press_mean_n": float(robot[pressing].mean()) if count else math.nan}
