"""docs/envs.md, "What `info` holds": its tables list exactly the keys a step's ``info`` has, on
every registered env (the parameter values under their own names aside)."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import pytest

import impact_envs

PAGE = Path(__file__).resolve().parents[2] / "docs" / "envs.md"
OPTIONAL = {"images_rendered", "ff_into_contact_trace_n", "contact_object_net_trace_n"}
"""Keys present only in an image mode or with the press diagnostics on (the table says so)."""


def _section() -> str:
    text = PAGE.read_text()
    return text[text.index("## What `info` holds"):text.index("## Measured expert success")]


def _documented() -> set[str]:
    return set(re.findall(r"`([a-z_]+)`", _section()))


@pytest.mark.parametrize("env_id", impact_envs.ENV_IDS)
def test_the_info_table_lists_every_key(env_id: str) -> None:
    env = gym.make(env_id)
    try:
        _, reset_info = env.reset(seed=0)
        _, _, _, _, info = env.step(env.action_space.sample())
        params = set(env.unwrapped._episode_params)  # noqa: SLF001 - the parameters, by name
    finally:
        env.close()
    assert set(reset_info) == set(info)
    undocumented = set(info) - _documented() - params
    assert undocumented == set(), f"{env_id}: info keys missing from docs/envs.md"
    common = _section().split("The tasks add")[0]
    listed = set(re.findall(r"^\| `([a-z_]+)`", common, re.MULTILINE))
    assert listed - OPTIONAL <= set(info), "docs/envs.md lists keys no env has"
