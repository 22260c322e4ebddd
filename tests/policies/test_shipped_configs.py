"""Every training recipe under ``configs/`` loads as a ``DiffusionConfig`` (a typo in a key
or a bad value is caught here, not an hour into a training run)."""

from __future__ import annotations

from pathlib import Path

import pytest

from impact_envs.policies.diffusion.config import DiffusionConfig

CONFIGS = sorted((Path(__file__).resolve().parents[2] / "configs").glob("*.json"))


@pytest.mark.parametrize("path", CONFIGS, ids=[p.name for p in CONFIGS])
def test_a_shipped_recipe_loads(path: Path) -> None:
    cfg = DiffusionConfig.from_json(path)
    assert cfg.n_action_steps <= cfg.horizon


def test_the_hammer_basket_camera_recipe_is_theirs() -> None:
    cfg = DiffusionConfig.from_json(CONFIGS[0].parent / "dp_rgb_hb_cpu.json")
    assert (cfg.horizon, cfg.n_action_steps, cfg.n_obs_steps) == (32, 16, 2)
    assert cfg.vision is not None
    assert cfg.vision.image_keys == ("basket_front_rgb", "basket_side_rgb")
    assert "object_pos" not in cfg.obs_keys and "joint_pos" in cfg.obs_keys
    assert cfg.action_xyz == "delta_measured"
