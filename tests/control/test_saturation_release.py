"""The saturated-lift release (``control/saturation_release.py``, issue 37 item 5): when it
starts, its ramp, its recovery and its progress test, with hand-computed values; on in
``default`` only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impact_control.config import ControllerConfig
from impact_control.errors import InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_control.saturation_release import (
    SaturationRelease,
    SaturationReleaseConfig,
    saturation_release_restore,
)

TAU_MAX = np.array([87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0])
FREE = np.zeros(7)
WRIST_AT_BOUND = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 12.0, 0.0])  # joint 6 clipped
W_FF = np.array([0.0, 0.0, 86.0, 1.0, -2.0, 0.5])


def _release(rise_min_m: float = 0.001, **kw) -> SaturationRelease:
    # dt 1 ms; hold 3 ms = 3 ticks; release tau 10 ms, recover tau 20 ms; the TCP stays at
    # z = 0 unless a test moves it, so the lift is stalled (no rise of 1 mm)
    cfg = SaturationReleaseConfig(enabled=True, hold_s=0.003, release_tau_s=0.01,
                                  recover_tau_s=0.02, rise_min_m=rise_min_m, **kw)
    return SaturationRelease(cfg, 0.001)


def test_release_starts_after_the_hold_and_ramps_down_exponentially() -> None:
    sr = _release(margin_nm=0.0)
    # ticks 1, 2: at the bound for 1, 2 ticks < 3: nothing released
    for _ in range(2):
        np.testing.assert_array_equal(sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF), W_FF)
        assert sr.scale == 1.0
    # tick 3: 3 ticks >= 3: s = 1 - (1 - e^(-1/10)) = e^(-0.1) = 0.904837418...
    w = sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(0.9048374180359595, rel=1e-14)
    np.testing.assert_allclose(w, 0.9048374180359595 * W_FF, rtol=1e-14)
    # 7 more ticks: s = e^(-10/10) = e^-1 (one time constant after the release began)
    for _ in range(7):
        sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(math.exp(-0.8), rel=1e-12)
    for _ in range(2):
        sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(math.exp(-1.0), rel=1e-12)
    assert sr.state.releases[0] == 10.0
    np.testing.assert_array_equal(sr.state.ff_unscaled, W_FF)  # kept unscaled


def test_recovery_when_the_bound_clears() -> None:
    sr = _release(margin_nm=0.0)
    for _ in range(12):  # 10 release ticks: s = e^-1
        sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    s0 = math.exp(-1.0)
    # one free tick: s = 1 - (1 - s0) e^(-1/20)
    sr.step(FREE, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(1.0 - (1.0 - s0) * math.exp(-0.05), rel=1e-12)
    assert sr.state.at_bound_ticks[0] == 0.0
    # 19 more: 1 - (1 - s0) e^-1 (one recovery time constant)
    for _ in range(19):
        sr.step(FREE, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(1.0 - (1.0 - s0) * math.exp(-1.0), rel=1e-12)
    # back at the bound: the hold counts again from 0, so 2 ticks still recover
    s1 = sr.scale
    sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(1.0 - (1.0 - s1) * math.exp(-0.1), rel=1e-12)
    sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)  # third: released again
    assert sr.scale < 1.0 - (1.0 - s1) * math.exp(-0.1)


def test_a_break_restarts_the_hold_and_the_margin_and_sign_count() -> None:
    sr = _release(margin_nm=0.1)
    near = np.array([0.0, 0.0, 0.0, -86.95, 0.0, 0.0, 0.0])  # |tau| >= 87 - 0.1: at bound
    below = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 11.85, 0.0])  # 11.85 < 11.9: not
    sr.step(near, TAU_MAX, W_FF)
    sr.step(near, TAU_MAX, W_FF)
    assert sr.state.at_bound_ticks[0] == 2.0
    sr.step(below, TAU_MAX, W_FF)  # a break: 0
    assert sr.state.at_bound_ticks[0] == 0.0
    for _ in range(2):
        sr.step(near, TAU_MAX, W_FF)
    assert sr.scale == 1.0
    sr.step(near, TAU_MAX, W_FF)
    assert sr.scale == pytest.approx(math.exp(-0.1), rel=1e-14)


def test_the_command_is_not_scaled_and_restore_gives_the_unscaled_feedforward() -> None:
    sr = _release(margin_nm=0.0, )
    for _ in range(3):
        sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF)
    from impact_control.saturation_release import saturation_release_step

    w, cmd, extra = W_FF.copy(), np.array([0.0, 0.0, -5.0, 0.0, 0.0, 0.0]), np.zeros(6)
    saturation_release_step(WRIST_AT_BOUND, TAU_MAX, 0.0, 1.0, w, cmd, extra, sr.state)
    s = math.exp(-0.2)
    np.testing.assert_allclose(w, s * W_FF, rtol=1e-13)
    np.testing.assert_allclose(extra, s * W_FF + cmd, rtol=1e-13)
    saturation_release_restore(w, sr.state)
    np.testing.assert_array_equal(w, W_FF)
    sr.reset()
    assert (sr.scale, sr.state.at_bound_ticks[0], sr.state.releases[0]) == (1.0, 0.0, 0.0)
    assert not sr.state.ff_unscaled.any()


def test_on_in_default_only_and_off_through_an_override() -> None:
    from impact_control.optional_stages import OptionalStages, saturation_release_on
    from impact_control.presets import PRESETS, preset_config

    for name in PRESETS:
        on = name in ("default", "keep_carried", "lift_watch")
        assert preset_config(name).saturation_release.enabled == on, name
    assert ControllerConfig().saturation_release == SaturationReleaseConfig(
        enabled=True, hold_s=0.5, release_tau_s=0.25, recover_tau_s=2.0, margin_nm=0.1,
        rise_min_m=0.01)
    cfg = apply_overrides(ControllerConfig(), ["saturation_release.enabled=False"])
    assert not cfg.saturation_release.enabled

    def stages(c):
        return OptionalStages(c.target_filter, c.observer, c.payload, c.joint_limits,
                              c.dt_s, saturation_release=c.saturation_release)

    assert not saturation_release_on(stages(cfg).packed.buffer)
    on = stages(ControllerConfig())
    assert saturation_release_on(on.packed.buffer)
    assert on.saturation_release.state.hold_ticks[0] == 500.0
    with pytest.raises(InvalidArgumentError):
        SaturationReleaseConfig(release_tau_s=0.0)


def test_a_lift_still_rising_restarts_the_window_and_a_stalled_one_is_released() -> None:
    sr = _release(margin_nm=0.0, rise_min_m=0.01)
    # rising 6 mm a tick: at the end of each 3-tick window the TCP rose 12 mm >= 10 mm since
    # the window began (z at its first tick), so the window restarts and nothing is released
    z = 0.0
    for _ in range(9):
        sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF, z_tcp_m=z)
        z += 0.006
    assert sr.scale == 1.0 and sr.state.releases[0] == 0.0
    assert sr.state.at_bound_ticks[0] == 0.0  # tick 9 ended the third window: restarted
    # then stalled (rises 4 mm a tick: 8 mm over a window < 10 mm): released on its 3rd tick
    z_first = z
    for k in range(3):
        sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF, z_tcp_m=z_first + 0.004 * k)
    assert sr.scale == pytest.approx(math.exp(-0.1), rel=1e-14)
    assert sr.state.z_start[0] == z_first
    # once released it stays released while at the bound, even if the TCP moves up again
    sr.step(WRIST_AT_BOUND, TAU_MAX, W_FF, z_tcp_m=z_first + 1.0)
    assert sr.scale == pytest.approx(math.exp(-0.2), rel=1e-14)


def test_rise_min_must_be_finite() -> None:
    with pytest.raises(InvalidArgumentError, match="rise_min_m"):
        SaturationReleaseConfig(rise_min_m=math.inf)


# --- the lift watch (issue 54; the ``lift_watch`` preset) -------------------------------------
UP = np.array([0.0, 0.0, 30.0, 0.0, 0.0, 0.0])  # 30 N up: above the 10 N threshold
WEAK = np.array([0.0, 0.0, 5.0, 0.0, 0.0, 0.0])  # below it


def _watch(lift_watch_s: float = 0.005, **kw) -> SaturationRelease:
    # dt 1 ms; watch 5 ms = 5 ticks; lift seen at 20 mm; release tau 10 ms
    cfg = SaturationReleaseConfig(enabled=True, hold_s=0.003, release_tau_s=0.01,
                                  recover_tau_s=0.02, lift_watch_s=lift_watch_s, **kw)
    return SaturationRelease(cfg, 0.001)


def _close(sr: SaturationRelease, z: float = 0.0) -> None:
    sr.step(FREE, TAU_MAX, FREE[:6], z_tcp_m=z, gripper_cmd=-1.0)  # open, then close
    sr.step(FREE, TAU_MAX, FREE[:6], z_tcp_m=z, gripper_cmd=1.0)


def test_a_push_that_lifts_nothing_is_released_and_stays_released_until_the_hand_opens() -> None:
    sr = _watch()
    _close(sr)
    for _ in range(4):  # 4 ticks pushing up, no rise: not yet
        np.testing.assert_array_equal(sr.step(FREE, TAU_MAX, UP, gripper_cmd=1.0), UP)
    w = sr.step(FREE, TAU_MAX, UP, gripper_cmd=1.0)  # the 5th: stalled, released
    assert sr.state.stalled[0] == 1.0
    np.testing.assert_allclose(w, math.exp(-0.1) * UP, rtol=1e-12)
    for _ in range(200):  # latched: no joint at its bound, still released
        sr.step(FREE, TAU_MAX, UP, gripper_cmd=1.0)
    assert sr.scale < 1e-6
    sr.step(FREE, TAU_MAX, UP, gripper_cmd=-1.0)  # the hand opens: disarmed, recovering
    assert sr.state.armed[0] == 0.0 and sr.state.stalled[0] == 0.0
    assert sr.scale > 1e-6


def test_a_lift_seen_in_time_is_never_released_and_spared_at_the_bound() -> None:
    sr = _watch(spare_carried=True)
    _close(sr, z=0.10)
    for k in range(4):
        sr.step(FREE, TAU_MAX, UP, z_tcp_m=0.10 - 0.001 * k, gripper_cmd=1.0)  # sinks 3 mm
    sr.step(FREE, TAU_MAX, UP, z_tcp_m=0.097 + 0.020, gripper_cmd=1.0)  # 20 mm above the low
    assert sr.state.lifted[0] == 1.0 and sr.state.stalled[0] == 0.0
    for _ in range(50):  # carried with the wrist at its bound: spared, no release
        w = sr.step(WRIST_AT_BOUND, TAU_MAX, UP, z_tcp_m=0.12, gripper_cmd=1.0)
    np.testing.assert_array_equal(w, UP)
    assert sr.state.releases[0] == 0.0


def test_without_spare_carried_the_wrist_release_still_acts_on_a_carried_load() -> None:
    sr = _watch(spare_carried=False)
    _close(sr)
    sr.step(FREE, TAU_MAX, UP, z_tcp_m=0.05, gripper_cmd=1.0)  # lifted at once
    for _ in range(10):
        sr.step(WRIST_AT_BOUND, TAU_MAX, UP, z_tcp_m=0.05, gripper_cmd=1.0)
    assert sr.state.lifted[0] == 1.0 and sr.scale < 1.0


def test_weak_push_or_a_hand_closed_from_the_start_never_stalls() -> None:
    sr = _watch()
    _close(sr)
    for _ in range(50):  # below lift_force_min_n: a light load, no time counted
        sr.step(FREE, TAU_MAX, WEAK, gripper_cmd=1.0)
    assert sr.state.pushing_ticks[0] == 0.0 and sr.scale == 1.0
    sr = _watch()  # closed since reset (a tool in the hand): never armed
    for _ in range(50):
        sr.step(FREE, TAU_MAX, UP, gripper_cmd=1.0)
    assert sr.state.armed[0] == 0.0 and sr.scale == 1.0


def test_a_late_lift_ends_the_stall() -> None:
    sr = _watch()
    _close(sr)
    for _ in range(20):
        sr.step(FREE, TAU_MAX, UP, gripper_cmd=1.0)
    assert sr.state.stalled[0] == 1.0
    sr.step(FREE, TAU_MAX, UP, z_tcp_m=0.02, gripper_cmd=1.0)
    assert sr.state.stalled[0] == 0.0 and sr.state.lifted[0] == 1.0
    s = sr.scale
    sr.step(FREE, TAU_MAX, UP, z_tcp_m=0.02, gripper_cmd=1.0)
    assert sr.scale > s  # recovering


def test_lift_watch_values_are_checked() -> None:
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(InvalidArgumentError, match="lift_watch_s"):
            SaturationReleaseConfig(lift_watch_s=bad)
    with pytest.raises(InvalidArgumentError, match="lift_min_m"):
        SaturationReleaseConfig(lift_min_m=0.0)


def test_the_tip_test_stalls_on_time_at_the_bound_in_all_before_the_lift() -> None:
    # no lift watch by time; 3 ticks at the bound in all (with breaks) since the close stall it
    sr = _watch(lift_watch_s=math.inf, tip_hold_s=0.003)
    _close(sr)
    for tau in (WRIST_AT_BOUND, FREE, WRIST_AT_BOUND, FREE):
        sr.step(tau, TAU_MAX, UP, gripper_cmd=1.0)
    assert sr.state.stalled[0] == 0.0 and sr.state.bound_ticks[0] == 2.0
    sr.step(WRIST_AT_BOUND, TAU_MAX, UP, gripper_cmd=1.0)
    assert sr.state.stalled[0] == 1.0
    sr = _watch(lift_watch_s=math.inf, tip_hold_s=0.003, spare_carried=True)
    _close(sr)
    sr.step(FREE, TAU_MAX, UP, z_tcp_m=0.05, gripper_cmd=1.0)  # lifted first: no tip test
    for _ in range(20):
        sr.step(WRIST_AT_BOUND, TAU_MAX, UP, z_tcp_m=0.05, gripper_cmd=1.0)
    assert sr.state.stalled[0] == 0.0 and sr.scale == 1.0
    with pytest.raises(InvalidArgumentError, match="tip_hold_s"):
        SaturationReleaseConfig(tip_hold_s=0.0)


def test_keep_carried_releases_a_stall_on_the_table_and_spares_a_carried_load() -> None:
    """``keep_carried`` (issue 54's preset): no watch timer (``lift_watch_s`` inf), only
    ``spare_carried``. Before the lift is seen, a wrist at its bound with no rise is released
    as in ``default`` (the Hammer stall); once the TCP has risen 20 mm since the close, the
    wrist at its bound is spared (the HammerBasket carry); opening the hand ends the spare."""
    from impact_control.presets import preset_config

    kept = preset_config("keep_carried").saturation_release
    assert math.isinf(kept.lift_watch_s) and kept.spare_carried and math.isinf(kept.tip_hold_s)
    stall = _watch(lift_watch_s=math.inf, spare_carried=True)
    _close(stall)
    for _ in range(500):  # pushing up at the bound, never rising: the release acts
        stall.step(WRIST_AT_BOUND, TAU_MAX, UP, z_tcp_m=0.0, gripper_cmd=1.0)
    assert stall.state.stalled[0] == 0.0 and stall.scale < 1e-6  # the release, not the watch
    carried = _watch(lift_watch_s=math.inf, spare_carried=True)
    _close(carried)
    carried.step(FREE, TAU_MAX, UP, z_tcp_m=0.02, gripper_cmd=1.0)  # 20 mm up: lifted
    for _ in range(500):
        w = carried.step(WRIST_AT_BOUND, TAU_MAX, UP, z_tcp_m=0.02, gripper_cmd=1.0)
    np.testing.assert_array_equal(w, UP)
    assert carried.state.releases[0] == 0.0
    carried.step(FREE, TAU_MAX, UP, z_tcp_m=0.02, gripper_cmd=-1.0)  # set down and opened
    for _ in range(500):  # a new stall without a close: released as in default
        carried.step(WRIST_AT_BOUND, TAU_MAX, UP, z_tcp_m=0.02, gripper_cmd=-1.0)
    assert carried.scale < 1e-6
