"""impact-eval method registry: names, checkpoint paths, SB3 wrapping."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest
from fixtures.eval_fake import BARE_ID, ENV_ID

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_envs.envs.options import ObservationOptions
from impact_eval.cli import main
from impact_eval.methods import (
    CHECKPOINTS_ENV_VAR,
    checkpoint_dir,
    env_short_name,
    method_choices,
    resolve_method,
)
from impact_eval.sb3 import load_sb3


def test_builtin_methods_and_controllers() -> None:
    expected = {
        "scripted": "impedance",
        "scripted_impact": "impact",
        "vanilla_dp": "impedance",
        "augmented_dp": "impedance",
        "impact": "impact",
    }
    for name, controller in expected.items():
        assert resolve_method(name).controller == controller
    assert "sb3:<path.zip>" in method_choices()
    assert resolve_method("sb3:x.zip").controller == "impact"
    assert resolve_method("sb3_impedance:x.zip").controller == "impedance"
    with pytest.raises(InvalidArgumentError, match="valid choices: scripted, scripted_impact"):
        resolve_method("sb3:")


def test_checkpoint_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert env_short_name("IMPACT/Hammer-v1") == "hammer"
    assert env_short_name("pkg.mod:IMPACT/PickPlace-v12") == "pickplace"
    monkeypatch.setenv(CHECKPOINTS_ENV_VAR, str(tmp_path))
    (tmp_path / "hammer" / "augmented").mkdir(parents=True)
    assert checkpoint_dir("IMPACT/Hammer-v1", "augmented") == tmp_path / "hammer" / "augmented"
    with pytest.raises(CheckpointError, match="no vanilla checkpoint for IMPACT/Hammer-v1"):
        checkpoint_dir("IMPACT/Hammer-v1", "vanilla")


@pytest.fixture(scope="module")
def sac_zip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An untrained SAC on the fake env, saved (PPO.load must fail, SAC.load succeed)."""
    from stable_baselines3 import SAC

    env = gym.make(BARE_ID)
    path = tmp_path_factory.mktemp("sb3") / "sac_fake.zip"
    SAC("MultiInputPolicy", env, buffer_size=10, seed=0, device="cpu").save(path)
    return path


def test_sb3_zip_is_not_loaded_without_opt_in(sac_zip: Path, monkeypatch) -> None:
    monkeypatch.delenv("IMPACT_TRUST_SB3", raising=False)
    with pytest.raises(CheckpointError, match="can execute code; pass --trust-sb3"):
        load_sb3(str(sac_zip), gym.make(BARE_ID))


def test_sb3_policy_is_batched_and_deterministic(sac_zip: Path, monkeypatch) -> None:
    monkeypatch.setenv("IMPACT_TRUST_SB3", "1")
    env = gym.make(BARE_ID)
    policy = load_sb3(str(sac_zip), env)
    obs = {"progress": np.zeros((3, 1), np.float32), "noise": np.ones((3, 2), np.float32)}
    policy.reset(3)
    actions = policy.act(obs)
    assert actions.shape == (3, 10) and actions.dtype == np.float32
    assert np.array_equal(actions, policy.act(obs))


def test_sb3_method_sweeps(sac_zip: Path, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.delenv("IMPACT_TRUST_SB3", raising=False)  # --trust-sb3 below sets it
    out = tmp_path / "out"
    args = [
        "--env",
        ENV_ID,
        "--method",
        f"sb3:{sac_zip},fake_fast",
        "--masses",
        "1,3",
        "--episodes",
        "2",
        "--workers",
        "1",
        "--out",
        str(out),
        "--trust-sb3",
    ]
    assert main(args) == 0
    episodes = pd.read_csv(out / "episodes.csv")
    assert set(episodes["method"]) == {f"sb3:{sac_zip}", "fake_fast"}
    assert len(episodes) == 8


def test_trace_prints_one_episode():
    """python -m impact_experiments.trace: header, sampled rows, and the outcome line."""
    import impact_experiments.trace as trace_mod

    lines = trace_mod.trace("IMPACT/Hammer-v1", "scripted_impact", 0.2, seed=0, every=60)
    assert lines[0] == trace_mod.HEADER
    assert lines[-1].startswith("success: True")
    assert len(lines) >= 4


def test_trace_guard_columns_show_the_applied_feedforward_carrying_the_load():
    """--guard: the guard's phase and the applied force feedforward; while the scripted
    expert carries a 2.5 kg hammer aloft, the vertical feedforward holds its weight
    (24.5 N, within the learner's and the hammer's grip lever: 20-28 N) and sideways little."""
    import impact_experiments.trace as trace_mod

    lines = trace_mod.trace("IMPACT/Hammer-v1", "scripted_impact", 2.5, seed=0, every=40,
                            guard=True)
    assert lines[0] == trace_mod.HEADER + trace_mod.GUARD_HEADER
    aloft = [row.split() for row in lines[1:-1] if float(row.split()[4]) > 0.1]  # obj_z
    assert aloft
    for row in aloft:
        assert row[11] in trace_mod.GUARD_PHASES.values()
        ff_x, ff_y, ff_z = map(float, row[12:15])
        assert 20.0 < ff_z < 28.0 and abs(ff_x) < 5.0 and abs(ff_y) < 5.0


def test_trace_contacts_show_the_grasp_while_carrying():
    """--contacts: a line under each row; while the scripted expert carries the 2.5 kg hammer
    aloft, the finger pads hold its handle (each pad's grip above 5 N) and nothing else of the
    robot touches anything."""
    import impact_experiments.trace as trace_mod

    lines = trace_mod.trace("IMPACT/Hammer-v1", "scripted_impact", 2.5, seed=0, every=40,
                            contacts=True)
    rows = lines[1:-1]
    assert all(c.startswith("      contacts: ") for c in rows[1::2])
    aloft = [c for r, c in zip(rows[0::2], rows[1::2], strict=True)
             if float(r.split()[4]) > 0.1]
    assert aloft
    for line in aloft:
        pairs = dict(p.split(": ") for p in line.split("contacts: ")[1].split("; "))
        assert set(pairs) == {"left_pad/hammer_handle", "right_pad/hammer_handle"}
        assert all(float(n) > 5.0 for n in pairs.values())


def test_trace_without_joint_friction_zeroes_the_plants_friction(monkeypatch):
    """--no-joint-friction: the arm's dof friction is 0 in the episode's model (after reset),
    and a Calligraphy trace ends with the writing summary."""
    import impact_experiments.trace as trace_mod
    from impact_eval import envs as envs_mod

    made = []

    def recording_method_env(*args, **kwargs):
        made.append(envs_mod.method_env(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(trace_mod, "method_env", recording_method_env)
    lines = trace_mod.trace("IMPACT/Calligraphy-v1", "scripted", 0.1, seed=0, every=1000,
                            joint_friction=False)
    sim = made[0].unwrapped.sim
    assert np.all(sim.model.dof_frictionloss[sim.arm_dof] == 0.0)
    assert sim.data.nf == 0  # no Coulomb-friction constraint rows left in the plant
    assert "writing: force in band" in lines[-1]


def test_trace_opens_a_camera_method_as_impact_eval_does():
    """A camera method's trace env renders its checkpoint's cameras and hides the object's
    pose from the policy; the trace reads the object from the task instead."""
    import impact_experiments.trace as trace_mod

    env, _ = trace_mod.open_method("IMPACT/HammerBasket-v2", "impact_rgb")
    try:
        keys = set(env.observation_space.spaces)
        assert {"basket_front_rgb", "basket_side_rgb"} <= keys and "object_pos" not in keys
        env.reset(seed=0)
        assert env.unwrapped.task.observation(env.unwrapped.sim)["object_pos"].shape == (3,)
    finally:
        env.close()


@pytest.mark.parametrize("argv", [["--method", "nope", "--value", "1"],
                                  ["--method", "scripted", "--value", "-3"],
                                  ["--env", "IMPACT/Nope-v0", "--method", "scripted",
                                   "--value", "1"]])
def test_trace_bad_input_is_one_line_exit_2(argv, capsys):
    import impact_experiments.trace as trace_mod

    with pytest.raises(SystemExit) as exc:
        trace_mod.main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "error" in err


SHIPPED = sorted((p.parent.name, p.name) for p in
                 (Path(__file__).parents[2] / "impact_envs" / "checkpoints").glob("*/*"))


VARIANT_METHOD = {"vanilla": "vanilla_dp", "augmented": "augmented_dp", "impact": "impact",
                  "vanilla_rgb": "vanilla_dp_rgb", "lerobot_dp": "lerobot_dp",
                  "vanilla_authors": "vanilla_dp_authors",
                  "augmented_authors": "augmented_dp_authors",
                  "augmented_rgb": "augmented_dp_rgb"}
"""The method that loads each checkpoint variant (``lerobot_dp`` needs LeRobot: checked in its
venv, tests/lerobot_plugin/test_plugin_policy.py without it)."""


@pytest.mark.parametrize("env_name, variant", SHIPPED)
def test_shipped_checkpoint_loads_and_acts_in_its_env(env_name: str, variant: str,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """Every shipped checkpoint loads without pickle and emits in-space actions for its env."""
    if variant == "lerobot_dp":
        pytest.importorskip("lerobot", reason="LeRobot's checkpoint needs lerobot")
    import impact_envs
    from impact_control.policy import stack_obs
    from impact_eval.envs import method_env

    monkeypatch.delenv(CHECKPOINTS_ENV_VAR, raising=False)
    env_id = next(e for e in impact_envs.ENV_IDS if env_short_name(e) == env_name)
    spec = resolve_method(VARIANT_METHOD[variant])
    env = method_env(env_id, spec)  # the method's controller and observation (cameras)
    policy = spec.build(env_id, env)
    obs, _ = env.reset(seed=0)
    policy.reset(2)
    actions = policy.act(stack_obs([obs, obs]))
    assert actions.shape == (2, *env.action_space.shape) and np.all(np.isfinite(actions))
    assert env.action_space.contains(actions[0].astype(np.float32))
    env.close()


def test_the_paper_benchmarks_ship_vanilla_and_augmented() -> None:
    for env_name in ("hammer", "dumbbell"):
        assert {(env_name, "vanilla"), (env_name, "augmented")} <= set(SHIPPED)


def test_sb3_model_trained_on_rl_actions_is_evaluated_in_its_mode(tmp_path, monkeypatch):
    """A delta-mode SAC on Hammer: the sweep wraps its envs in RLActions(mode="delta") (read
    from the zip, no unpickling), under IMPACT (sb3:) or impedance (sb3_impedance:); saved
    VecNormalize statistics normalize its observations."""
    sb3 = pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from impact_envs.wrappers import RLActions
    from impact_eval.sb3 import sb3_action_mode

    venv = VecNormalize(DummyVecEnv([lambda: RLActions(gym.make("IMPACT/Hammer-v1"),
                                                       mode="delta")]), norm_reward=False)
    model = sb3.SAC("MultiInputPolicy", venv, learning_starts=8, batch_size=8, seed=0,
                    device="cpu")
    model.learn(16)
    zip_path = tmp_path / "sac_delta.zip"
    model.save(zip_path)
    venv.save(tmp_path / "vec_normalize.pkl")
    assert sb3_action_mode(str(zip_path)) == "delta"
    monkeypatch.setenv("IMPACT_TRUST_SB3", "1")
    env = RLActions(gym.make("IMPACT/Hammer-v1"), mode="delta")
    policy = load_sb3(str(zip_path), env)
    assert policy.vecnormalize is not None
    obs, _ = env.reset(seed=0)
    batch = {k: v[None] for k, v in obs.items()}
    expected, _ = model.predict(policy.vecnormalize.normalize_obs(batch), deterministic=True)
    np.testing.assert_array_equal(policy.act(batch), expected)
    for prefix, controller in (("sb3:", "impact"), ("sb3_impedance:", "impedance")):
        spec = resolve_method(f"{prefix}{zip_path}")
        assert (spec.controller, spec.action_mode) == (controller, "delta")


def test_camera_methods_make_their_envs_with_the_checkpoint_cameras():
    """``vanilla_dp_rgb`` / ``impact_rgb`` / ``impact_rgb_paper``: the env observes the cameras
    the checkpoint's demonstrations recorded (Hammer: overview and wrist at 96², no shadows; no
    object pose), and these methods share envs only with methods of the same observation."""
    from impact_eval.envs import method_env

    hammer = "IMPACT/Hammer-v1"
    expected = ObservationOptions(obs_mode="rgb", cameras=("overview", "wrist"), image_width=96,
                                  image_height=96, shadows=False)
    rgb, impact_rgb = resolve_method("vanilla_dp_rgb"), resolve_method("impact_rgb")
    paper = resolve_method("impact_rgb_paper")
    assert rgb.observation_for(hammer) == impact_rgb.observation_for(hammer) == expected
    assert paper.observation_for(hammer) == expected
    assert resolve_method("vanilla_dp").observation_for(hammer) is None
    assert (rgb.controller, impact_rgb.controller) == ("impedance", "impact")
    assert (paper.controller, paper.preset, impact_rgb.preset) == ("impact", "paper", "default")
    assert rgb.env_key(hammer) != resolve_method("vanilla_dp").env_key(hammer)
    env = method_env(hammer, rgb)
    try:
        spaces = env.observation_space.spaces
        assert spaces["overview_rgb"].shape == spaces["wrist_rgb"].shape == (96, 96, 3)
        assert "object_pos" not in spaces and "goal_pos" not in spaces
        assert env.unwrapped.observation_options == expected
    finally:
        env.close()


def test_a_camera_method_without_its_checkpoint_is_one_line(monkeypatch, tmp_path):
    monkeypatch.setenv(CHECKPOINTS_ENV_VAR, str(tmp_path))
    with pytest.raises(CheckpointError, match="no vanilla_rgb checkpoint for IMPACT/Dumbbell-v1"):
        resolve_method("vanilla_dp_rgb").observation_for("IMPACT/Dumbbell-v1")
    (tmp_path / "dumbbell" / "vanilla_rgb").mkdir(parents=True)
    (tmp_path / "dumbbell" / "vanilla_rgb" / "meta.json").write_text("{not json")
    with pytest.raises(CheckpointError, match="cannot read the observation of checkpoint"):
        resolve_method("vanilla_dp_rgb").observation_for("IMPACT/Dumbbell-v1")


def test_the_sweep_passes_a_resolved_preset() -> None:
    from impact_eval.envs import (
        describe_env,
        make_env,  # the sweep's env factory
    )

    env = make_env("IMPACT/Hammer-v1", "impact", preset="keep_carried")
    assert env.unwrapped.controller_preset == "keep_carried"
    # run.json's env spec keeps the preset by name (serialisable, as before)
    assert '"controller_preset": "keep_carried"' in describe_env(env).spec_json
    env.close()
    env = make_env("IMPACT/Hammer-v1", "impact", ["internal_model.learning_rate=0.02"],
                   preset="keep_carried")
    assert env.unwrapped.controller_preset == "custom"
    assert env.unwrapped.controller.config.saturation_release.spare_carried
    env.close()
