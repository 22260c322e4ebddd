"""The authors' controller as presets (authors_presets.py): their values, the as-coded
choices one field away from the intended ones, the robot refusal, and the controller
running every optional stage (hold, hold-off, TCP-z feedforward) end to end."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fixtures.fake_dynamics import ConstantArmDynamics

from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError
from impact_control.lie import matrix_to_quat
from impact_control.overrides import apply_overrides
from impact_control.presets import (
    PRESETS,
    ROBOT_PRESETS,
    check_robot_preset,
    preset_config,
    preset_name,
)


def test_both_presets_carry_the_authors_values() -> None:
    sim, real = preset_config("authors_sim"), preset_config("authors_real")
    for cfg in (sim, real):
        imp = cfg.impedance
        assert imp.stiffness_translational_n_per_m == (400.0,) * 3
        assert imp.damping_rotational_nms_per_rad == (2.0 * math.sqrt(30.0),) * 3  # 2 sqrt(K)
        assert (imp.nullspace_stiffness_nm_per_rad, imp.nullspace_damping_nms_per_rad) == (
            2.0, -1.0)
        assert (imp.nullspace_torque_max_nm, imp.gains_frame) == (5.0, "tcp")
        assert cfg.target_filter.enabled and cfg.target_filter.weight_new == 0.9
        assert cfg.observer.lowpass_alpha_per_tick == 0.02 and cfg.observer.warmup_ticks == 100
        assert cfg.estimator.regularization == 0.02
        assert (cfg.slow_wrench.clip_force_n, cfg.slow_wrench.clip_torque_nm) == (10.0, 1.0)
        assert cfg.slow_wrench.leak_per_s == 0.01
        assert cfg.joint_limits.torque_max_nm == 5.0 and cfg.joint_limits.range_rad == 0.3
        assert cfg.limits.torque_rate_max_nm_per_s * cfg.dt_s == 0.5
        pay = cfg.payload
        assert (pay.hold_on_n, pay.feedforward_holdoff_s, pay.reset_ratio) == (2.0, 0.5, 0.8)
        assert (pay.surprise_lowpass_alpha, pay.surprise_threshold_n) == (1e-4, 5.0)
        assert (pay.learning_rate, pay.estimate_max_n, pay.slow_rate_max) == (0.01, 100.0, 0.2)
    assert (sim.impedance.pose_error_clip_m, real.impedance.pose_error_clip_m) == (None, 0.1)
    assert real.impedance.pose_error_clip_rad == 0.5
    assert (sim.observer.force_norm_max_n, sim.observer.torque_norm_max_nm) == (120.0, 50.0)
    assert (real.observer.force_norm_max_n, real.observer.torque_norm_max_nm) == (80.0, 15.0)
    assert (sim.slow_wrench.rate_force_per_s, sim.slow_wrench.rate_torque_per_s) == (2.0, 1.0)
    assert (real.slow_wrench.rate_force_per_s, real.slow_wrench.rate_torque_per_s) == (0.5, 0.5)
    assert (sim.slow_wrench.force_norm_max_n, sim.slow_wrench.torque_norm_max_nm) == (120, 50)
    assert (real.slow_wrench.force_norm_max_n, real.slow_wrench.torque_norm_max_nm) == (50, 8)
    assert (sim.payload.feedforward, real.payload.feedforward) == ("slow_wrench", "estimate")
    assert (sim.payload.gripper_holdoff, real.payload.gripper_holdoff) == (False, True)
    assert (sim.limits.rate_limit_includes_gravity, real.limits.rate_limit_includes_gravity) == (
        True, False)


def test_names_and_the_intended_variants_one_field_away() -> None:
    assert [preset_name(preset_config(n, revision=1), revision=1) for n in PRESETS] == (
        list(PRESETS))
    assert set(PRESETS) >= {"authors_sim", "authors_real"}
    intended = apply_overrides(preset_config("authors_sim"), [
        "impedance.nullspace_damping_nms_per_rad=none", "payload.gripper_holdoff=true"])
    assert intended.impedance.nullspace_damping == pytest.approx(2.0 * math.sqrt(2.0))
    assert preset_name(intended) == "custom"
    with pytest.raises(InvalidArgumentError, match="runs the authors' observer"):
        preset_config("authors_sim", estimator="momentum")
    with pytest.raises(InvalidArgumentError, match="residual estimator's place"):
        apply_overrides(preset_config("authors_real"), ["estimator.kind=momentum"])


def test_a_robot_takes_authors_real_and_refuses_authors_sim_in_one_line() -> None:
    assert "authors_real" in ROBOT_PRESETS and "authors_sim" not in ROBOT_PRESETS
    assert check_robot_preset("authors_real") == "authors_real"
    with pytest.raises(InvalidArgumentError) as err:
        check_robot_preset("authors_sim")
    message = str(err.value)
    assert "\n" not in message and "use authors_real" in message
    assert "valid: default, paper, keep_carried, lift_watch, authors_real" in message


def _controller(preset: str, mode: str = "impact"):
    dyn = ConstantArmDynamics(seed=21)
    dyn.friction_nms_per_rad = 0.0
    ctrl = ImpactController(dyn, preset_config(preset), mode=mode)
    q0 = np.full(7, 0.1)
    ctrl.reset(q0)
    dyn.update(q0, np.zeros(7))
    return dyn, ctrl, q0


def _hold(dyn, ctrl, q0, weight: float, ticks: int, gripper_cmd: float = 1.0) -> list:
    """Ticks at rest whose torque reading carries a weight along TCP z (w_hat = -W z_tcp,
    i.e. +W up for a TCP pointing down); returns the feedforward of each tick."""
    w = np.r_[-weight * dyn.rot_ee_world[:, 2], np.zeros(3)]
    tau = dyn.gravity + dyn.jacobian.T @ w
    pos, quat = dyn.pos_ee_world.copy(), matrix_to_quat(dyn.rot_ee_world)
    out = []
    for _ in range(ticks):
        ctrl.compute(q0, np.zeros(7), tau, pos, quat, gripper_cmd=gripper_cmd)
        out.append(ctrl.signals.wrench_ff_world.copy())
    return out


def test_authors_sim_feeds_forward_the_slow_wrench_along_tcp_z_after_the_hold_off() -> None:
    """100 warm-up ticks, then the observer's 0.02 low-pass: the measured weight (30 N read)
    passes 2 N on tick 100 + k with 30 (1 - 0.98^k) >= 2, k = 4; the feedforward starts 500
    holding ticks later and is w_slow's TCP z, along TCP z; nothing else is fed forward."""
    dyn, ctrl, q0 = _controller("authors_sim")
    ff = np.array(_hold(dyn, ctrl, q0, 30.0, 700))
    pay = ctrl.optional.payload
    start = 100 + 4 - 1  # index of the first holding tick
    assert not ff[: start + 499].any()
    assert np.abs(ff[start + 499]).max() > 0.0
    z_tcp = dyn.rot_ee_world[:, 2]
    slow_z = float(ctrl.slow_filter.wrench_slow_world[:3] @ z_tcp)
    np.testing.assert_allclose(ff[-1], np.r_[slow_z * z_tcp, np.zeros(3)], atol=1e-9)
    assert pay.holding and pay.estimate_n == 0.0  # the surprise is still far below 5 N
    assert ctrl.internal_model.wrench_pred_world.any() == 0  # the internal model never runs


def test_authors_real_feeds_forward_the_estimate_and_the_gripper_can_stop_it() -> None:
    dyn, ctrl, q0 = _controller("authors_real")
    ctrl.optional.payload.state.estimate_n[0] = 12.0
    ff = np.array(_hold(dyn, ctrl, q0, 30.0, 700))
    z_tcp = dyn.rot_ee_world[:, 2]
    np.testing.assert_allclose(ff[-1], np.r_[-12.0 * z_tcp, np.zeros(3)], atol=1e-12)
    ff = _hold(dyn, ctrl, q0, 30.0, 1, gripper_cmd=-1.0)  # commanded open: the hold ends
    assert not ctrl.optional.payload.holding and not ff[0].any()
    with pytest.raises(InvalidArgumentError, match="gripper_cmd"):
        _hold(dyn, ctrl, q0, 30.0, 1, gripper_cmd=2.0)
    assert ctrl.optional.payload.state.gripper_cmd[0] == -1.0  # refused: unchanged


def test_impedance_mode_feeds_nothing_forward_with_the_authors_presets() -> None:
    dyn, ctrl, q0 = _controller("authors_real", mode="impedance")
    ctrl.optional.payload.state.estimate_n[0] = 12.0
    assert not np.array(_hold(dyn, ctrl, q0, 30.0, 700)).any()


def test_every_array_of_the_optional_stages_is_in_the_snapshot() -> None:
    """Each optional stage keeps its state in the one buffer ``opt`` of the controller's
    named state (what env.get_state() copies): a later change can carry it across episodes."""
    _, ctrl, _ = _controller("authors_sim")
    live = list(ctrl.state_arrays().values())
    assert "opt.buffer" in ctrl.state_arrays()
    opt = ctrl.optional
    stages = (opt.target_filter, opt.observer, opt.payload, opt.joint_limits)
    arrays = [(type(s).__name__, n, v) for s in stages for n, v in vars(s).items()
              if isinstance(v, np.ndarray)]
    arrays += [(type(s).__name__, f, v) for s in stages for f, v in s.state._asdict().items()
               if isinstance(v, np.ndarray)]
    assert len(arrays) > 20
    for stage, name, value in arrays:
        assert any(np.shares_memory(value, a) for a in live), (stage, name)


def test_the_tick_reads_each_optional_stage_flag_from_the_header() -> None:
    from impact_control.optional_stages import (
        joint_limits_on,
        observer_on,
        target_filter_on,
        unpack_optional,
    )

    for preset, on in (("default", False), ("paper", False), ("authors_sim", True)):
        _, ctrl, _ = _controller(preset)
        buf = ctrl.optional.packed.buffer
        assert (target_filter_on(buf), observer_on(buf), joint_limits_on(buf)) == (on,) * 3
        assert unpack_optional(buf, ())[1] == buf.shape[0]
        assert ctrl.tick.payload_feedforward[0] == float(on)
