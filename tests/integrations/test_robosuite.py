"""IMPACT as a robosuite controller (``impact_robosuite``; runs where the ``[robosuite]`` extra
is installed, docs/robosuite.md, and skips elsewhere)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("robosuite", reason="the robosuite extra is not installed (docs/robosuite.md)")

from impact_control.errors import InvalidArgumentError  # noqa: E402
from impact_robosuite import controller_config  # noqa: E402
from impact_robosuite.experiment import TASKS, make_env, run_episode, set_mass  # noqa: E402
from impact_robosuite.scripted import PickLift  # noqa: E402

SEED = 7  # not one of the documented seeds (100-119)


def _arm(env):
    return env.robots[0].composite_controller.part_controllers["right"]


@pytest.mark.parametrize("method, cls, mode", [("impact", "ImpactArmController", "impact"),
                                               ("impedance", "ImpactArmController", "impedance"),
                                               ("osc", "OperationalSpaceController", None)])
def test_the_config_selects_the_controller(method, cls, mode):
    env = make_env(TASKS["lift"], method, SEED)
    try:
        env.reset()
        arm = _arm(env)
        assert type(arm).__name__ == cls
        if mode is not None:
            assert arm.core.mode == mode
            assert arm.core.config.dt_s == env.sim.model.opt.timestep  # robosuite's 500 Hz
    finally:
        env.close()


@pytest.mark.parametrize("method, preset", [("impact", "default"), ("impact_paper", "paper")])
def test_the_preset_reaches_the_controller(method, preset):
    import dataclasses

    from impact_control.presets import preset_config

    env = make_env(TASKS["lift"], method, SEED)
    try:
        env.reset()
        config = _arm(env).core.config
        # robosuite's 2 ms period: libfranka's 1 ms limiter becomes the per-tick clip
        assert config.dt_s != 0.001 and config.limits.rate_limiter == "per_tick_clip"
        assert config == dataclasses.replace(preset_config(preset), dt_s=config.dt_s,
                                             limits=config.limits)
    finally:
        env.close()


def test_bad_options_are_one_line_errors():
    with pytest.raises(InvalidArgumentError, match="valid choices"):
        controller_config("mpc")
    with pytest.raises(InvalidArgumentError, match="unknown arm options"):
        controller_config("impact", stiffness=5)


@pytest.mark.parametrize("argv, message", [
    (["--methods", "mpc"], "unknown method 'mpc'"), (["--tasks", "door"], "unknown task"),
    (["--masses", "x"], "--masses must be numbers"),
    (["--goal-update-mode", "up"], "invalid --goal-update-mode"),
    (["--episodes", "0"], "--episodes must be >= 1")])
def test_experiment_bad_input_is_one_line_and_writes_nothing(argv, message, tmp_path, capsys):
    from impact_robosuite.experiment import main

    with pytest.raises(SystemExit) as exc:
        main(["--out", str(tmp_path / "out"), *argv])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and message in err
    assert not (tmp_path / "out").exists()


def test_emulated_torque_sensor_reads_the_holding_torque():
    """Arm at rest: the link-side reading equals the model's gravity torque within the
    unsensed joint friction (frictionloss 0.1 Nm) and the noise."""
    env = make_env(TASKS["lift"], "impedance", SEED)
    try:
        env.reset()
        for _ in range(10):
            env.step(np.zeros(7))
        arm = _arm(env)
        reading = arm.sensors.read(env.sim.data._data)
        arm.arm_model.update(reading.q, np.zeros(7))
        np.testing.assert_allclose(reading.tau, arm.arm_model.gravity, atol=0.3)
    finally:
        env.close()


def test_impact_lifts_and_learns_a_4kg_cube_that_impedance_cannot_lift():
    rows = {m: run_episode(TASKS["lift"], m, 4.0, SEED) for m in ("impedance", "impact")}
    assert rows["impact"]["success"] == 1 and rows["impact"]["final_lift_m"] > 0.2
    assert rows["impedance"]["success"] == 0 and rows["impedance"]["final_lift_m"] < 0.05
    env = make_env(TASKS["lift"], "impact", SEED)
    try:
        obs = env.reset()
        set_mass(env, "cube_main", 4.0)
        policy = PickLift()
        policy.reset(obs)
        for _ in range(TASKS["lift"].horizon):
            obs, *_ = env.step(policy.act(obs))
        predicted = _arm(env).core.signals.wrench_pred_world
        assert abs(predicted[2] - 4.0 * 9.81) < 0.1 * 4.0 * 9.81  # the cube's weight, learned
    finally:
        env.close()
