"""The scalar payload model (payload_model.py) against values computed by hand from the
authors' rules (../shared/reference/authors_impact.md, their controller's lines 411-513)."""

from __future__ import annotations

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_control.payload_model import PayloadModel, PayloadModelConfig

DT = 0.001
DOWN = np.diag([1.0, -1.0, -1.0])
"""A top grasp: the TCP's z axis points down, so a held weight W reads w_hat_z = +W in the
world and -W along TCP z."""


def _model(**fields: object) -> PayloadModel:
    return PayloadModel(PayloadModelConfig(enabled=True, **fields), DT)


def _w(fz: float) -> np.ndarray:
    """A world wrench with force fz along world z."""
    return np.array([0.0, 0.0, fz, 0.0, 0.0, 0.0])


def _run(pm: PayloadModel, weight: float, slow: float, ticks: int) -> list[float]:
    """``ticks`` ticks at measured weight and slow-wrench z (world, N); the feedforward along
    world z of each."""
    return [float(pm.step(_w(weight), _w(slow), DOWN)[2]) for _ in range(ticks)]


def test_hold_begins_at_2_n_and_ends_the_tick_it_drops_below() -> None:
    pm = _model()
    _run(pm, 1.99, 0.0, 1)
    assert not pm.holding
    _run(pm, 2.0, 0.0, 1)
    assert pm.holding and pm.state.hold_time_s[0] == DT
    _run(pm, 1.999, 0.0, 1)  # re-tested every tick: no hysteresis
    assert not pm.holding and pm.state.hold_time_s[0] == 0.0


def test_feedforward_starts_on_the_500th_holding_tick() -> None:
    """The hold's clock adds dt per tick: 0.001 summed 500 times is 0.5000000000000003 >= 0.5
    (499 times: 0.49899999999999967)."""
    clock = 0.0
    for k in range(1, 501):
        clock += DT
        if k == 499:
            assert clock < 0.5
    assert clock >= 0.5
    pm = _model(feedforward="slow_wrench")
    ff = _run(pm, 10.0, 7.0, 500)
    assert ff[:499] == [0.0] * 499
    assert ff[499] == pytest.approx(7.0, abs=1e-12)  # w_slow's TCP z (-7) along TCP z: +7 up
    assert pm.state.hold_time_s[0] == clock
    _run(pm, 1.0, 7.0, 1)  # the hold ends: no feedforward, the clock restarts
    assert pm.state.feedforward_n[0] == 0.0 and pm.state.hold_time_s[0] == 0.0


@pytest.mark.parametrize(("weight", "kept"), [(39.9, False), (40.0, True)])
def test_reset_at_0_8_of_the_estimate_at_the_hold_off(weight: float, kept: bool) -> None:
    pm = _model()
    pm.state.estimate_n[0] = 50.0  # 0.8 x 50 = 40 N
    _run(pm, weight, weight, 499)  # the surprise stays below 5 N: no learning before
    assert pm.estimate_n == 50.0
    ff = _run(pm, weight, weight, 1)[0]
    assert pm.estimate_n == (50.0 if kept else 0.0)
    assert ff == pytest.approx(pm.estimate_n, abs=1e-12)  # -E along TCP z: +E up
    _run(pm, 30.0, 30.0, 10)  # tested once per hold: 30 < 40 no longer resets
    assert pm.estimate_n == (50.0 if kept else pytest.approx(0.0, abs=1e-9))


def test_surprise_lowpass_gates_learning_and_the_estimate_steps_by_1_percent() -> None:
    pm = _model()
    pm.state.slow_prev_tcp[2] = -50.0  # w_slow steady: rate 0
    _run(pm, 50.0, 50.0, 1)
    s_f = 1e-4 * 50.0
    assert pm.state.surprise_filtered_n[0] == pytest.approx(s_f, rel=1e-12)
    k, estimate = 1, 0.0
    while estimate == 0.0:  # by hand: s_f <- 0.9999 s_f + 1e-4 |W - E| until s_f >= 5 N
        k += 1
        s_f = (1.0 - 1e-4) * s_f + 1e-4 * 50.0
        if s_f >= 5.0:
            estimate = 0.01 * 50.0
    assert k == 1054  # ln(0.9) / ln(0.9999) = 1053.6
    _run(pm, 50.0, 50.0, k - 2)
    assert pm.estimate_n == 0.0
    _run(pm, 50.0, 50.0, 1)
    assert pm.estimate_n == pytest.approx(0.5, rel=1e-12)
    _run(pm, 50.0, 50.0, 1)
    assert pm.estimate_n == pytest.approx(0.5 + 0.01 * (50.0 - 0.5), rel=1e-12)
    _run(pm, 1.0, 50.0, 1)  # not holding: the surprise is zeroed, the estimate stays
    assert pm.state.surprise_filtered_n[0] == 0.0 and pm.estimate_n > 0.99


def test_estimate_is_clamped_to_100_n_and_learns_only_when_w_slow_is_quasi_steady() -> None:
    pm = _model()
    pm.state.estimate_n[0], pm.state.surprise_filtered_n[0] = 99.9, 10.0
    pm.state.slow_prev_tcp[2] = -500.0
    _run(pm, 500.0, 500.0, 1)  # 99.9 + 0.01 (500 - 99.9) = 103.9 -> 100
    assert pm.estimate_n == 100.0
    slow = _model()
    slow.state.estimate_n[0], slow.state.surprise_filtered_n[0] = 10.0, 10.0
    slow.state.slow_prev_tcp[2] = -20.0
    _run(slow, 20.0, 20.0 + 0.0001, 1)  # |dw_slow/dt| = 0.1 <= 0.2: learns
    learned = 10.0 + 0.01 * (20.0001 - 10.0)
    assert slow.estimate_n == pytest.approx(learned, rel=1e-12)
    _run(slow, 20.0, 20.0 + 0.0006, 1)  # 0.5 > 0.2: does not
    assert slow.estimate_n == pytest.approx(learned, rel=1e-12)
    assert slow.state.slow_rate[0] == pytest.approx(0.5, rel=1e-6)


def test_gripper_commanded_open_forces_the_hold_off() -> None:
    pm = _model()
    for cmd, holding in ((-1.0, False), (0.79, False), (0.8, True), (1.0, True)):
        pm.set_gripper_command(cmd)  # opening (1 - cmd) / 2 > 0.1 is "open"
        _run(pm, 50.0, 0.0, 1)
        assert pm.holding is holding, cmd
    as_coded_sim = _model(gripper_holdoff=False)  # their simulation never sees the command
    as_coded_sim.set_gripper_command(-1.0)
    _run(as_coded_sim, 50.0, 0.0, 1)
    assert as_coded_sim.holding
    with pytest.raises(InvalidArgumentError, match=r"valid: a number in \[-1, 1\]"):
        pm.set_gripper_command(float("nan"))


def test_feedforward_acts_along_the_tcp_z_axis_only() -> None:
    angle = 0.3
    c, s = np.cos(angle), np.sin(angle)
    rot = DOWN @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])  # tilted about x
    pm = _model()
    pm.state.estimate_n[0] = 20.0
    weight = 25.0  # along TCP z: w_hat . z_tcp = -25
    w_ext = np.r_[-weight * rot[:, 2], np.zeros(3)]
    for _ in range(500):
        ff = pm.step(w_ext, w_ext, rot)
    np.testing.assert_allclose(ff, np.r_[-20.0 * rot[:, 2], np.zeros(3)], atol=1e-12)


def test_bad_config_is_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="valid choices: estimate, slow_wrench"):
        PayloadModelConfig(feedforward="both")
    with pytest.raises(InvalidArgumentError, match=r"learning_rate 0.0; valid: \(0, 1\]"):
        PayloadModelConfig(learning_rate=0.0)
