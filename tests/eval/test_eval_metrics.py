"""Wilson intervals, episode metrics and the lockstep rollout (with the fake env)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from fixtures.eval_fake import BARE_ID, FakePolicy

from impact_eval.metrics import EpisodeTracker, fisher_two_sided, wilson_interval
from impact_eval.rollout import EpisodeJob, LockstepBatch
from impact_eval.safety import scene_contact


@pytest.mark.parametrize(
    ("k", "n", "low", "high"),
    [  # reference values: statsmodels proportion_confint(k, n, method="wilson")
        (0, 10, 0.0, 0.2775327998628892),
        (5, 10, 0.2365930905493394, 0.7634069094506606),
        (10, 10, 0.7224672001371108, 1.0),
        (1, 20, 0.008881, 0.2361311),
    ],
)
def test_wilson_interval_known_values(k: int, n: int, low: float, high: float) -> None:
    got = wilson_interval(k, n)
    assert got == pytest.approx((low, high), abs=1e-6)


@pytest.mark.parametrize(("k", "n"), [(0, 7), (3, 20), (81, 263), (50, 50)])
def test_wilson_bounds_invert_the_score_test(k: int, n: int) -> None:
    z2 = 1.959963984540054**2
    for p in wilson_interval(k, n):
        assert (k / n - p) ** 2 == pytest.approx(z2 * p * (1 - p) / n, abs=1e-12)
    assert wilson_interval(0, n)[1] == pytest.approx(z2 / (n + z2))


def test_wilson_interval_edge_cases() -> None:
    assert all(math.isnan(v) for v in wilson_interval(0, 0))
    with pytest.raises(ValueError):
        wilson_interval(3, 2)


def test_tracker_missing_info_keys_give_nan() -> None:
    tracker = EpisodeTracker(policy_dt=0.5)
    tracker.update({})
    tracker.update({"is_success": True, "energy_j": 2.0, "peak_torque_nm": [1.0, 7.0]})
    tracker.update({"is_success": False, "energy_j": 3.0, "peak_torque_nm": 4.0})
    tracker.finish("timeout")
    row = tracker.row()
    assert row["success"] == 0 and row["success_once"] == 1
    assert row["length"] == 3 and row["time_to_success_s"] == 1.0
    assert row["energy_j"] == 5.0 and row["peak_torque_nm"] == 7.0
    assert math.isnan(row["peak_contact_force_n"]) and math.isnan(row["mean_pose_error_m"])
    assert row["failure_reason"] == "timeout"


def test_tracker_sustained_contact_columns_from_the_per_tick_trace() -> None:
    """Two steps of 4 ticks at 1 ms: 3 ticks above 10 N, 2 above 20 N; p95 of the 8 ticks."""
    tracker = EpisodeTracker(policy_dt=0.004)
    for trace in ([0.0, 12.0, 25.0, 5.0], [30.0, 1.0, 0.0, 0.0]):
        tracker.update({"contact_robot_trace_n": np.array(trace),
                        "contact_object_trace_n": np.zeros(4), "contact_trace_dt_s": 1e-3})
    tracker.finish("timeout")
    row = tracker.row()
    assert row["contact_over_10n_s"] == pytest.approx(3e-3)
    assert row["contact_over_20n_s"] == pytest.approx(2e-3)
    assert row["contact_p95_n"] == pytest.approx(
        np.percentile([0, 12, 25, 5, 30, 1, 0, 0], 95))


def test_scene_contact_counts_the_object_beyond_its_declared_support() -> None:
    """The robot's contact counts in full, the object's beyond ``supported_weight_n``."""
    info = {"peak_robot_contact_force_n": 3.0, "peak_object_contact_force_n": 30.0,
            "contact_robot_trace_n": np.array([3.0, 0.0]),
            "contact_object_trace_n": np.array([19.6, 30.0]), "supported_weight_n": 19.6}
    peak, trace = scene_contact(info)
    assert peak == pytest.approx(10.4) and trace == pytest.approx([3.0, 10.4])
    assert scene_contact({**info, "supported_weight_n": 40.0})[0] == 3.0
    assert scene_contact({}) == (None, None)


@pytest.mark.parametrize("env_id", ["IMPACT/Hammer-v1", "IMPACT/Dumbbell-v1",
                                    "IMPACT/Calligraphy-v1", "IMPACT/Disturbance-v1"])
def test_each_task_declares_its_supported_weight(env_id) -> None:
    env = gym.make(env_id)
    _, info = env.reset(seed=0)
    task = env.unwrapped.task
    mass = info.get("object_mass")
    expected = 0.0 if env_id == "IMPACT/Calligraphy-v1" else 9.81 * mass
    assert info["supported_weight_n"] == task.supported_weight_n(env.unwrapped._episode_params)
    assert info["supported_weight_n"] == pytest.approx(expected)
    env.close()


def test_env_contact_trace_is_per_tick_and_peaks_at_the_peak() -> None:
    from impact_control.policy import stack_obs
    from impact_envs.policies.experts import make_expert

    env, expert = gym.make("IMPACT/Hammer-v1"), make_expert("IMPACT/Hammer-v1")
    obs, _ = env.reset(seed=3)
    expert.reset(1)
    peaks = []
    for _ in range(150):  # the expert grasps the hammer and strikes the nail
        obs, _, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
        peak, trace = scene_contact(info)
        assert trace.shape in ((33,), (34,)) and info["contact_trace_dt_s"] == 1e-3
        assert trace.min() >= 0.0 and trace.max() == peak
        peaks.append(trace.max())
    assert max(peaks) > 10.0  # a real contact
    env.close()


def test_tracker_success_and_crash() -> None:
    ok = EpisodeTracker(policy_dt=0.1)
    ok.update({"is_success": True, "pose_error_m": 0.2})
    ok.finish("terminated")
    assert ok.row()["failure_reason"] == "" and ok.row()["success"] == 1
    crashed = EpisodeTracker(policy_dt=0.1)
    crashed.update({"is_success": True})
    crashed.finish("unstable: NaN\nin qacc")
    assert crashed.row()["success"] == 0 and crashed.row()["success_once"] == 1
    assert crashed.row()["failure_reason"] == "unstable: NaN in qacc"


def _run_batch(masses: list[float]) -> dict[int, dict[str, object]]:
    envs = [gym.make(BARE_ID, controller="impedance") for _ in masses]
    rows: dict[int, dict[str, object]] = {}
    jobs = [EpisodeJob(m, 100 + i, i) for i, m in enumerate(masses)]
    LockstepBatch(envs, FakePolicy(0.9), "object_mass", 1 / 30).run(
        jobs, lambda i, row: rows.__setitem__(i, row)
    )
    return rows


def test_lockstep_batch_records_crashes_and_goes_on() -> None:
    rows = _run_batch([0.5, 66.0, 77.0, 88.0, 1.0])
    assert sorted(rows) == [0, 1, 2, 3, 4]
    assert rows[1]["failure_reason"] == "unstable: qacc diverged at t=0.1 s"
    assert rows[2]["failure_reason"] == "exception: RuntimeError"
    assert rows[3]["failure_reason"] == "unstable: non-finite observation"
    assert rows[1]["length"] == 2 and rows[3]["length"] == 3
    for i in (0, 4):
        assert rows[i]["length"] > 3
        assert rows[i]["failure_reason"] in ("", "timeout")


def test_lockstep_batch_is_reproducible() -> None:
    first, second = _run_batch([0.5, 2.0, 4.0]), _run_batch([0.5, 2.0, 4.0])
    assert first == second
    assert np.isfinite([r["energy_j"] for r in first.values()]).all()


def test_fisher_matches_textbook_values() -> None:
    assert fisher_two_sided(3, 4, 1, 4) == pytest.approx(0.4857, abs=1e-4)  # the lady tasting tea
    assert fisher_two_sided(10, 10, 0, 10) == pytest.approx(2 / 184756, rel=1e-9)
    assert fisher_two_sided(5, 10, 5, 10) == pytest.approx(1.0)
