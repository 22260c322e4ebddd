"""Task-specific physics of the Dumbbell, Calligraphy and Disturbance environments."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import impact_envs  # noqa: F401  (registers the envs)
from impact_control.policy import stack_obs
from impact_envs.policies.experts import make_expert
from impact_envs.tasks.calligraphy import (
    FORCE_DESIRED_N,
    PAPER_TOP_M,
    PEN_TIP_OFFSET_M,
    missed_criteria,
)
from impact_envs.tasks.calligraphy_force import NormalForceCommand
from impact_envs.tasks.calligraphy_strokes import (
    CHARACTERS,
    DT_REF_S,
    bowed,
    build_reference,
    distance_to_path,
    place_strokes,
)
from impact_envs.tasks.disturbance import DisturbanceProfile
from impact_envs.tasks.dumbbell import PAD_TOP_M, PLATE_APOTHEM_M

GRAVITY = 9.81


def _run(env: gym.Env, expert, obs: dict, steps: int, stop=lambda info: False) -> dict:
    info: dict = {}
    for _ in range(steps):
        obs, _, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
        if stop(info):
            break
    return info


# ---------------------------------------------------------------------------- dumbbell
def test_dumbbell_resting_on_pad_is_success_and_off_pad_is_not():
    env = gym.make("IMPACT/Dumbbell-v1").unwrapped
    env.reset(seed=0)
    task, sim = env.task, env.sim
    pad = sim.model.body_pos[task.pad]
    qpos = sim.data.qpos[task.body.qpos_adr:task.body.qpos_adr + 7]
    qpos[:] = [pad[0], pad[1], PAD_TOP_M + PLATE_APOTHEM_M, 1, 0, 0, 0]
    mujoco.mj_forward(sim.model, sim.data)
    assert task.is_success(sim)
    qpos[0] = pad[0] + 0.07  # one plate's centre beyond the pad's edge (0.085 + 0.07 > 0.15)
    mujoco.mj_forward(sim.model, sim.data)
    assert not task.is_success(sim)
    env.close()


@pytest.mark.parametrize("controller", ["impact", "impedance"])
def test_dumbbell_expert_places_2_5kg(controller):
    env = gym.make("IMPACT/Dumbbell-v1", controller=controller)
    obs, _ = env.reset(seed=0)
    expert = make_expert("IMPACT/Dumbbell-v1")
    expert.reset(1)
    info = _run(env, expert, obs, 750, stop=lambda i: i["is_success"])
    assert info["is_success"] and info["object_mass"] == 2.5
    env.close()


# ------------------------------------------------------------------------- calligraphy
def test_stroke_geometry():
    arc = bowed((0, 3), (-3, -3), 0.8)
    np.testing.assert_allclose(arc[[0, -1]], [[0, 3], [-3, -3]], atol=1e-9)
    chord = np.array([-3.0, -6.0]) / np.hypot(3.0, 6.0)
    sag = np.abs(np.cross(arc - [0.0, 3.0], chord)).max()
    assert sag == pytest.approx(0.8, abs=0.02)
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    assert distance_to_path(np.array([0.5, 0.2]), path) == pytest.approx(0.2)
    assert distance_to_path(np.array([1.3, 0.5]), path) == pytest.approx(0.3)


def test_reference_writes_each_stroke_at_constant_speed_on_the_paper():
    paths = place_strokes(CHARACTERS["shi"], np.array([0.41, 0.0]), 0.2, 1.0)
    ref = build_reference(paths, PAPER_TOP_M, write_speed=0.03)
    for k, path in enumerate(paths):
        pts = ref.points[ref.stroke == k]
        np.testing.assert_allclose(pts[:, 2], PAPER_TOP_M)
        speed = np.linalg.norm(np.diff(pts[:, :2], axis=0), axis=1) / DT_REF_S
        np.testing.assert_allclose(speed, 0.03, rtol=0.02)
        np.testing.assert_allclose(pts[[0, -1], :2], path[[0, -1]], atol=1e-9)
    assert ref.at(ref.t_end_s + 1.0)[1] == -1


def test_normal_force_command_ramps_and_masks_the_force_axes():
    cmd = NormalForceCommand(15.0, ramp_n_per_s=60.0)
    cmd.tick(dt_s=0.001)  # not engaged: nothing
    assert cmd.level_n == 0.0
    wrench, mask = cmd.engage()
    assert not mask[:3].any() and mask[3:].all()  # forces frozen, torques learnable
    for _ in range(100):
        cmd.tick(dt_s=0.001)
    assert cmd.level_n == pytest.approx(6.0)
    assert wrench[2] == pytest.approx(-6.0) and not wrench[[0, 1, 3, 4, 5]].any()
    for _ in range(1000):
        cmd.tick(dt_s=0.001)
    assert wrench[2] == pytest.approx(-15.0)
    assert cmd.engage()[0] is wrench and wrench[2] == pytest.approx(-15.0)  # idempotent
    cmd.release()
    assert not wrench.any()


def test_calligraphy_force_command_follows_the_commanded_tip():
    env = gym.make("IMPACT/Calligraphy-v1").unwrapped
    env.reset(seed=0)
    task, sim = env.task, env.sim
    tip = sim.data.site_xpos[task.tip_site]
    # TCP pointing down (rot6d of diag(1, −1, −1)) with the pen tip target on the paper
    action = np.array([tip[0], tip[1], PAPER_TOP_M + PEN_TIP_OFFSET_M, 1, 0, 0, 0, -1, 0, 1.0])
    assert task.control_inputs(sim, action) == (None, None)  # real tip far above the paper
    sim.data.site_xpos[task.tip_site, 2] = PAPER_TOP_M + 0.001
    wrench, mask = task.control_inputs(sim, action)
    assert wrench[2] <= 0.0 and not mask[2]
    action[2] += 0.008  # a few mm of jitter while writing: still pressing (hysteresis)
    assert task.control_inputs(sim, action)[0] is wrench
    action[2] += 0.004  # 12 mm up: lifted off the paper
    assert task.control_inputs(sim, action) == (None, None)
    action[2] -= 0.005  # 7 mm: not yet on the paper again (engages at 5 mm)
    assert task.control_inputs(sim, action) == (None, None)
    env.close()


def _write(controller: str, tool_mass: float, seed: int) -> tuple[dict, np.ndarray]:
    env = gym.make("IMPACT/Calligraphy-v1", controller=controller)
    obs, _ = env.reset(seed=seed, options={"tool_mass": tool_mass})
    expert = make_expert("IMPACT/Calligraphy-v1")
    expert.reset(1)
    forces, info = [], {}
    while not info.get("writing_done", False):
        obs, _, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
        if info["writing"]:
            forces.append(info["normal_force_n"])
    env.close()
    return info, np.array(forces)


def test_calligraphy_impact_presses_with_commanded_force_despite_1kg_tool():
    """IMPACT learns the tool weight in free air and keeps it compensated while pressing:
    the normal force is the commanded 15 N, not 15 N + m g as under plain impedance."""
    info, forces = _write("impact", 1.0, seed=11)
    assert abs(np.median(forces) - FORCE_DESIRED_N) < 2.5
    assert info["in_band_frac"] >= 0.9 and not info["contact_lost"] and info["is_success"]
    assert info["failure_reason"] == ""
    info_imp, forces_imp = _write("impedance", 1.0, seed=11)
    assert abs(np.median(forces_imp) - (FORCE_DESIRED_N + 1.0 * GRAVITY)) < 3.0
    assert not info_imp["is_success"] and info_imp["failure_reason"].startswith("force in band")


def test_calligraphy_missed_criteria_names_each_failed_criterion():
    ok = {"stroke_rms_m": 0.004, "in_band_frac": 0.95, "contact_lost": False}
    assert missed_criteria(ok) == ""
    bad = {"stroke_rms_m": 0.0061, "in_band_frac": 0.78, "contact_lost": True}
    assert missed_criteria(bad) == (
        "force in band 78% < 90%; stroke rms 6.1 mm > 5 mm; contact lost"
    )


@pytest.mark.parametrize("controller", ["impact", "impedance"])
def test_calligraphy_expert_writes_at_nominal_tool_mass(controller):
    info, _ = _write(controller, 0.1, seed=21)  # "kou": three strokes with a corner
    assert info["is_success"], info


def test_surface_friction_option_sets_paper_friction():
    env = gym.make("IMPACT/Calligraphy-v1").unwrapped
    env.reset(seed=0, options={"surface_friction": 0.9})
    assert env.sim.model.geom_friction[env.task.paper_geom, 0] == 0.9
    env.close()


# ------------------------------------------------------------------------- disturbance
def test_disturbance_profiles():
    d = (0.0, 1.0, 0.0)
    const = DisturbanceProfile("constant", 10.0, d, 1.5, 4.0)
    step = DisturbanceProfile("step", 10.0, d, 1.5, 4.0)
    slow = DisturbanceProfile("slow", 10.0, d, 1.5, 4.0)
    assert const.scale(-0.1) == step.scale(-0.1) == slow.scale(-0.1) == 0.0
    assert const.scale(0.0) == 10.0 and step.scale(1.49) == 0.0 and step.scale(1.5) == 10.0
    assert slow.scale(2.0) == pytest.approx(5.0) and slow.scale(4.0) == slow.scale(9.0) == 10.0
    np.testing.assert_allclose(step.force(2.0), [0.0, 10.0, 0.0])
    a = DisturbanceProfile.sample(np.random.default_rng(3), 20.0)
    assert a == DisturbanceProfile.sample(np.random.default_rng(3), 20.0)
    assert np.linalg.norm(a.direction) == pytest.approx(1.0)


def test_disturbance_applied_force_and_load_change_follow_the_profile():
    env = gym.make("IMPACT/Disturbance-v1", controller="impact").unwrapped
    obs, _ = env.reset(seed=0, options={"disturbance_n": 10.0, "added_mass": 0.5})
    task, sim = env.task, env.sim
    expert = make_expert("IMPACT/Disturbance-v1")
    expert.reset(1)
    assert task.profile.kind == "step"
    nominal_inertia = sim.model.body_inertia[task.body].copy()
    checked = 0
    for _ in range(330):
        obs, _, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
        applied = sim.data.xfrc_applied[task.body]
        if task.t_lift is None:
            assert not applied.any()
            continue
        tau_last_tick = sim.data.time - sim.dt - task.t_lift
        np.testing.assert_allclose(applied[:3], task.profile.force(tau_last_tick), atol=1e-12)
        assert not applied[3:].any()
        loaded = task.t_load is not None
        assert sim.model.body_mass[task.body] == pytest.approx(0.3 + 0.5 * loaded)
        checked += 1
    assert checked > 150 and task.t_load is not None and info["is_grasped"]
    np.testing.assert_allclose(sim.model.body_inertia[task.body], nominal_inertia * 0.8 / 0.3)
    env.close()


def test_disturbance_stops_pushing_a_dropped_trough():
    """A 40 N push acts on the held trough only; dropping it ends the push (no fling)."""
    env = gym.make("IMPACT/Disturbance-v1", controller="impact").unwrapped
    obs, _ = env.reset(seed=0, options={"disturbance_n": 40.0})
    task, sim = env.task, env.sim
    expert = make_expert("IMPACT/Disturbance-v1")
    expert.reset(1)
    for _ in range(400):
        action = expert.act(stack_obs([obs]))[0]
        obs, _, _, _, info = env.step(action)
        if task.t_lift is not None and task.profile.scale(sim.data.time - task.t_lift) > 0:
            break
    assert info["is_grasped"] and np.linalg.norm(sim.data.xfrc_applied[task.body, :3]) > 0
    action[9] = -1.0  # open the hand: the trough falls
    for _ in range(60):
        obs, _, terminated, _, info = env.step(action)
        assert not terminated
    assert not info["is_grasped"]
    assert not sim.data.xfrc_applied[task.body].any()
    assert np.abs(sim.data.qvel).max() < 10.0
    env.close()


@pytest.mark.parametrize(("controller", "magnitude", "success"),
                         [("impact", 2.0, True), ("impedance", 2.0, True),
                          ("impact", 30.0, True), ("impedance", 30.0, False)])
def test_disturbance_expert_holds_goal(controller, magnitude, success):
    env = gym.make("IMPACT/Disturbance-v1", controller=controller)
    obs, _ = env.reset(seed=3, options={"disturbance_n": magnitude})
    expert = make_expert("IMPACT/Disturbance-v1")
    expert.reset(1)
    info = _run(env, expert, obs, 540, stop=lambda i: i["is_success"])
    assert info["is_success"] is success
    env.close()
