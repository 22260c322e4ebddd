"""Sustained-contact measures (impact_eval/safety.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impact_eval.safety import sustained_contact


def test_a_growing_press_shows_in_every_measure_a_single_spike_in_none() -> None:
    t = np.arange(0.0, 8.0, 0.004)
    press = 9.0 + 12.0 * np.clip(t - 2.0, 0.0, None)  # ratchet: +12 N/s after 2 s
    spike = np.full_like(t, 5.0)
    spike[1000] = 600.0  # a hammer set down: one 4 ms sample
    p, s = sustained_contact(press, 0.004), sustained_contact(spike, 0.004)
    assert p["contact_p95_n"] > 70.0 and s["contact_p95_n"] == pytest.approx(5.0)
    assert p["contact_over_10n_s"] == pytest.approx(8.0 - 2.0 - 1.0 / 12.0, abs=0.01)
    assert p["contact_over_20n_s"] == pytest.approx(8.0 - 2.0 - 11.0 / 12.0, abs=0.01)
    assert s["contact_over_10n_s"] == pytest.approx(0.004) and s["contact_over_20n_s"] == 0.004


def test_empty_and_bad_traces() -> None:
    empty = sustained_contact(np.zeros(0), 0.004)
    assert math.isnan(empty["contact_p95_n"]) and empty["contact_over_20n_s"] == 0.0
    with pytest.raises(ValueError, match="period_s"):
        sustained_contact(np.ones(3), 0.0)
    with pytest.raises(ValueError, match="finite"):
        sustained_contact(np.array([1.0, np.nan]), 0.004)


def test_ff_press_counts_only_where_the_contact_is_hard_and_the_feedforward_pushes_into_it():
    from impact_eval.safety import ff_press

    robot = np.array([0.0, 25.0, 25.0, 25.0, 15.0, 40.0])
    push = np.array([5.0, 5.0, 1.0, -3.0, 5.0, 2.5])  # into the contact [N]
    out = ff_press(robot, push, 0.001)
    assert out["ff_press_over_20n_s"] == pytest.approx(0.002)  # samples 1 and 5 only
    assert out["ff_press_mean_n"] == pytest.approx(32.5)
    quiet = ff_press(robot, np.zeros(6), 0.001)
    assert quiet["ff_press_over_20n_s"] == 0.0 and np.isnan(quiet["ff_press_mean_n"])
    with pytest.raises(ValueError, match="traces"):
        ff_press(robot, push[:3], 0.001)


def test_a_wedged_object_counts_its_sum_of_normals_but_not_its_net_force():
    """A body jammed between floor and wall (docs/hammer_basket.md, "Contact after a
    success"): its normals sum to kilonewtons, its net force is its weight. The scene contact
    read with the net force (``NET_CONTACT_COLUMNS``) counts nothing beyond the support; a
    robot press still counts in full."""
    from impact_eval.safety import net_contact, scene_contact

    weight, n = 84.2, 8
    info = {"contact_robot_trace_n": np.zeros(n), "contact_object_trace_n": np.full(n, 2700.0),
            "contact_object_net_trace_n": np.full(n, weight + 0.5),
            "supported_weight_n": weight, "peak_robot_contact_force_n": 0.0,
            "peak_object_contact_force_n": 2700.0}
    _, normals = scene_contact(info)
    _, net = scene_contact(info, "contact_object_net_trace_n")
    assert normals == pytest.approx(2700.0 - weight) and net == pytest.approx(0.5)
    assert net_contact(net, 0.001) == {"contact_net_p95_n": pytest.approx(0.5),
                                       "contact_net_over_20n_s": 0.0}
    info["contact_robot_trace_n"] = np.full(n, 30.0)  # the hand presses: it counts
    assert net_contact(scene_contact(info, "contact_object_net_trace_n")[1], 0.001)[
        "contact_net_over_20n_s"] == pytest.approx(n * 0.001)
