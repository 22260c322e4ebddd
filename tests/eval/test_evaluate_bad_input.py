"""``impact_eval.evaluate`` on bad input: one-line InvalidArgumentError, nothing written, no
method name left registered; resume refuses any change of what the rows were run with."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from fixtures.eval_fake import ENV_ID, FakePolicy

from impact_control.errors import InvalidArgumentError
from impact_envs import ObservationOptions
from impact_eval import evaluate
from impact_eval.api import EvaluationError
from impact_eval.methods import method_choices


class NoAct:
    def reset(self, n_envs: int) -> None:
        pass


class NoReset:
    def act(self, obs):
        return np.zeros((1, 10), np.float32)


GOOD = {"policy": FakePolicy(0.9), "env_id": ENV_ID, "values": [0.5, 1.0], "episodes": 2,
        "envs_per_worker": 2}

# name: (keyword arguments replacing GOOD's, part of the one-line message)
CASES: dict[str, tuple[dict[str, object], str]] = {
    "policy None": ({"policy": None}, "invalid policy None"),
    "policy without act": ({"policy": NoAct()}, "lacks act"),
    "policy without reset": ({"policy": NoReset()}, "lacks reset"),
    "policy is a class": ({"policy": FakePolicy}, "is the class FakePolicy"),
    "policy is a number": ({"policy": 3}, "policy int lacks reset and act"),
    "factory returns None": ({"policy": lambda env_id, env: None}, "factory returned"),
    "factory returns a class": ({"policy": lambda env_id, env: FakePolicy}, "is the class"),
    "values a string": ({"values": "25"}, "invalid values '25'"),
    "values a bool": ({"values": [True]}, "invalid value True"),
    "values a string item": ({"values": [1.0, "2"]}, "invalid value '2'"),
    "values nan": ({"values": [float("nan")]}, "invalid value nan"),
    "values inf": ({"values": [1.0, float("inf")]}, "invalid value inf"),
    "values empty": ({"values": []}, "values is empty"),
    "values a number": ({"values": 2.5}, "invalid values 2.5"),
    "values a dict": ({"values": {1: 2}}, "invalid values"),
    "values out of range": ({"values": [0.0]}, "object_mass=0.0 rejected"),
    "episodes zero": ({"episodes": 0}, "invalid episodes 0"),
    "episodes float": ({"episodes": 2.5}, "invalid episodes 2.5"),
    "episodes bool": ({"episodes": True}, "invalid episodes True"),
    "envs_per_worker zero": ({"envs_per_worker": 0}, "invalid envs_per_worker 0"),
    "seed negative": ({"seed": -1}, "invalid seed -1"),
    "seed a string": ({"seed": "0"}, "invalid seed '0'"),
    "controller unknown": ({"controller": "pid"}, "valid choices: impedance, impact"),
    "name a built-in method": ({"name": "scripted"}, "method name 'scripted' is taken"),
    "name with a comma": ({"name": "a,b"}, "invalid name 'a,b'"),
    "name empty": ({"name": ""}, "invalid name ''"),
    "name not a string": ({"name": 7}, "invalid name 7"),
    "name an sb3 prefix": ({"name": "sb3:x"}, "invalid name 'sb3:x'"),
    "env_id unknown": ({"env_id": "IMPACT/Nope-v0"}, "valid choices"),
    "env_id not a string": ({"env_id": 5}, "invalid env_id 5"),
    "param unknown": ({"param": "friction"}, "valid choices: object_mass"),
    "observation unknown key": ({"observation": {"mode": "rgb"}},
                                "invalid observation key(s) 'mode'; valid keys"),
    "observation a number": ({"observation": 3}, "invalid observation 3 (int)"),
    "observation a list": ({"observation": ["rgb"]}, "invalid observation ['rgb'] (list)"),
    "observation bad mode": ({"observation": "depth"}, "invalid obs_mode 'depth'"),
    "observation bad camera size": ({"observation": {"obs_mode": "rgb", "image_width": 0}},
                                    "invalid image_width 0"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input_is_one_line_and_writes_nothing(case: str, tmp_path: Path) -> None:
    changes, message = CASES[case]
    out = tmp_path / "out"
    before = set(method_choices())
    with pytest.raises(InvalidArgumentError) as err:
        evaluate(**{**GOOD, **changes}, out=out)
    text = str(err.value)
    assert message in text and "\n" not in text
    assert not out.exists()  # nothing written
    assert set(method_choices()) == before  # no name left registered by the refused call


def test_a_corrected_rerun_into_the_same_out_works_and_names_do_not_leak(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with pytest.raises(InvalidArgumentError):
        evaluate(**{**GOOD, "policy": None}, out=out, name="mine")
    table = evaluate(**GOOD, out=out, name="mine")
    assert len(table) == 4 and set(table["method"]) == {"mine"}
    assert "mine" not in method_choices()
    from impact_eval.methods import resolve_method

    assert resolve_method("scripted").description != "evaluate() policy object"


def test_resume_refuses_another_controller_even_without_run_json(tmp_path: Path) -> None:
    out = tmp_path / "out"
    evaluate(**GOOD, out=out, controller="impact")
    for gone in (False, True):
        if gone:
            (out / "run.json").unlink()
        with pytest.raises(InvalidArgumentError, match="ran with .*impact.* would now run"):
            evaluate(**GOOD, out=out, controller="impedance", resume=True)
    assert json.loads((out / "identity.json").read_text())["spec"]["episodes"] == 2
    with pytest.raises(InvalidArgumentError, match="episodes was 2"):
        evaluate(**{**GOOD, "episodes": 3}, out=out, resume=True)
    table = evaluate(**GOOD, out=out, controller="impact", resume=True)
    assert len(table) == 4


def test_every_episode_crashing_is_reported(tmp_path: Path) -> None:
    class Broken(FakePolicy):
        def act(self, obs):
            raise RuntimeError("boom")

    with pytest.raises(EvaluationError, match="every episode raised in 2 cell"):
        evaluate(**{**GOOD, "policy": Broken(0.0)}, out=tmp_path / "out")
    assert (tmp_path / "out" / "episodes.csv").exists()  # the rows are kept



class Interrupting(FakePolicy):
    """Raises KeyboardInterrupt (a user's Ctrl-C) at its ``stop_at``-th act call."""

    def __init__(self, push: float, stop_at: int) -> None:
        super().__init__(push)
        self.calls, self.stop_at = 0, stop_at

    def act(self, obs):
        self.calls += 1
        if self.calls == self.stop_at:
            raise KeyboardInterrupt
        return super().act(obs)


def test_an_interrupted_evaluate_resumes_to_the_same_bytes(tmp_path: Path) -> None:
    args = {**GOOD, "values": [0.5, 1.0, 3.0], "episodes": 3}
    evaluate(**args, out=tmp_path / "full")
    with pytest.raises(KeyboardInterrupt):
        evaluate(**{**args, "policy": Interrupting(0.9, stop_at=45)}, out=tmp_path / "cut")
    written = (tmp_path / "cut" / "episodes.csv").read_text().count("\n") - 1
    assert 0 < written < 9  # stopped mid-run, rows of finished episodes kept
    evaluate(**args, out=tmp_path / "cut", resume=True)
    assert (tmp_path / "cut" / "episodes.csv").read_bytes() == (
        tmp_path / "full" / "episodes.csv").read_bytes()


HAMMER = "IMPACT/Hammer-v1"


def _checkpoint(variant: str):
    from impact_envs.policies.diffusion.policy import DiffusionPolicy
    from impact_eval.methods import checkpoint_dir

    return DiffusionPolicy.load(checkpoint_dir(HAMMER, variant))


def _refused_before_writing(tmp_path: Path, error: type, match: str, **kwargs) -> str:
    out = tmp_path / "out"
    with pytest.raises(error) as info:
        evaluate(env_id=HAMMER, values=[2.5], out=out, episodes=1, **kwargs)
    assert not out.exists() and "\n" not in str(info.value)
    assert match in str(info.value)
    return str(info.value)


def test_camera_checkpoint_on_a_state_env_says_it_needs_images(tmp_path: Path) -> None:
    """It used to write a full results folder and raise "every episode raised"."""
    from impact_control.errors import CheckpointError

    policy = _checkpoint("vanilla_rgb")
    message = _refused_before_writing(tmp_path, CheckpointError, "needs camera images",
                                      policy=policy)
    assert "observation=" in message
    _refused_before_writing(tmp_path, CheckpointError, "needs camera images",
                            policy=lambda env_id, env: policy)  # a factory, held out


def test_state_checkpoint_on_an_image_env_names_the_hidden_entry(tmp_path: Path) -> None:
    from impact_control.errors import CheckpointError

    _refused_before_writing(tmp_path, CheckpointError, "needs observation 'object_pos'",
                            policy=_checkpoint("vanilla"),
                            observation={"obs_mode": "rgb", "image_width": 16,
                                         "image_height": 16})


def test_scripted_expert_on_an_image_env_is_refused_before_writing(tmp_path: Path) -> None:
    from impact_envs.policies.experts import make_expert

    _refused_before_writing(tmp_path, InvalidArgumentError,
                            "needs the observation entries object_pos, object_rot6d, goal_pos",
                            policy=make_expert(HAMMER),
                            observation=ObservationOptions(obs_mode="rgbd", cameras=("side",),
                                                           image_width=16, image_height=16))


def test_camera_checkpoint_fits_the_env_it_was_trained_for() -> None:
    """The positive side of the same check: the methods' RGB observation passes it."""
    import gymnasium as gym

    from impact_eval.api import check_fits_env
    from impact_eval.checkpoints import checkpoint_dir, checkpoint_observation

    observation = checkpoint_observation(checkpoint_dir(HAMMER, "vanilla_rgb"))
    env = gym.make(HAMMER, observation=observation)
    try:
        check_fits_env(_checkpoint("vanilla_rgb"), HAMMER, env)
    finally:
        env.close()


def test_cli_camera_checkpoint_as_a_state_method_exits_2_before_writing(
        tmp_path: Path, capsys, monkeypatch) -> None:
    """A camera checkpoint runs with the cameras its meta.json records, whatever its folder's
    name (``hammer/vanilla`` below: ``vanilla_dp`` observes them); one whose meta.json records
    none (written by hand) is refused through impact-eval in one line, nothing written."""
    import json
    import shutil

    from impact_eval.cli import main
    from impact_eval.methods import CHECKPOINTS_ENV_VAR, checkpoint_dir, resolve_method

    root = tmp_path / "checkpoints"
    shutil.copytree(checkpoint_dir(HAMMER, "vanilla_rgb"), root / "hammer" / "vanilla")
    monkeypatch.setenv(CHECKPOINTS_ENV_VAR, str(root))
    assert resolve_method("vanilla_dp").observation_for(HAMMER).cameras == ("overview", "wrist")
    meta_path = root / "hammer" / "vanilla" / "meta.json"
    meta = json.loads(meta_path.read_text())
    del meta["dataset"]["attrs"]["observation"]
    meta_path.write_text(json.dumps(meta))
    out = tmp_path / "out"
    code = main(["--env", HAMMER, "--method", "vanilla_dp", "--masses", "2.5", "--episodes",
                 "1", "--workers", "1", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "needs camera images" in err[0]
    assert not out.exists()
