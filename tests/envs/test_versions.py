"""One version history (impact_envs/versions.py): every env registers -v1, a retired -v0 is
refused in one line naming -v1, checkpoints trained on v0 run on v1, and docs/envs.md's
table is the history's."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import pytest
from gymnasium import error as gym_error

from impact_control.errors import InvalidArgumentError
from impact_envs import ENV_IDS
from impact_envs.versions import (
    VERSIONS,
    current_id,
    history_markdown,
    retired,
    runs_checkpoint_of,
    version_of,
)
from impact_eval.cli import main
from impact_eval.envs import check_env_id

DOCS = Path(__file__).resolve().parents[2] / "docs" / "envs.md"


def test_every_env_registers_its_current_version() -> None:
    assert tuple(current_id(family) for family in VERSIONS) == ENV_IDS
    assert all(version_of(env_id) == 1 for env_id in ENV_IDS)


@pytest.mark.parametrize("family", sorted(VERSIONS))
def test_a_retired_id_is_one_line_naming_the_current_one(family: str) -> None:
    old, now = f"IMPACT/{family}-v0", f"IMPACT/{family}-v1"
    with pytest.raises(gym_error.DeprecatedEnv, match=f"{now}"):
        gym.make(old)
    with pytest.raises(InvalidArgumentError, match=f"retired.*use {now}") as info:
        check_env_id(old)
    assert "\n" not in str(info.value)
    assert retired(now) is None and retired("ImpactTest/Fake-v0") is None


def test_the_cli_refuses_a_retired_env(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["--env", "IMPACT/Hammer-v0", "--method", "scripted", "--masses", "0.2",
                 "--episodes", "1", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "IMPACT/Hammer-v1" in err[0]
    assert not (tmp_path / "out").exists()


def test_collect_and_the_lerobot_task_refuse_a_retired_env(tmp_path: Path) -> None:
    from impact_learn.collect_config import CollectConfig
    from impact_lerobot.settings import PluginSettings

    with pytest.raises(InvalidArgumentError, match="use IMPACT/Dumbbell-v1"):
        CollectConfig(env_id="IMPACT/Dumbbell-v0", out=str(tmp_path / "x.zarr"))
    with pytest.raises(InvalidArgumentError, match="use gym_impact/Hammer-v1"):
        PluginSettings(task="Hammer-v0")


def test_v1_runs_checkpoints_trained_on_v0_of_its_own_family_only() -> None:
    assert runs_checkpoint_of("IMPACT/Hammer-v1", "IMPACT/Hammer-v0")
    assert runs_checkpoint_of("mod:IMPACT/Hammer-v1", "IMPACT/Hammer-v1")
    assert not runs_checkpoint_of("IMPACT/Hammer-v1", "IMPACT/Dumbbell-v0")
    assert runs_checkpoint_of("ImpactTest/Fake-v0", "ImpactTest/Fake-v0")
    assert not runs_checkpoint_of("ImpactTest/Fake-v0", "ImpactTest/Fake-v1")


def test_the_docs_table_is_the_history() -> None:
    assert history_markdown() in DOCS.read_text()
