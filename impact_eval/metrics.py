"""Per-episode metrics (one ``episodes.csv`` row) and binomial confidence intervals."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from impact_envs.tasks.bins import MASS_PARAM
from impact_eval.safety import (
    FF_PRESS_COLUMNS,
    NET_CONTACT_COLUMNS,
    ff_press,
    net_contact,
    scene_contact,
    sustained_contact,
    sustained_peak,
)

EPISODE_COLUMNS: tuple[str, ...] = (
    "method",
    "env_id",
    "param_name",
    "param_value",
    "seed",
    "episode",
    "success",
    "success_once",
    "length",
    "time_to_success_s",
    "energy_j",
    "peak_torque_nm",
    "peak_contact_force_n",
    "peak_contact_sustained_n",
    "contact_p95_n",
    "contact_over_10n_s",
    "contact_over_20n_s",
    "mean_pose_error_m",
    "drawn_mass_kg",
    "robot_profile",
    "failure_reason",
)
"""Columns of ``episodes.csv``, in file order. No wall-clock values (the file is deterministic)."""

SUSTAINED_COLUMNS: tuple[str, ...] = ("contact_p95_n", "contact_over_10n_s", "contact_over_20n_s")
"""The sustained-contact columns (``safety.sustained_contact``), added on 2026-11-26."""

SUSTAINED_PEAK_COLUMN = "peak_contact_sustained_n"
"""The safety measure of the summaries and plots (``safety.sustained_peak``)."""

EPISODE_INFO_COLUMNS: tuple[str, ...] = ("drawn_mass_kg", "robot_profile")
"""What the env used in the episode, as its ``info`` reports it: ``drawn_mass_kg`` from
``info[<the task's mass parameter>]`` (``object_mass``, Calligraphy's ``tool_mass``: the mass
the env set for the episode [kg]; ``info["object_mass"]`` for an env without a task; NaN
when the env reports none) and ``robot_profile`` from ``info["robot_profile"]`` (the simulated
robot's profile, ``"ideal"`` for every IMPACT env today; ``""`` when the env reports none)."""

ROBOT_PROFILE_INFO_KEY = "robot_profile"

ADDED_COLUMNS: dict[str, tuple[str, ...]] = {
    "2026-11-26": SUSTAINED_COLUMNS,
    "2026-11-27": (SUSTAINED_PEAK_COLUMN, *EPISODE_INFO_COLUMNS),
}
"""Columns added to ``episodes.csv`` after its first version, by date: a file without them was
written by an older impact-eval (``csvio.read_rows`` refuses to resume it; the report reads a
file lacking only the newest ones, ``report.OPTIONAL_COLUMNS``)."""

Z_95 = 1.959963984540054
"""Two-sided 95 % standard-normal quantile."""

MAX_REASON_CHARS = 200
"""``failure_reason`` is cut to this length and kept on one line."""


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion.

    Args:
        successes: number of successes ``k`` (0 <= k <= n).
        n: number of trials; ``n == 0`` gives ``(nan, nan)``.
        z: normal quantile (1.96 for 95 %).

    Returns:
        ``(low, high)`` in [0, 1].
    """
    if n <= 0:
        return math.nan, math.nan
    if not 0 <= successes <= n:
        raise ValueError(f"successes={successes} outside [0, n={n}]")
    p = successes / n
    z2 = z * z
    denom = 1.0 + z2 / n
    center = (p + z2 / (2 * n)) / denom
    half = z / denom * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n))
    return max(0.0, center - half), min(1.0, center + half)


def fisher_two_sided(k1: int, n1: int, k2: int, n2: int) -> float:
    """Two-sided Fisher exact test p of a 2 x 2 table (successes k of n, two groups): the
    summed probability of every table with the same margins no likelier than this one."""
    total, ones = n1 + n2, k1 + k2
    denom = math.comb(total, n1)

    def prob(a: int) -> float:
        return math.comb(ones, a) * math.comb(total - ones, n1 - a) / denom

    observed = prob(k1)
    support = range(max(0, ones - n2), min(ones, n1) + 1)
    return min(1.0, sum(p for p in map(prob, support) if p <= observed * (1 + 1e-9)))


def one_line(text: str) -> str:
    """Collapse whitespace to single spaces and cut to ``MAX_REASON_CHARS``."""
    return " ".join(str(text).split())[:MAX_REASON_CHARS]


def _reduce(value: object, how: str) -> float | None:
    """Reduce a scalar or array info value to one float (``None`` when empty or not numeric)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    if arr.size == 0:
        return None
    return float({"sum": np.sum, "max": np.max, "mean": np.mean}[how](arr))


@dataclass
class EpisodeTracker:
    """Accumulates one episode's step ``info`` dicts into an ``episodes.csv`` row.

    Missing info keys give NaN, never an error. ``policy_dt`` [s] converts the step index of the
    first success into ``time_to_success_s``.
    """

    policy_dt: float
    length: int = 0
    success: bool = False
    first_success_step: int | None = None
    failure_reason: str | None = None
    _energy: list[float] = field(default_factory=list)
    _peak_torque: list[float] = field(default_factory=list)
    _peak_force: list[float] = field(default_factory=list)
    _pose_error: list[float] = field(default_factory=list)
    _contact: list[np.ndarray] = field(default_factory=list)
    _contact_dt: float = math.nan
    _robot_contact: list[np.ndarray] = field(default_factory=list)
    _ff_into_contact: list[np.ndarray] = field(default_factory=list)
    _contact_net: list[np.ndarray] = field(default_factory=list)
    mass_key: str = MASS_PARAM
    """The ``info`` key of the env's mass (``bins.mass_info_key``)."""
    _drawn_mass: float = math.nan
    _robot_profile: str = ""

    @property
    def done(self) -> bool:
        """True once the episode ended (``finish`` was called)."""
        return self.failure_reason is not None

    def start(self, info: object) -> None:
        """Record the ``info`` of the episode's ``reset`` (the mass and robot profile the env
        set up: an episode that crashes before its first step still reports them); anything
        but a mapping is ignored."""
        if isinstance(info, Mapping):
            self._note_setup(info)

    def _note_setup(self, info: Mapping[str, object]) -> None:
        """Keep the latest ``EPISODE_INFO_COLUMNS`` values ``info`` reports."""
        if self.mass_key in info:
            mass = _reduce(info[self.mass_key], "max")
            self._drawn_mass = math.nan if mass is None else mass
        if ROBOT_PROFILE_INFO_KEY in info:
            self._robot_profile = one_line(str(info[ROBOT_PROFILE_INFO_KEY]))

    def update(self, info: Mapping[str, object]) -> None:
        """Record the ``info`` of one env step."""
        self._note_setup(info)
        self.length += 1
        self.success = bool(info.get("is_success", False))
        if self.success and self.first_success_step is None:
            self.first_success_step = self.length
        for key, how, store in (
            ("energy_j", "sum", self._energy),
            ("peak_torque_nm", "max", self._peak_torque),
            ("pose_error_m", "mean", self._pose_error),
        ):
            if key in info and (value := _reduce(info[key], how)) is not None:
                store.append(value)
        peak, trace = scene_contact(info)
        if peak is not None:
            self._peak_force.append(peak)
        if trace is not None and "contact_trace_dt_s" in info:
            self._contact.append(trace)
            self._contact_dt = float(info["contact_trace_dt_s"])  # type: ignore[arg-type]
        if "ff_into_contact_trace_n" in info and "contact_robot_trace_n" in info:
            self._robot_contact.append(np.asarray(info["contact_robot_trace_n"], dtype=float))
            self._ff_into_contact.append(
                np.asarray(info["ff_into_contact_trace_n"], dtype=float))
        if "contact_object_net_trace_n" in info:
            self._contact_net.append(scene_contact(info, "contact_object_net_trace_n")[1])

    def finish(self, reason: str) -> None:
        """End the episode: ``reason`` is "timeout", "terminated", "unstable: …" or "exception: …".

        An episode that ended normally while successful gets reason ``""``; one that crashed
        counts as a failure even if it succeeded earlier (``success_once`` keeps that).
        """
        crashed = reason.startswith(("unstable", "exception"))
        if crashed:
            self.success = False
        self.failure_reason = "" if self.success else one_line(reason)

    def row(self) -> dict[str, object]:
        """Metric columns of the row (the caller adds method, env, value, seed, episode)."""
        if not self.done:
            raise RuntimeError("row() before finish()")
        step = self.first_success_step
        return {
            "success": int(self.success),
            "success_once": int(step is not None),
            "length": self.length,
            "time_to_success_s": math.nan if step is None else step * self.policy_dt,
            "energy_j": math.fsum(self._energy) if self._energy else math.nan,
            "peak_torque_nm": float(np.max(self._peak_torque)) if self._peak_torque else math.nan,
            "peak_contact_force_n": (
                float(np.max(self._peak_force)) if self._peak_force else math.nan
            ),
            **self._sustained(),
            "mean_pose_error_m": float(np.mean(self._pose_error)) if self._pose_error else math.nan,
            "drawn_mass_kg": self._drawn_mass,
            "robot_profile": self._robot_profile,
            "failure_reason": self.failure_reason,
        }

    def press_diagnostics(self) -> dict[str, float]:
        """``safety.FF_PRESS_COLUMNS`` (the press the feedforward takes part in,
        ``safety.ff_press``) and ``safety.NET_CONTACT_COLUMNS`` (the scene contact with the
        object's net force) of the episode: issue 54's diagnostic columns, not in
        ``episodes.csv``; NaN when the env gives no traces."""
        if not self._ff_into_contact or not self._contact_net:
            return dict.fromkeys((*FF_PRESS_COLUMNS, *NET_CONTACT_COLUMNS), math.nan)
        return {**ff_press(np.concatenate(self._robot_contact),
                           np.concatenate(self._ff_into_contact), self._contact_dt),
                **net_contact(np.concatenate(self._contact_net), self._contact_dt)}

    def _sustained(self) -> dict[str, float]:
        """``peak_contact_sustained_n``, ``contact_p95_n`` and ``contact_over_*`` of the
        episode's per-tick contact trace (``safety.sustained_peak``, ``sustained_contact``);
        NaN when the env gives no trace."""
        if not self._contact:
            return dict.fromkeys((SUSTAINED_PEAK_COLUMN, *SUSTAINED_COLUMNS), math.nan)
        trace = np.concatenate(self._contact)
        return {SUSTAINED_PEAK_COLUMN: sustained_peak(trace, self._contact_dt),
                **sustained_contact(trace, self._contact_dt)}
