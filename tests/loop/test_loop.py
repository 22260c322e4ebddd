"""The closed loop (one numba call per tick) against the same ticks through public APIs."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from fixtures.rollouts import expert_rollout

from impact_control.errors import InvalidArgumentError
from impact_envs import ENV_IDS
from impact_envs.loop import ClosedLoop, StepTrace, TickTargets
from impact_envs.loop.closed_loop import FF_PUSH_FROM_N
from impact_envs.tasks.base import Task


class _ReferenceLoop:
    """``ClosedLoop.run`` written with the public APIs a real FR3 integration would use:
    ``read_sensors`` -> ``ImpactController.compute`` -> ``apply`` -> ``step``, per tick."""

    def __init__(self, loop: ClosedLoop) -> None:
        self.sim, self.controller, self.hook = loop.sim, loop.controller, loop.tick_hook
        self.record_press_diagnostics = loop.record_press_diagnostics

    def run(self, targets: TickTargets) -> StepTrace:
        sim, ctrl = self.sim, self.controller
        n = targets.positions.shape[0]
        taus, qvels = np.empty((n, 7)), np.empty((n, 7))
        contact, last = np.zeros((n, 4)), 0
        for i in range(n):
            if self.hook is not None:
                self.hook(sim, float(sim.data.time))
            q, dq, tau_meas = sim.read_sensors(None, targets.noise[i])
            tau = ctrl.compute(q, dq, tau_meas, targets.positions[i], targets.quats[i],
                               targets.wrench_cmd, targets.learn_mask, sim.gripper_width(),
                               gripper_cmd=targets.gripper_cmd)
            sim.apply(tau, targets.gripper_cmd)
            sim.step()
            taus[i], qvels[i] = sim.tau_applied, sim.arm_state()[1]
            if (i + 1) % 4 == 0 or i == n - 1:
                robot, obj = sim.contact_forces()
                push = (sim.push_into_contact(ctrl.signals.wrench_ff_world)
                        if self.record_press_diagnostics and robot > FF_PUSH_FROM_N else 0.0)
                net = sim.object_net_contact() if self.record_press_diagnostics else 0.0
                contact[last:i + 1], last = (robot, obj, push, net), i + 1
        sim.check_finite()
        peaks = np.maximum(contact[:, :2].max(axis=0), 0.0)
        return StepTrace(taus, qvels, q.copy(), dq.copy(), float(peaks[0]), float(peaks[1]),
                         contact[:, 0], contact[:, 1],
                         contact[:, 2] if self.record_press_diagnostics else None,
                         contact[:, 3] if self.record_press_diagnostics else None)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_closed_loop_equals_public_api_ticks(env_id):
    """Same expert episode prefix, bit for bit, through both (every task: hooks included)."""
    runs = []
    for reference in (False, True):
        env = gym.make(env_id, controller="impact")
        if reference:
            env.unwrapped.loop = _ReferenceLoop(env.unwrapped.loop)
        runs.append(expert_rollout(env, env_id, seed=5, steps=60))
    np.testing.assert_array_equal(runs[0], runs[1])


@pytest.mark.parametrize("preset", ["authors_sim", "authors_real"])
def test_closed_loop_equals_public_api_ticks_with_the_authors_presets(preset):
    """The optional stages (target filter, observer, payload model with the gripper command,
    joint limits, the rate limit with gravity) run the same in both, bit for bit."""
    runs = []
    for reference in (False, True):
        env = gym.make("IMPACT/Hammer-v1", controller="impact", controller_preset=preset)
        if reference:
            env.unwrapped.loop = _ReferenceLoop(env.unwrapped.loop)
        runs.append(expert_rollout(env, "IMPACT/Hammer-v1", seed=5, steps=60))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_a_task_declares_its_tick_hook():
    with pytest.raises(TypeError, match="set has_tick_hook = True"):
        type("Hooked", (Task,), {"before_tick": lambda self, sim, t: None})
    with pytest.raises(TypeError, match="set has_tick_hook = False"):
        type("Claims", (Task,), {"has_tick_hook": True})


def test_loop_needs_a_reset_controller():
    env = gym.make("IMPACT/Hammer-v1")
    loop = env.unwrapped.loop
    targets = TickTargets(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 1)), np.zeros((2, 21)),
                          -1.0, None, None)
    with pytest.raises(InvalidArgumentError, match="reset"):
        loop.run(targets)


def test_the_press_diagnostics_are_recorded_only_when_asked():
    """``ClosedLoop.record_press_diagnostics`` (issue 54's diagnostics) adds
    ``info["ff_into_contact_trace_n"]`` and ``info["contact_object_net_trace_n"]``, one value
    per tick; off (the default) the loop does none of that work and the keys are absent."""
    env = gym.make("IMPACT/Hammer-v1", controller="impact")
    env.reset(seed=0)
    action = np.concatenate([env.unwrapped.sim.tcp_pose()[0], [1, 0, 0, 0, -1, 0], [-1.0]])
    _, _, _, _, info = env.step(action)
    assert "ff_into_contact_trace_n" not in info and "contact_object_net_trace_n" not in info
    env.unwrapped.loop.record_press_diagnostics = True
    _, _, _, _, info = env.step(action)
    trace = info["ff_into_contact_trace_n"]
    assert trace.shape == info["contact_robot_trace_n"].shape and not trace.any()  # no contact
    net = info["contact_object_net_trace_n"]  # the hammer rests on the table: its weight
    assert net.shape == trace.shape
    assert net == pytest.approx(9.81 * info["object_mass"], rel=0.05)
    env.close()
