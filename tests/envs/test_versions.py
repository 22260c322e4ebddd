"""One version history (impact_envs/versions.py): every env registers -v2 and keeps -v1
registered with its pins, a retired -v0 is refused in one line naming -v1, checkpoints trained
on v0 and v1 run on v2, and docs/envs.md's table is the history's."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import pytest
from gymnasium import error as gym_error

from impact_control.errors import InvalidArgumentError
from impact_control.presets import preset_config
from impact_envs import ENV_IDS, REGISTERED_IDS, RobotOptions
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


def test_every_env_registers_its_current_version_and_keeps_v1() -> None:
    assert tuple(current_id(family) for family in VERSIONS) == ENV_IDS
    assert all(version_of(env_id) == 2 for env_id in ENV_IDS)
    assert set(REGISTERED_IDS) == {*ENV_IDS, *(i.replace("-v2", "-v1") for i in ENV_IDS)}
    for env_id in REGISTERED_IDS:
        assert gym.spec(env_id).kwargs["env_version"] == version_of(env_id)


@pytest.mark.parametrize("family", sorted(VERSIONS))
def test_each_version_pins_its_robot_and_presets(family: str) -> None:
    """-v1 keeps the ideal robot and preset revision 1 (the default its tables ran); -v2 is
    the fr3 robot (HammerBasket: the authors' ideal one) and revision 2."""
    v1 = gym.make(f"IMPACT/{family}-v1").unwrapped
    v2 = gym.make(f"IMPACT/{family}-v2").unwrapped
    assert v1.robot_profile == "ideal"
    assert v2.robot_profile == ("ideal" if family == "HammerBasket" else "fr3")
    assert v1.controller.config == preset_config("default", revision=1)
    assert v2.controller.config == preset_config("default", revision=2)
    assert v1.controller_preset == v2.controller_preset == "default"
    # an explicit profile wins over the version's; other robot fields leave it to the version
    assert gym.make(f"IMPACT/{family}-v2", robot={"realism": "ideal"}).unwrapped.robot_profile == (
        "ideal")
    assert gym.make(f"IMPACT/{family}-v1",
                    robot=RobotOptions(sensor_noise=False)).unwrapped.robot_profile == "ideal"
    for env in (v1, v2):
        env.close()


def test_env_version_is_checked_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="valid: 1, 2"):
        gym.make("IMPACT/Hammer-v2", env_version=0)


@pytest.mark.parametrize("family", sorted(VERSIONS))
def test_a_retired_id_is_one_line_naming_the_pinned_one(family: str) -> None:
    old, then, now = (f"IMPACT/{family}-v{v}" for v in (0, 1, 2))
    with pytest.raises(gym_error.DeprecatedEnv, match=f"{now}"):  # Gymnasium's own message
        gym.make(old)
    with pytest.raises(InvalidArgumentError, match=f"retired.*use {then}.*or {now}") as info:
        check_env_id(old)
    assert "\n" not in str(info.value)
    assert retired(then) is None and retired(now) is None
    assert retired("ImpactTest/Fake-v0") is None


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
    assert runs_checkpoint_of("IMPACT/Hammer-v2", "IMPACT/Hammer-v1")
    assert not runs_checkpoint_of("IMPACT/Hammer-v1", "IMPACT/Hammer-v2")
    assert runs_checkpoint_of("mod:IMPACT/Hammer-v1", "IMPACT/Hammer-v1")
    assert not runs_checkpoint_of("IMPACT/Hammer-v1", "IMPACT/Dumbbell-v0")
    assert runs_checkpoint_of("ImpactTest/Fake-v0", "ImpactTest/Fake-v0")
    assert not runs_checkpoint_of("ImpactTest/Fake-v0", "ImpactTest/Fake-v1")


def test_the_docs_table_is_the_history() -> None:
    assert history_markdown() in DOCS.read_text()


def test_the_hammer_basket_authors_methods_run_the_same_on_v1_and_v2() -> None:
    """HammerBasket-v2 changes only what "default" resolves to; no method of the table of
    their baselines (results/hammer_basket_authors) runs it, so each builds the same controller
    and robot on both versions (issue 59: that table needs no -v2 rerun)."""
    import json

    from impact_eval.envs import make_env
    from impact_eval.methods import resolve_method

    manifest = json.loads((DOCS.parents[1] / "results" / "manifest.json").read_text())
    args = manifest["tables"]["hammer_basket_authors"]["sweep_args"]
    for name in args[args.index("--method") + 1].split(","):
        spec = resolve_method(name)
        assert spec.preset != "default", name
        built = []
        for version in (1, 2):
            env = make_env(f"IMPACT/HammerBasket-v{version}", spec.controller, (), spec.preset,
                           robot=spec.robot).unwrapped
            built.append((env.controller.config, env.robot_profile, env.realism,
                          env.controller_preset))
            env.close()
        assert built[0] == built[1], name
