"""``IMPACT/HammerBasket-v1`` (issue 38): the authors' scene facts, their spawn ranges and
success test, the 60 s episode that success does not end, their 200 N hand, and the expert."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import impact_envs  # noqa: F401 - registers the envs
from impact_control.errors import InvalidArgumentError
from impact_control.policy import stack_obs
from impact_envs import RobotOptions
from impact_envs.policies.experts import make_expert
from impact_envs.tasks.hammer_basket import (
    GRASP_OFFSET_FROM_COM_M,
    SUCCESS_HALF_M,
    TABLE_TOP_M,
    HammerBasketTask,
)

ENV_ID = "IMPACT/HammerBasket-v1"


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID, controller="impedance")
    yield e
    e.close()


def _geom_aabb(m: mujoco.MjModel, d: mujoco.MjData, names: tuple[str, ...]) -> np.ndarray:
    """Axis-aligned box (2, 3) around the named box geoms, in the hammer body's frame (the
    spawn turns the hammer about z)."""
    body = m.body("hammer").id
    b_pos, b_rot = d.xpos[body], d.xmat[body].reshape(3, 3)
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for name in names:
        g = m.geom(name).id
        rot, half = d.geom_xmat[g].reshape(3, 3), m.geom_size[g]
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        pts = (d.geom_xpos[g] + (corners * half) @ rot.T - b_pos) @ b_rot
        lo, hi = np.minimum(lo, pts.min(0)), np.maximum(hi, pts.max(0))
    return np.array([lo, hi])


def test_scene_facts(env) -> None:
    """Their table height, hammer extent and mass distribution, basket, contacts and hand."""
    u = env.unwrapped
    m, d = u.sim.model, u.sim.data
    env.reset(seed=0, options={"object_mass": 0.1})
    table = m.geom("work_table").id
    assert d.geom_xpos[table][2] + m.geom_size[table][2] == pytest.approx(TABLE_TOP_M)
    box = _geom_aabb(m, d, ("hammer_handle", "hammer_head"))
    np.testing.assert_allclose(box[1] - box[0], [0.289, 0.095, 0.060], atol=0.003)
    hammer = m.body("hammer").id
    assert m.body_mass[hammer] == pytest.approx(0.1)
    com = m.body_ipos[hammer]
    np.testing.assert_allclose(-com, GRASP_OFFSET_FROM_COM_M, atol=1e-9)
    assert np.linalg.norm(com) == pytest.approx(0.0447, abs=0.001)  # 4.4 cm along the handle
    assert m.body_mass[m.body("basket").id] == pytest.approx(2.2)
    assert m.jnt_type[m.joint("basket_free").id] == mujoco.mjtJoint.mjJNT_FREE
    for g in ("hammer_handle", "hammer_head"):
        gid = m.geom(g).id
        assert m.geom_condim[gid] == 6 and m.geom_friction[gid][0] == 4.0
    pads = {m.geom("left_pad").id, m.geom("right_pad").id}
    pairs = [i for i in range(m.npair) if {m.pair_geom1[i], m.pair_geom2[i]} & pads]
    assert len(pairs) == 4
    for i in pairs:  # the pads' priority would otherwise impose their friction 1.0
        assert m.pair_dim[i] == 6 and m.pair_friction[i][0] == 4.0
    assert m.actuator_forcerange[u.sim.gripper_act][1] == 2.0 * 200.0  # 200 N grasp


def test_mass_scales_inertia_and_keeps_the_com(env) -> None:
    u = env.unwrapped
    m = u.sim.model
    hammer = m.body("hammer").id
    env.reset(seed=0, options={"object_mass": 0.1})
    i0, c0 = m.body_inertia[hammer].copy(), m.body_ipos[hammer].copy()
    env.reset(seed=0, options={"object_mass": 7.5})
    assert m.body_mass[hammer] == pytest.approx(7.5)
    np.testing.assert_allclose(m.body_inertia[hammer], 75.0 * i0, rtol=1e-12)
    np.testing.assert_array_equal(m.body_ipos[hammer], c0)


def test_spawn_ranges_and_home_posture(env) -> None:
    origins, baskets = [], []
    for seed in range(40):
        obs, _ = env.reset(seed=seed)
        d = env.unwrapped.sim.data
        origins.append(d.xpos[env.unwrapped.task.hammer].copy())
        baskets.append(d.xpos[env.unwrapped.task.basket].copy())
    origins, baskets = np.array(origins), np.array(baskets)
    assert origins[:, 0].min() >= 0.25 and origins[:, 0].max() <= 0.40
    assert origins[:, 1].min() >= -0.40 and origins[:, 1].max() <= -0.20
    assert np.ptp(origins[:, 0]) > 0.1 and np.ptp(origins[:, 1]) > 0.15
    assert baskets[:, 0].min() >= 0.30 and baskets[:, 0].max() <= 0.40
    assert baskets[:, 1].min() >= 0.10 and baskets[:, 1].max() <= 0.30
    q, _ = env.unwrapped.sim.arm_state()
    np.testing.assert_allclose(q, [0, -np.pi / 4, 0, -3 * np.pi / 4, 0, np.pi / 2, np.pi / 4])


@pytest.mark.parametrize(("dx", "dy", "inside"), [(0.0, 0.0, True), (0.18, -0.18, True),
                                                  (0.19, 0.0, False), (0.0, -0.19, False)])
def test_their_success_test_reads_the_body_origin(env, dx: float, dy: float,
                                                  inside: bool) -> None:
    env.reset(seed=1)
    u = env.unwrapped
    d, task = u.sim.data, u.task
    basket = d.xpos[task.basket].copy()
    task.body.place(d, basket[:2] + [dx, dy], 0.6, 0.0)  # in the air: no height check
    mujoco.mj_forward(u.sim.model, d)
    assert abs(d.xpos[task.hammer][0] - basket[0]) == pytest.approx(abs(dx))
    assert task.is_success(u.sim) is inside
    assert SUCCESS_HALF_M == 0.1875


def test_success_does_not_end_the_episode() -> None:
    """Their protocol reads the end of a 60 s episode: terminate_on_success has no effect."""
    e = gym.make(ENV_ID, controller="impedance", terminate_on_success=True)
    try:
        assert e.spec.max_episode_steps == 1800
        obs, _ = e.reset(seed=2)
        u = e.unwrapped
        d = u.sim.data
        u.task.body.place(d, d.xpos[u.task.basket][:2], 0.6, 0.0)  # held over it: a success
        hold = np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]])
        obs, _, terminated, truncated, info = e.step(hold)
        assert info["is_success"] and not terminated and not truncated
    finally:
        e.close()


def test_the_hand_is_theirs_unless_named() -> None:
    assert HammerBasketTask.hand == "authors_sim"
    e = gym.make(ENV_ID, robot=RobotOptions(hand="franka_hand"))
    try:
        assert e.unwrapped.sim.model.actuator_forcerange[e.unwrapped.sim.gripper_act][1] == 140.0
    finally:
        e.close()
    with pytest.raises(InvalidArgumentError, match=r"^invalid grasp_force_n 210.*200 N"):
        RobotOptions(grasp_force_n=210.0)
    with pytest.raises(InvalidArgumentError, match=r"^invalid grasp_force_n 150.*140 N"):
        gym.make("IMPACT/Hammer-v1", robot=RobotOptions(grasp_force_n=150.0))
    with pytest.raises(InvalidArgumentError, match=r"^invalid hand 'other'; valid choices"):
        RobotOptions(hand="other")


@pytest.mark.parametrize("mass", [0.3, 2.0])
def test_their_expert_solves_it_under_impedance(mass: float) -> None:
    """Their demonstrator (privileged m g / K offset) places the hammer; the episode's end
    (here: 60 policy steps after the release) passes their test."""
    e = gym.make(ENV_ID, controller="impedance")
    expert = make_expert(ENV_ID, compensation="privileged")
    try:
        obs, _ = e.reset(seed=3, options={"object_mass": mass})
        expert.reset(1, object_mass_kg=np.array([mass]))
        released_at = None
        for step in range(1800):
            action = expert.act(stack_obs([obs]))[0]
            obs, _, _, truncated, info = e.step(action)
            if released_at is None and step > 100 and action[9] < 0:
                released_at = step
            if released_at is not None and step >= released_at + 60 or truncated:
                break
        assert info["is_success"], (step, obs["object_origin_pos"], obs["goal_pos"])
    finally:
        e.close()
