"""``SweepSpec``: one description of a sweep from the CLI and ``evaluate()`` through the
workers to run.json and back to the arguments that rerun it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fixtures.eval_fake import ENV_ID, FakePolicy

from impact_control.errors import InvalidArgumentError
from impact_eval import evaluate
from impact_eval.cli import main
from impact_eval.reproduce_manifest import sweep_argv
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep_command import _with_defaults, sweep_parser


def _spec_of(argv: list[str]) -> SweepSpec:
    return SweepSpec.from_cli(_with_defaults(sweep_parser().parse_args([*argv, "--out", "x"])))


def test_argv_spec_json_argv_round_trip() -> None:
    argv = ["--env", ENV_ID, "--method", "fake_fast,fake_impact", "--param-values", "0.5,3",
            "--episodes", "3", "--seed", "7", "--controller-set",
            "internal_model.slow_rate_max=1.5", "--robot-set", "realism=fr3"]
    spec = _spec_of(argv)
    assert spec.values == (0.5, 3.0) and spec.methods == ("fake_fast", "fake_impact")
    again = SweepSpec.from_json(json.loads(json.dumps(spec.to_json())))
    assert again == spec
    assert _spec_of(spec.to_argv()) == spec
    bins = _spec_of(["--env", ENV_ID, "--method", "fake_fast", "--mass-bins", "0.5-1.5,1.5-4"])
    assert bins.bin_highs == (1.5, 4.0) and _spec_of(bins.to_argv()) == bins


@pytest.mark.parametrize(("fields", "named"), [
    ({"methods": ()}, "malformed --method ''"),
    ({"methods": ("a", "a")}, "repeated method"),
    ({"episodes": 0}, "--episodes must be >= 1, got 0"),
    ({"seed": -1}, "--seed must be >= 0"),
    ({"values": ()}, "no parameter values"),
    ({"values": (1.0, 1.0)}, "duplicate values"),
    ({"values": (float("nan"),)}, "must be finite"),
    ({"values": (2.0,), "bin_highs": (1.0,)}, "reversed or empty"),
    ({"values": (1.0, 2.0), "bin_highs": (3.0,)}, "2 bin lower edges but 1 upper"),
    ({"controller_overrides": ("limits.torque_rate_max_nm_per_s=2000",)},
     "--beyond-hardware-limits"),
    ({"robot_overrides": ("realism=perfect",)}, "realism"),
])
def test_a_bad_spec_is_one_line(fields: dict, named: str) -> None:
    base = {"env_id": ENV_ID, "methods": ("fake_fast",), "values": (1.0,)}
    with pytest.raises(InvalidArgumentError) as info:
        SweepSpec(**{**base, **fields})
    assert "\n" not in str(info.value) and named in str(info.value)


@pytest.mark.parametrize(("fields", "named"), [
    ({"workers": 0}, "--workers must be >= 1"),
    ({"envs_per_worker": 0}, "--envs-per-worker must be >= 1"),
    ({"video_episodes": -1}, "--video must be >= 0"),
    ({"executor": "slurm"}, "slurm"),
])
def test_bad_run_options_are_one_line(fields: dict, named: str) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        RunOptions(out=Path("x"), **fields)
    assert "\n" not in str(info.value) and named in str(info.value)


def test_cli_and_evaluate_record_the_same_spec(tmp_path: Path) -> None:
    cli, api = tmp_path / "cli", tmp_path / "api"
    assert main(["--env", ENV_ID, "--method", "fake_fast", "--masses", "0.5,3", "--episodes",
                 "2", "--workers", "1", "--envs-per-worker", "2", "--out", str(cli)]) == 0
    evaluate(FakePolicy(0.9), ENV_ID, [0.5, 3], api, episodes=2, name="mine",
             envs_per_worker=2)
    recorded = json.loads((api / "run.json").read_text())
    assert recorded["identity"]["spec_format"] == 2 and "spec" not in recorded
    spec = SweepSpec.from_json(recorded["identity"]["spec"])
    assert spec == SweepSpec(env_id=ENV_ID, methods=("mine",), values=(0.5, 3.0), episodes=2)
    assert sweep_argv(recorded) == spec.to_argv()
    assert recorded["run_options"]["envs_per_worker"] == 2
    from_cli = SweepSpec.from_json(json.loads((cli / "run.json").read_text())["identity"]["spec"])
    assert from_cli == SweepSpec.from_json({**spec.to_json(), "methods": ["fake_fast"]})
