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
computed from the env's ``info["contact_force_trace_n"]``: per tick, each sample held over
the ticks since the previous one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

SUSTAINED_THRESHOLDS_N: tuple[float, ...] = (10.0, 20.0)
"""Force levels [N] whose time above is reported (``contact_over_10n_s``, ...)."""


def scene_contact(info: Mapping[str, object]) -> tuple[float | None, np.ndarray | None]:
    """``(peak [N], per-tick trace [N])`` of one env step's contact with the scene that
    counts (module docstring), from the step's ``info``: ``peak_robot_contact_force_n``,
    ``peak_object_contact_force_n``, their traces ``contact_robot_trace_n`` /
    ``contact_object_trace_n`` and ``supported_weight_n`` (0 when absent). None for what the
    env does not report."""
    allowance = float(info.get("supported_weight_n", 0.0))  # type: ignore[arg-type]
    peak = trace = None
    if "peak_robot_contact_force_n" in info and "peak_object_contact_force_n" in info:
        peak = max(float(info["peak_robot_contact_force_n"]),  # type: ignore[arg-type]
                   float(info["peak_object_contact_force_n"]) - allowance, 0.0)  # type: ignore[arg-type]
    if "contact_robot_trace_n" in info and "contact_object_trace_n" in info:
        robot = np.asarray(info["contact_robot_trace_n"], dtype=float)
        obj = np.asarray(info["contact_object_trace_n"], dtype=float)
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
    samples = np.asarray(samples_n, dtype=float).ravel()
    if not period_s > 0.0:
        raise ValueError(f"period_s={period_s!r}; valid: > 0")
    if samples.size and not np.all(np.isfinite(samples)):
        raise ValueError("contact-force samples must be finite")
    out = {"contact_p95_n": float(np.percentile(samples, 95)) if samples.size else math.nan}
    for level in SUSTAINED_THRESHOLDS_N:
        out[f"contact_over_{level:g}n_s"] = float(np.count_nonzero(samples > level) * period_s)
    return out
