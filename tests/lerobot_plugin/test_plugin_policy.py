"""The LeRobot policy adapter's side that needs no LeRobot: a batch of our observations laid
out as ``lerobot-eval`` lays out each env's (through the plugin's wrapper and LeRobot's
``preprocess_observation`` conventions), and the one-line refusals of the ``lerobot_*``
methods. The loaded checkpoint's rows are checked in the LeRobot venv (docs/lerobot.md)."""

from __future__ import annotations

import importlib.util

import gymnasium as gym
import numpy as np
import pytest

from impact_control.errors import CheckpointError
from impact_eval.methods import resolve_method
from impact_lerobot import PluginSettings, make_lerobot_env, observation_plan
from impact_lerobot.policy import LEROBOT_MISSING, load_lerobot_policy

HAS_LEROBOT = importlib.util.find_spec("lerobot") is not None


def _two_envs(settings: PluginSettings) -> tuple[list[dict], list[dict]]:
    """Our observation and the wrapper's (what ``lerobot-eval`` gets), for two seeds."""
    ours, theirs = [], []
    for seed in (1, 2):
        env = gym.make(settings.env_id, observation=settings.observation)
        ours.append(env.reset(seed=seed)[0])
        env.close()
        wrapped = make_lerobot_env(settings.task, settings)
        theirs.append(wrapped.reset(seed=seed)[0])
        wrapped.close()
    return ours, theirs


@pytest.mark.parametrize("obs_mode", ["state", "state+rgb"])
def test_policy_batch_is_what_lerobot_eval_feeds(obs_mode: str) -> None:
    settings = PluginSettings(task="Hammer-v1", obs_mode=obs_mode, image_width=32,
                              image_height=24)
    plan = observation_plan(settings)
    ours, theirs = _two_envs(settings)
    batch = plan.policy_batch({k: np.stack([o[k] for o in ours]) for k in ours[0]})
    vectors = {"observation.state": "agent_pos",
               "observation.environment_state": "environment_state"}
    for name, key in vectors.items():
        assert batch[name].dtype == np.float32
        np.testing.assert_array_equal(batch[name], np.stack([t[key] for t in theirs]))
    cameras = [k for k in batch if k.startswith("observation.images.")]
    assert len(cameras) == (2 if obs_mode == "state+rgb" else 0)
    for name in cameras:
        camera = name.rsplit(".", 1)[1]
        frames = np.stack([t["pixels"][camera] for t in theirs])  # B x H x W x 3, uint8
        assert batch[name].shape == (2, 3, 24, 32)
        np.testing.assert_array_equal(
            batch[name], frames.transpose(0, 3, 1, 2).astype(np.float32) / 255.0)


@pytest.mark.skipif(HAS_LEROBOT, reason="LeRobot is installed: its absence cannot be tested")
def test_lerobot_methods_without_lerobot_are_one_line(tmp_path) -> None:
    with pytest.raises(CheckpointError) as err:
        load_lerobot_policy(tmp_path, "IMPACT/Hammer-v1")
    assert str(err.value) == LEROBOT_MISSING and "\n" not in str(err.value)
    for name in ("lerobot_dp", "lerobot_dp_impact"):
        spec = resolve_method(name)
        assert spec.controller == ("impedance" if name == "lerobot_dp" else "impact")
        with pytest.raises(CheckpointError):
            spec.build("IMPACT/Hammer-v1", None)


def _no_lerobot_needed(monkeypatch) -> None:
    """The config.json is read before any LeRobot class is used: stand-ins that fail the test
    if a damaged config got that far."""
    from impact_lerobot import policy

    def looked_up(*args: object, **kwargs: object) -> None:
        raise AssertionError("a damaged config.json reached LeRobot")

    monkeypatch.setattr(policy, "_lerobot_classes", lambda: (looked_up, looked_up))


@pytest.mark.parametrize(("content", "message"), [
    (b'{"type": "diffusion", "n_obs_steps": 2', "is not JSON (Expecting ',' delimiter at line 1"),
    (b"", "is not JSON (Expecting value at line 1 column 1)"),
    (b"\xff\xfe{}", "cannot be read (not UTF-8 text)"),
    (b"[" * 100_000, "nested too deeply"),
    (b'["diffusion"]', "holds a JSON array, not an object"),
    (b"3.5", "holds a JSON number, not an object"),
    (b'"diffusion"', "holds a JSON string, not an object"),
    (b"null", "holds a JSON null, not an object"),
    (b"true", "holds a JSON boolean, not an object"),
    (b"{}", 'has no "type"'),
    (b'{"type": 7}', 'has "type" 7'),
    (b'{"type": ["diffusion"]}', "has \"type\" ['diffusion']"),
    (b'{"type": "  "}', "has \"type\" '  '"),
])
def test_a_damaged_or_foreign_config_json_is_one_checkpoint_error(content, message, tmp_path,
                                                                   monkeypatch) -> None:
    """Was a raw JSONDecodeError / AttributeError: now the docstring's one line, naming the
    file and what is wrong, before LeRobot is asked for anything."""
    _no_lerobot_needed(monkeypatch)
    config = tmp_path / "config.json"
    config.write_bytes(content)
    with pytest.raises(CheckpointError) as err:
        load_lerobot_policy(tmp_path, "IMPACT/Hammer-v1")
    text = str(err.value)
    assert "\n" not in text and str(config) in text and message in text, text
    assert "valid: the config.json lerobot-train saves" in text
    assert config.read_bytes() == content  # read, never rewritten


def test_a_config_json_that_is_a_folder_or_missing_is_one_line(tmp_path, monkeypatch) -> None:
    _no_lerobot_needed(monkeypatch)
    with pytest.raises(CheckpointError, match="config.json is missing$"):
        load_lerobot_policy(tmp_path, "IMPACT/Hammer-v1")
    (tmp_path / "config.json").mkdir()
    with pytest.raises(CheckpointError, match="config.json is not a file; valid: "):
        load_lerobot_policy(tmp_path, "IMPACT/Hammer-v1")
