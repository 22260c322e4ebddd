"""Pixel observations (``ObservationOptions``, ``envs/pixels.py``) on every registered env.

Small, non-square images (48 wide, 40 high) keep it fast and catch a swapped width and height;
SB3's checker warns below 36 px, so its warnings are checked at that size too.
"""

from __future__ import annotations

import copy
import warnings

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import impact_envs
from impact_control.errors import InvalidArgumentError
from impact_envs.envs.options import ObservationOptions
from impact_envs.envs.pixels import privileged_keys

ENV_IDS = impact_envs.ENV_IDS
ROBOT_KEYS = ("ee_pos", "ee_rot6d", "gripper_width", "joint_pos", "joint_vel")
W, H = 48, 40


def _make(env_id: str, mode: str, cameras: tuple[str, ...] = ("overview", "wrist"),
          width: int = W, height: int = H) -> gym.Env:
    return gym.make(env_id, observation=ObservationOptions(mode, cameras, width, height))


def _hold(obs: dict[str, np.ndarray], gripper: float) -> np.ndarray:
    """Keep the TCP where it is; gripper -1 open, +1 closed."""
    return np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [gripper]]).astype(np.float32)


@pytest.mark.parametrize("mode", ["rgb", "rgbd", "state+rgb"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_check_env(env_id, mode):
    env = _make(env_id, mode)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize("mode", ["rgb", "rgbd", "state+rgb"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env(env_id, mode):
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = _make(env_id, mode)
    sb3_check_env(env, warn=False)
    env.close()


@pytest.mark.parametrize("mode", ["rgb", "rgbd"])
def test_sb3_warns_only_about_float_depth(mode):
    """At 96x96 SB3's checker has nothing to say about the RGB images; a depth image is a
    float32 image in metres, which SB3's checker warns about (not uint8 in [0, 255]): its
    ``MultiInputPolicy`` flattens it instead of passing it through its CNN."""
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = _make(ENV_IDS[0], mode, width=96, height=96)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_check_env(env, warn=True)
    env.close()
    image_warnings = [str(w.message) for w in caught if "image" in str(w.message)]
    if mode == "rgb":
        assert image_warnings == []
    else:
        assert any("float32" in m for m in image_warnings)
        assert all("_depth" in m for m in image_warnings)  # dtype and [0, 255] bounds


@pytest.mark.parametrize("mode", ["state", "rgb", "rgbd", "state+rgb"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_keys_shapes_dtypes_and_hidden_state(env_id, mode):
    env = _make(env_id, mode)
    obs, _ = env.reset(seed=0)
    state_keys = set(gym.make(env_id).observation_space.spaces)
    hidden = set(privileged_keys(env.unwrapped.task))
    images = {f"{c}_{kind}": (H, W, n) for c in ("overview", "wrist")
              for kind, n in (("rgb", 3), ("depth", 1)) if kind == "rgb" or mode == "rgbd"}
    expected = {"state": state_keys, "state+rgb": state_keys | images.keys()}.get(
        mode, (state_keys - hidden) | images.keys())
    assert set(obs) == set(env.observation_space.spaces) == expected
    assert list(obs) == list(env.observation_space.spaces)
    assert set(ROBOT_KEYS) <= set(obs) and hidden and "object_pos" in hidden
    for key, shape in images.items() if mode != "state" else ():
        assert obs[key].shape == shape
        assert obs[key].dtype == (np.uint8 if key.endswith("_rgb") else np.float32)
    assert env.observation_space.contains(obs)
    env.close()


def test_calligraphy_keeps_its_reference_and_hides_the_pen():
    env = _make("IMPACT/Calligraphy-v1", "rgb")
    assert "goal_pos" in env.observation_space.spaces
    assert not {"object_pos", "object_rot6d"} & set(env.observation_space.spaces)
    env.close()


def test_a_task_without_a_declaration_hides_all_its_entries():
    import fixtures.reach_task  # noqa: F401  (registers IMPACT-Test/Reach-v0)

    env = _make("IMPACT-Test/Reach-v0", "rgb", cameras=("wrist",))
    assert set(env.observation_space.spaces) == {*ROBOT_KEYS, "wrist_rgb"}
    env.close()


def _rollout(env: gym.Env, seed: int, steps: int) -> list[dict[str, np.ndarray]]:
    obs, _ = env.reset(seed=seed)
    frames = [obs]
    for k in range(steps):
        obs, *_ = env.step(_hold(frames[0], 1.0 if k >= 1 else -1.0))
        frames.append(obs)
    return frames


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_images_are_deterministic_for_a_seed(env_id):
    a = _rollout(_make(env_id, "rgbd"), seed=3, steps=3)
    b = _rollout(_make(env_id, "rgbd"), seed=3, steps=3)
    for fa, fb in zip(a, b, strict=True):
        for key in fa:
            np.testing.assert_array_equal(fa[key], fb[key], err_msg=key)
    other = _rollout(_make(env_id, "rgb"), seed=4, steps=0)[0]
    assert not np.array_equal(a[0]["overview_rgb"], other["overview_rgb"])


def test_a_deep_copy_renders_the_same_next_images():
    env = _make(ENV_IDS[0], "rgb").unwrapped
    obs, _ = env.reset(seed=5)
    env.step(_hold(obs, -1.0))
    twin = copy.deepcopy(env)
    action = _hold(obs, 1.0)
    first, second = env.step(action)[0], twin.step(action)[0]
    for key in first:
        np.testing.assert_array_equal(first[key], second[key], err_msg=key)
    env.close()
    twin.close()


def test_wrist_camera_sees_the_fingers_close():
    """Closing the gripper changes the wrist image far more than holding it open."""
    def wrist_change(gripper: float) -> float:
        env = _make("IMPACT/Hammer-v1", "rgb", cameras=("wrist",))
        obs, _ = env.reset(seed=0)
        for _ in range(10):
            last, *_ = env.step(_hold(obs, gripper))
        env.close()
        return float(np.abs(last["wrist_rgb"].astype(int) - obs["wrist_rgb"]).mean())

    still, closing = wrist_change(-1.0), wrist_change(1.0)
    assert closing > 5.0 * still + 1.0, (still, closing)


@pytest.mark.parametrize("camera", ["overview", "wrist"])
def test_depth_is_metres_along_the_optical_axis(camera):
    """The centre pixel (odd size: on the optical axis) reads the distance that a ray cast
    from the camera along its axis finds to the first visible geom."""
    env = _make("IMPACT/Dumbbell-v1", "rgbd", cameras=(camera,), width=41, height=41)
    obs, _ = env.reset(seed=0)
    m, d = env.unwrapped.sim.model, env.unwrapped.sim.data
    cam = m.camera(camera).id
    axis = -d.cam_xmat[cam].reshape(3, 3)[:, 2]
    geomid = np.zeros(1, np.int32)
    visible = np.array([1, 1, 1, 0, 0, 0], np.uint8)  # the renderer's default geom groups
    dist = mujoco.mj_ray(m, d, d.cam_xpos[cam], axis, visible, 1, -1, geomid)
    assert geomid[0] >= 0 and dist > 0.05
    assert abs(float(obs[f"{camera}_depth"][20, 20, 0]) - dist) < 2e-3
    env.close()


def test_one_renderer_reused_and_closed():
    env = _make(ENV_IDS[0], "rgb").unwrapped
    assert env._pixels._renderer is None
    obs, _ = env.reset(seed=0)
    renderer = env._pixels._renderer
    env.step(_hold(obs, -1.0))
    assert env._pixels._renderer is renderer is not None
    env.close()
    assert env._pixels._renderer is None


def test_state_mode_is_the_default_and_renders_nothing():
    default, explicit = gym.make(ENV_IDS[0]).unwrapped, _make(ENV_IDS[0], "state").unwrapped
    assert default._pixels is None and explicit._pixels is None
    assert default.observation_space == explicit.observation_space
    a, b = default.reset(seed=1)[0], explicit.reset(seed=1)[0]
    assert list(a) == list(b) and all(np.array_equal(a[k], b[k]) for k in a)
    default.close()
    explicit.close()


BAD = {
    "unknown mode": (lambda: ObservationOptions("pixels"),
                     "invalid obs_mode 'pixels'; valid choices: state, rgb, rgbd, state+rgb"),
    "cameras a string": (lambda: ObservationOptions("rgb", "wrist"), "invalid cameras 'wrist'"),
    "no camera": (lambda: ObservationOptions("rgb", ()), "a tuple of distinct camera names"),
    "camera twice": (lambda: ObservationOptions("rgb", ("wrist", "wrist")), "distinct"),
    "width zero": (lambda: ObservationOptions(image_width=0), "invalid image_width 0"),
    "height fractional": (lambda: ObservationOptions(image_height=2.5),
                          "invalid image_height 2.5; valid: an integer from 1 to 4096 px"),
    "width a bool": (lambda: ObservationOptions(image_width=True), "invalid image_width True"),
    "shadows not a bool": (lambda: ObservationOptions(shadows=1),
                           "invalid shadows 1; valid: True or False"),
}


@pytest.mark.parametrize("case", BAD)
def test_bad_options_are_one_line(case):
    build, message = BAD[case]
    with pytest.raises(InvalidArgumentError, match=message.replace("+", r"\+")) as err:
        build()
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(("opts", "message"), [
    (ObservationOptions("rgb", ("overview", "nope")),
     "invalid camera 'nope'; valid choices: front, side, overview, wrist"),
    (ObservationOptions("rgb", image_width=1000, image_height=900),
     "invalid image size 1000x900; valid: at most 640x480 px"),
])
def test_bad_camera_or_size_for_the_scene_is_one_line(opts, message):
    with pytest.raises(InvalidArgumentError, match=message) as err:
        gym.make(ENV_IDS[0], observation=opts)
    assert "\n" not in str(err.value)


def test_shadows_can_be_switched_off():
    def first_image(shadows: bool) -> np.ndarray:
        env = gym.make(ENV_IDS[0], observation=ObservationOptions(
            "rgb", ("overview",), W, H, shadows=shadows))
        image = env.reset(seed=0)[0]["overview_rgb"]
        env.close()
        return image

    assert not np.array_equal(first_image(True), first_image(False))


def test_bench_prints_the_pixel_costs(capsys):
    """A 2-step ``impact-bench --pixels`` run prints one row per camera and variant and the
    reference rows (what it prints, never how fast)."""
    from impact_eval import bench

    bench.main(["--steps", "2", "--repeat", "1", "--pixels", "--image-size", "16"])
    out = capsys.readouterr().out
    for row in ("env step, state (reference)", "env step, state+rgb (overview, wrist)",
                "render wrist rgb+depth", "render overview rgb, no shadows"):
        assert row in out


@pytest.mark.parametrize(("size", "message"), [("0", "need --image-size >= 1, got 0"),
                                               ("1000", "at most 640x480 px")])
def test_bench_bad_image_size_is_one_line(size, message, capsys):
    from impact_eval import bench

    with pytest.raises(SystemExit) as exit_:
        bench.main(["--pixels", "--image-size", size])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and message in err and err.count("\n") == 1
