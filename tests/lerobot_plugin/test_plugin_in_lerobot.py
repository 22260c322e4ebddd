"""The ``impact_lerobot`` plugin inside LeRobot 0.4.4: LeRobot's own plugin loader, parser,
``make_env`` and ``preprocess_observation`` on our envs, and ``lerobot-eval`` on Hammer with
a tiny random-weight Diffusion Policy (a wiring check: its success rate means nothing).

Needs ``IMPACT_LEROBOT_PYTHON`` (the virtualenv of ``tests/learn/lerobot_venv.sh``, which
holds lerobot and this package); skipped with that reason without it. Run by hand, not in CI,
as the export's load check (docs/lerobot.md)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

from impact_envs.tasks.bins import draw_in_bin

ROOT = Path(__file__).resolve().parents[2]
CHECK = Path(__file__).resolve().parent / "lerobot_plugin_check.py"
PYTHON = os.environ.get("IMPACT_LEROBOT_PYTHON", "")
EVAL_STEPS = 30
"""Policy steps of the ``lerobot-eval`` episode (the plugin's ``episode_length``)."""

pytestmark = pytest.mark.skipif(
    not PYTHON, reason="IMPACT_LEROBOT_PYTHON (lerobot's virtualenv with this package, "
                       "tests/learn/lerobot_venv.sh) not set: the plugin check needs lerobot")


def _run(args: list[str], check: bool = True) -> subprocess.CompletedProcess:
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "OMP_NUM_THREADS": "1", "MUJOCO_GL": "egl"}
    return subprocess.run(args, check=check, env=env, cwd=ROOT, timeout=600,
                          capture_output=True, text=True)


def _lerobot_env(tmp_path: Path, args: list[str]) -> dict:
    _run([PYTHON, str(CHECK), "env", str(tmp_path / "env.json"), *args])
    return json.loads((tmp_path / "env.json").read_text())


def test_lerobot_makes_and_steps_the_default_env(tmp_path) -> None:
    seen = _lerobot_env(tmp_path, ["--env.episode_length=2"])
    assert (seen["config_class"], seen["type"], seen["gym_id"]) == (
        "ImpactEnv", "impact", "gym_impact/Hammer-v1")
    assert seen["features_map"] == {"agent_pos": "observation.state",
                                    "environment_state": "observation.environment_state",
                                    "action": "action"}
    assert seen["policy_features"] == {"observation.state": [24],
                                       "observation.environment_state": [12], "action": [10]}
    assert seen["lerobot_obs"] == [{"observation.state": [1, 24],
                                    "observation.environment_state": [1, 12]}] * 3
    assert seen["max_episode_steps"] == 2 and seen["reset_mass"] == 0.2
    # LeRobot reads success from final_info when the episode ends (here: its length)
    assert seen["steps"][0]["final_is_success"] is None
    assert seen["steps"][1]["truncated"] and seen["steps"][1]["final_is_success"] is False


def test_lerobot_makes_an_image_env_with_a_mass_bin(tmp_path) -> None:
    seen = _lerobot_env(tmp_path, [
        "--env.task=Dumbbell-v1", "--env.controller=impedance", "--env.mass_bin=[1.0, 2.5]",
        "--env.obs_mode=state+rgb", "--env.cameras=[wrist]", "--env.image_width=32",
        "--env.image_height=24", "--env.episode_length=2"])
    assert seen["gym_id"] == "gym_impact/Dumbbell-v1"
    assert "controller='impedance'" in seen["settings"]
    assert seen["policy_features"]["observation.images.wrist"] == [3, 24, 32]
    assert seen["lerobot_obs"][-1] == {"observation.state": [1, 24],
                                       "observation.environment_state": [1, 12],
                                       "observation.images.wrist": [1, 3, 24, 32]}
    assert seen["reset_mass"] == draw_in_bin(1.0, 2.5, 7)  # the reset seed's draw


def test_a_bad_value_names_the_valid_choices_through_lerobots_parser(tmp_path) -> None:
    run = _run([PYTHON, str(CHECK), "env", str(tmp_path / "env.json"), "--env.controller=pid"],
               check=False)
    assert run.returncode != 0
    assert "invalid controller 'pid'; valid choices: impedance, impact" in run.stderr


def test_lerobot_eval_runs_on_hammer(tmp_path) -> None:
    policy, out = tmp_path / "policy", tmp_path / "eval"
    _run([PYTHON, str(CHECK), "policy", str(policy)])
    run = _run([str(Path(PYTHON).parent / "lerobot-eval"),
                "--env.discover_packages_path=impact_lerobot", "--env.type=impact",
                "--env.task=Hammer-v1", f"--env.episode_length={EVAL_STEPS}",
                f"--policy.path={policy}", "--eval.n_episodes=1", "--eval.batch_size=1",
                f"--output_dir={out}"])
    assert "'pc_success': " in run.stdout
    overall = json.loads((out / "eval_info.json").read_text())["overall"]
    assert overall["n_episodes"] == 1 and 0.0 <= overall["pc_success"] <= 100.0
    # lerobot-eval 0.4.4 always renders videos: offscreen rendering (MUJOCO_GL=egl) works
    assert [Path(p).stat().st_size > 0 for p in overall["video_paths"]] == [True]
