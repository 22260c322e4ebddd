"""Contact guard and feedforward bounds (``control/contact_guard.py``), tested with physics."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from impact_control.config import ContactGuardConfig, ControllerConfig
from impact_control.contact_guard import ContactGuard, guard_feedforward
from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError
from impact_control.ik import HOME_Q
from impact_control.presets import preset_config
from impact_experiments.physics import Rig
from impact_experiments.press import press

GUARD_ON = ContactGuardConfig(enabled=True)


def test_guard_keeps_a_rigid_press_at_the_impedance_force() -> None:
    """A closed hand held 30 mm inside a rigid plate tilted by 40 deg: `default` without its
    guard ratchets the press up; with it (as shipped) the steady force stays within 3 N of
    impedance's and does not grow after 2 s."""
    ref = press("impedance", 40.0, 0.03, 4.0, seed=1)
    guarded = press("impact", 40.0, 0.03, 4.0, seed=1)
    unguarded = press("impact_unguarded", 40.0, 0.03, 4.0, seed=1)
    assert ref["steady_force_n"] > 10.0  # it is a real press
    assert guarded["steady_force_n"] <= ref["steady_force_n"] + 3.0
    assert abs(guarded["growth_after_2s_n"]) < 0.5 and guarded["holds"] >= 1
    assert unguarded["steady_force_n"] > ref["steady_force_n"] + 20.0  # the ratchet


def test_guard_lets_the_model_learn_a_force_that_gives() -> None:
    """A constant 20 N sideways pull on the free hand: the TCP gives when the feedforward
    grows, so the guard does not hold it (a hold at the turning point of the first swing ends
    when the TCP moves) and the model learns to cancel the pull."""
    rig = Rig.build("payload_scene.xml", "impact", "residual", seed=2)
    cfg = replace(ControllerConfig(), guard=GUARD_ON)
    rig = Rig(rig.sim, rig.arm, ImpactController(rig.arm, cfg, mode="impact"), rig.rng)
    rig.sim.model.body_mass[rig.sim.model.body("payload").id] = 1e-6
    pos, quat = rig.start(HOME_Q)
    rig.run(pos, quat, 0.3)
    rig.run(pos, quat, 3.0, wrench_on_tcp=(np.array([0.0, 20.0, 0.0]), np.zeros(3)))
    ctrl = rig.controller
    assert not ctrl.guard.holding and ctrl.guard.holds_started <= 1
    assert ctrl.signals.wrench_ff_world[1] == pytest.approx(-20.0, abs=2.0)  # robot-on-env
    assert abs(rig.sim.tcp_pose()[0][1] - pos[1]) < 8e-3  # impedance alone: 50 mm


def test_bounds_limit_the_rate_and_size_of_the_feedforward() -> None:
    guard = ContactGuard(GUARD_ON, 0.001, 400.0)
    applied = []
    for _ in range(400):
        w = np.array([400.0, 0.0, -300.0, 0.0, 60.0, 0.0])
        guard_feedforward(w, np.ones(6), guard.state)
        applied.append(w.copy())
    applied = np.asarray(applied)
    steps = np.linalg.norm(np.diff(applied[:, :3], axis=0), axis=1)
    assert steps.max() <= 1.0 + 1e-12  # 1000 N/s
    assert np.linalg.norm(applied[0, 3:]) <= 0.1 + 1e-12  # 100 Nm/s
    assert np.linalg.norm(applied[:, :3], axis=1).max() <= 150.0 + 1e-9
    assert np.linalg.norm(applied[:, :2], axis=1).max() <= 60.0 + 1e-9  # horizontal
    np.testing.assert_allclose(np.linalg.norm(applied[-1, :2]), 60.0)  # on both bounds
    assert np.linalg.norm(applied[-1, :3]) > 140.0 and applied[-1, 2] < -130.0
    np.testing.assert_allclose(np.linalg.norm(applied[-1, 3:]), 20.0)


def test_disabled_guard_changes_nothing() -> None:
    guard = ContactGuard(ContactGuardConfig(enabled=False), 0.001, 400.0)
    w = np.array([4000.0, 0.0, -3000.0, 0.0, 600.0, 0.0])
    before = w.copy()
    guard_feedforward(w, np.ones(6), guard.state)
    np.testing.assert_array_equal(w, before)
    assert ControllerConfig().guard == GUARD_ON  # default: on
    assert preset_config("paper").guard == ContactGuardConfig(enabled=False)  # paper: off


@pytest.mark.parametrize("kwargs", [{"growth_step_n": 0.0}, {"force_max_n": -1.0},
                                    {"upward_cos": 2.0}, {"follow_delay_s": float("nan")}])
def test_guard_config_validation(kwargs: dict) -> None:
    with pytest.raises(InvalidArgumentError):
        ContactGuardConfig(**kwargs)


def _holding_guard() -> ContactGuard:
    """A guard that has just blocked a growth along -z (a press down into a table) from a
    feedforward f0 = (3, 0, -4) N."""
    from impact_control.contact_guard import contact_guard_step

    guard = ContactGuard(GUARD_ON, 0.001, 400.0)
    ones, pos = np.ones(6), np.zeros(3)
    f0 = np.array([3.0, 0.0, -4.0, 0.0, 0.0, 0.0])
    contact_guard_step(f0, pos, pos, f0, ones, guard.state)  # window at f0
    pressed = f0 + np.array([0.0, 0.0, -5.0, 0.0, 0.0, 0.0])
    for _ in range(150):  # grows 5 N down; the TCP stays; the estimate follows
        contact_guard_step(pressed, pos, pos, pressed, ones, guard.state)
    assert guard.holding
    return guard


def test_a_hold_drops_the_push_into_the_contact_and_keeps_the_vertical_rise_free() -> None:
    guard = _holding_guard()
    for _ in range(50):  # past the 1 N/tick rate bound
        w = np.array([3.0, 0.0, -9.0, 0.0, 0.0, 0.0])
        guard_feedforward(w, np.ones(6), guard.state)
    np.testing.assert_allclose(w[:3], [3.0, 0.0, 0.0], atol=1e-12)  # -4 N push dropped too
    np.testing.assert_allclose(guard.target[:3], [3.0, 0.0, 0.0], atol=1e-12)
    guard2 = _holding_guard()
    for _ in range(50):
        up = np.array([3.0, 0.0, 25.0, 0.0, 0.0, 0.0])  # the model now asks to lift
        guard_feedforward(up, np.ones(6), guard2.state)
    np.testing.assert_allclose(up[:3], [3.0, 0.0, 25.0], atol=1e-12)


def test_a_hold_ends_when_the_tcp_moves() -> None:
    from impact_control.contact_guard import contact_guard_step

    guard = _holding_guard()
    w = np.array([3.0, 0.0, -9.0, 0.0, 0.0, 0.0])
    contact_guard_step(w, np.array([0.0, 0.0, 0.003]), np.zeros(3), w, np.ones(6),
                       guard.state)
    assert not guard.holding
