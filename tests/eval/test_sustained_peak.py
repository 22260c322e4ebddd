"""The sustained peak contact force (``safety.sustained_peak``, ``peak_contact_sustained_n``),
the ``drawn_mass_kg`` / ``robot_profile`` columns, and older tables (issue 37, items 6-7)."""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from impact_control.errors import InvalidArgumentError
from impact_eval.csvio import EpisodeLog, encode_rows, older_columns_missing, read_rows
from impact_eval.metrics import ADDED_COLUMNS, EPISODE_COLUMNS, EpisodeTracker
from impact_eval.safety import SUSTAINED_PEAK_WINDOW_S, sustained_peak, window_samples

TICK = 1e-3
"""The env's per-tick traces: one value per 1 ms tick (``info["contact_trace_dt_s"]``)."""


def _trace(floor: float, level: float, start: int, ticks: int, n: int = 500) -> np.ndarray:
    """``n`` ticks at ``floor`` N with ``ticks`` ticks at ``level`` N from tick ``start``."""
    trace = np.full(n, floor)
    trace[start:start + ticks] = level
    return trace


def _reference(samples: np.ndarray, k: int) -> float:
    """Brute force: max over every start of the min of the ``k`` samples from there."""
    if len(samples) <= k:
        return float(min(samples))
    return max(min(samples[i:i + k]) for i in range(len(samples) - k + 1))


def test_the_window_is_50_ms_rounded_up_to_whole_samples() -> None:
    assert SUSTAINED_PEAK_WINDOW_S == 0.05
    assert window_samples(1e-3) == 50  # 0.05 / 0.001 is not taken as 50.000...1 -> 51
    assert window_samples(0.004) == 13  # 52 ms >= 50 ms, 12 samples would be 48 ms
    assert window_samples(0.0005) == 100 and window_samples(0.02) == 3
    assert window_samples(0.2) == 1  # one sample already spans the window
    with pytest.raises(ValueError, match="period_s"):
        window_samples(0.0)


def test_a_3_ms_spike_of_9_kn_on_a_5_n_floor_reads_the_floor() -> None:
    assert sustained_peak(_trace(5.0, 9000.0, 200, 3), TICK) == 5.0


def test_a_60_ms_plateau_reads_in_full_a_40_ms_one_not() -> None:
    assert sustained_peak(_trace(0.0, 40.0, 100, 60), TICK) == 40.0
    assert sustained_peak(_trace(0.0, 40.0, 100, 50), TICK) == 40.0  # exactly 50 ms counts
    assert sustained_peak(_trace(0.0, 40.0, 100, 49), TICK) == 0.0
    assert sustained_peak(_trace(3.0, 40.0, 100, 40), TICK) == 3.0
    # a plateau at the very start or end of the episode counts as well
    assert sustained_peak(_trace(0.0, 40.0, 0, 50), TICK) == 40.0
    assert sustained_peak(_trace(0.0, 40.0, 450, 50), TICK) == 40.0


def test_ramps() -> None:
    """A rising ramp of 1 N per tick over 200 ticks (0..199 N): the last 50 ticks stay at or
    above 150 N. A triangle 0 -> 100 -> 0 N: the best 50-tick window straddles the top,
    from tick 75 (75 N) to 124 (76 N), or 76 to 125: 75 N."""
    assert sustained_peak(np.arange(200.0), TICK) == 150.0
    triangle = 100.0 - np.abs(np.arange(201.0) - 100.0)
    assert sustained_peak(triangle, TICK) == 75.0


def test_a_sampling_period_above_one_tick() -> None:
    """Samples 4 ms apart, each held 4 ms: 13 samples (52 ms) make the window; 12 (48 ms) do
    not. The same trace held per tick (as the env reports it, ``CONTACT_EVERY`` = 4) at 1 ms
    gives the same, the window then being 50 ticks."""
    four_ms = 0.004
    assert sustained_peak(_trace(2.0, 30.0, 20, 13, n=100), four_ms) == 30.0
    assert sustained_peak(_trace(2.0, 30.0, 20, 12, n=100), four_ms) == 2.0
    held = np.repeat(_trace(2.0, 30.0, 20, 13, n=100), 4)  # 52 ticks at 30 N
    assert sustained_peak(held, TICK) == 30.0
    held = np.repeat(_trace(2.0, 30.0, 20, 12, n=100), 4)  # 48 ticks at 30 N
    assert sustained_peak(held, TICK) == 2.0


def test_short_empty_and_bad_traces() -> None:
    """Shorter than the window: the force held over the whole episode, its minimum."""
    assert sustained_peak(np.array([10.0, 30.0, 20.0]), TICK) == 10.0
    assert sustained_peak(np.array([7.0]), TICK) == 7.0
    assert sustained_peak(np.full(50, 4.0), TICK) == 4.0  # exactly one window
    assert math.isnan(sustained_peak(np.zeros(0), TICK))  # as contact_p95_n
    with pytest.raises(ValueError, match="period_s"):
        sustained_peak(np.ones(3), 0.0)
    with pytest.raises(ValueError, match="finite"):
        sustained_peak(np.array([1.0, np.nan]), TICK)


@pytest.mark.parametrize("period_s", [1e-3, 0.004, 0.03])
def test_matches_a_brute_force_sliding_minimum(period_s: float) -> None:
    rng = np.random.default_rng(0)
    for n in (1, 12, 13, 14, 60, 333):
        samples = rng.exponential(20.0, n) * (rng.uniform(size=n) < 0.7)
        assert sustained_peak(samples, period_s) == _reference(samples, window_samples(period_s))


def _step_info(trace: list[float], **extra: object) -> dict[str, object]:
    return {"contact_robot_trace_n": np.array(trace),
            "contact_object_trace_n": np.zeros(len(trace)), "contact_trace_dt_s": TICK,
            "peak_robot_contact_force_n": max(trace), "peak_object_contact_force_n": 0.0,
            **extra}


def test_tracker_joins_the_steps_traces_and_keeps_the_raw_peak() -> None:
    """A press of 40 N from tick 10 of one 34-tick step to tick 29 of the next (54 ticks)
    counts in full across the step boundary; a 3-tick 900 N hit raises the raw peak only."""
    tracker = EpisodeTracker(policy_dt=1 / 30)
    tracker.update(_step_info([0.0] * 10 + [40.0] * 24, object_mass=3.5, robot_profile="ideal"))
    tracker.update(_step_info([40.0] * 30 + [900.0] * 3, object_mass=3.5, robot_profile="ideal"))
    tracker.finish("timeout")
    row = tracker.row()
    assert row["peak_contact_sustained_n"] == 40.0 and row["peak_contact_force_n"] == 900.0
    assert row["drawn_mass_kg"] == 3.5 and row["robot_profile"] == "ideal"
    assert set(row) == set(EPISODE_COLUMNS) - {"method", "env_id", "param_name", "param_value",
                                                "seed", "episode"}


def test_tracker_setup_columns_from_reset_and_when_unreported() -> None:
    """The reset's info alone (an episode that crashed at its first step) still gives the
    mass and profile; an env that reports neither gives NaN and ``""``; no trace, NaN."""
    tracker = EpisodeTracker(policy_dt=1 / 30)
    tracker.start({"object_mass": 9.8, "robot_profile": "fr3"})
    tracker.finish("exception: RuntimeError")
    row = tracker.row()
    assert row["drawn_mass_kg"] == 9.8 and row["robot_profile"] == "fr3"
    assert math.isnan(row["peak_contact_sustained_n"])
    bare = EpisodeTracker(policy_dt=1 / 30)
    bare.start(None)
    bare.update({})
    bare.finish("timeout")
    row = bare.row()
    assert math.isnan(row["drawn_mass_kg"]) and row["robot_profile"] == ""


def test_the_env_reports_the_mass_it_set_and_its_robot_profile() -> None:
    import gymnasium as gym

    import impact_envs  # noqa: F401 - registers the envs

    env = gym.make("IMPACT/Hammer-v1")
    try:
        _, info = env.reset(seed=0, options={"object_mass": 3.5})
        assert info["object_mass"] == 3.5 and info["robot_profile"] == "ideal"
        body = env.unwrapped.task.mass.id
        assert env.unwrapped.sim.model.body_mass[body] == 3.5  # what the env actually used
        env.unwrapped.robot_profile = "fr3"  # what a later RobotOptions(realism=...) sets
        assert env.reset(seed=0)[1]["robot_profile"] == "fr3"
    finally:
        env.close()


# --- older tables: resume refuses them in one line, the report reads them --------------------

def _row(value: float, episode: int) -> dict[str, object]:
    row: dict[str, object] = dict.fromkeys(EPISODE_COLUMNS, 1.0)
    row.update(method="impact", env_id="IMPACT/Hammer-v1", param_name="object_mass",
               param_value=value, seed=episode, episode=episode, success=episode % 2,
               success_once=1, length=30, failure_reason="", robot_profile="ideal",
               drawn_mass_kg=value, peak_contact_force_n=900.0 + episode,
               peak_contact_sustained_n=20.0 + episode)
    return row


def _write_without(path: Path, dropped: tuple[str, ...]) -> None:
    """An episodes.csv as an impact-eval without the ``dropped`` columns wrote it."""
    rows = [_row(v, e) for v in (1.0, 3.5) for e in range(3)]
    df = pd.read_csv(io.StringIO(encode_rows(rows)), keep_default_na=False)
    df.drop(columns=list(dropped)).to_csv(path, index=False)


@pytest.mark.parametrize("date", ["2026-11-27", "both"])
def test_resume_refuses_an_older_table_in_one_line(tmp_path: Path, date: str) -> None:
    dropped = ADDED_COLUMNS["2026-11-27"] + (ADDED_COLUMNS["2026-11-26"] if date == "both"
                                             else ())
    path = tmp_path / "episodes.csv"
    _write_without(path, dropped)
    with pytest.raises(InvalidArgumentError) as err:
        read_rows(path)
    message = str(err.value)
    assert "\n" not in message and "older impact-eval" in message
    assert "cannot be resumed" in message and all(c in message for c in dropped)
    assert older_columns_missing(EPISODE_COLUMNS) is None
    assert older_columns_missing(("a", "b")) is None
    partial = tuple(c for c in EPISODE_COLUMNS if c != "robot_profile")  # not a whole date's
    assert older_columns_missing(partial) is None


def test_a_table_written_now_resumes(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    log = EpisodeLog(path)
    log.open()
    log.append(_row(2.0, 0))
    log.close()
    (row,) = read_rows(path)
    assert row["drawn_mass_kg"] == "2.0" and row["robot_profile"] == "ideal"
    assert row["peak_contact_sustained_n"] == "20.0"


def test_the_report_reads_a_table_without_the_new_columns(tmp_path: Path, monkeypatch) -> None:
    from impact_eval import plots_outcome
    from impact_eval.report import load_episodes, summarize

    _write_without(tmp_path / "episodes.csv", ADDED_COLUMNS["2026-11-27"])
    episodes = load_episodes(tmp_path)
    summary = summarize(episodes)
    assert summary["peak_contact_sustained_mean_n"].isna().all()
    assert summary["peak_contact_force_mean_n"].tolist() == [901.0, 901.0]
    assert plots_outcome.safety_peak_column(episodes)[0] == "peak_contact_force_n"
    drawn: list[list[str]] = []
    monkeypatch.setattr(plots_outcome, "save_figure", lambda fig, out, stem: drawn.append(
        [ax.get_ylabel() for ax in fig.axes]) or [])
    plots_outcome.plot_safety(episodes, summary, tmp_path, "safety")
    assert any("no sustained peak" in label for label in drawn[0])


def test_the_report_summarises_and_draws_the_sustained_peak(tmp_path: Path, monkeypatch) -> None:
    from impact_eval import plots_outcome
    from impact_eval.report import SUMMARY_COLUMNS, load_episodes, summarize

    (tmp_path / "episodes.csv").write_text(
        encode_rows([_row(v, e) for v in (1.0, 3.5) for e in range(3)]))
    episodes = load_episodes(tmp_path)
    summary = summarize(episodes)
    assert summary["peak_contact_sustained_mean_n"].tolist() == [21.0, 21.0]
    assert summary["peak_contact_force_mean_n"].tolist() == [901.0, 901.0]
    order = list(SUMMARY_COLUMNS)
    assert order.index("peak_contact_sustained_mean_n") < order.index("peak_contact_force_mean_n")
    assert episodes["robot_profile"].tolist() == ["ideal"] * 6
    drawn: list[list[str]] = []
    monkeypatch.setattr(plots_outcome, "save_figure", lambda fig, out, stem: drawn.append(
        [ax.get_ylabel() for ax in fig.axes]) or [])
    plots_outcome.plot_safety(episodes, summary, tmp_path, "safety")
    labels = drawn[0]
    assert any("held 50 ms" in label for label in labels)
    assert not any(label.startswith(("peak contact force [N]", "raw")) for label in labels)
