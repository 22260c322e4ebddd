"""impact_eval.evaluate: a policy object over a grid, the CLI's files, resume, bad input."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from fixtures.eval_fake import ENV_ID

import impact_eval
from impact_control.errors import InvalidArgumentError


class _Constant:
    """Pushes the fake env's progress at full speed (its action's first entry)."""

    def reset(self, n_envs: int) -> None:
        self.n = n_envs

    def act(self, obs):
        import numpy as np

        return np.tile(np.array([1.0] + [0.0] * 9, dtype=np.float32), (self.n, 1))


def test_evaluate_writes_the_cli_files_and_returns_the_episodes(tmp_path):
    table = impact_eval.evaluate(_Constant(), ENV_ID, [0.5, 2.0], tmp_path / "run", episodes=3,
                                 controller="impedance", name="const")
    assert len(table) == 6 and set(table["method"]) == {"const"}
    assert sorted(table["param_value"].unique()) == [0.5, 2.0]
    on_disk = pd.read_csv(tmp_path / "run" / "episodes.csv", keep_default_na=False)
    pd.testing.assert_frame_equal(table, on_disk)
    assert (tmp_path / "run" / "summary.csv").is_file()
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    assert run["identity"]["spec"]["methods"] == ["const"] and "policy=const" in run["command"]
    again = impact_eval.evaluate(_Constant(), ENV_ID, [0.5, 2.0], tmp_path / "run", episodes=3,
                                 controller="impedance", name="const", resume=True)
    pd.testing.assert_frame_equal(again, table)  # nothing left to run, same rows


def test_a_factory_is_called_with_the_env(tmp_path):
    seen = []

    def factory(env_id, env):
        seen.append(env_id)
        return _Constant()

    impact_eval.evaluate(factory, ENV_ID, [1.0], tmp_path / "f", episodes=1)
    assert seen and seen[0].endswith("ImpactTest/Fake-v0")


def test_bad_input_is_one_line_and_writes_nothing(tmp_path):
    with pytest.raises(InvalidArgumentError, match="valid"):
        impact_eval.evaluate(_Constant(), ENV_ID, [1.0], tmp_path / "x", controller="pid")
    with pytest.raises(InvalidArgumentError, match="rejected"):
        impact_eval.evaluate(_Constant(), ENV_ID, [0.0], tmp_path / "y")
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_controller_preset_reaches_the_env_and_a_bad_one_is_one_line(tmp_path):
    with pytest.raises(InvalidArgumentError, match="valid choices: default, paper") as err:
        impact_eval.evaluate(_Constant(), ENV_ID, [1.0], tmp_path / "bad",
                             controller_preset="literal")
    assert "\n" not in str(err.value)
    # the fake env takes no preset: "paper" is handed to gym.make and refused there, in one
    # line, before anything is written (a plugin env never runs another configuration silently)
    with pytest.raises(InvalidArgumentError, match="controller_preset") as err:
        impact_eval.evaluate(_Constant(), ENV_ID, [1.0], tmp_path / "paper",
                             controller_preset="paper")
    assert "\n" not in str(err.value)
    assert not (tmp_path / "bad").exists() and not (tmp_path / "paper").exists()

