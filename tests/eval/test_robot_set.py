"""``impact-eval --robot-set FIELD=VALUE`` and ``evaluate(robot_set=...)``: the robot every
method's env gets, recorded in run.json, checked on resume, refused in one line when bad."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from fixtures.eval_fake import ENV_ID, FakePolicy

from impact_control.errors import InvalidArgumentError
from impact_eval.api import evaluate
from impact_eval.cli import main
from impact_eval.reproduce_manifest import sweep_argv


def _args(out: Path, *extra: str) -> list[str]:
    return ["--env", ENV_ID, "--method", "fake_fast", "--masses", "0.5,2", "--episodes", "2",
            "--envs-per-worker", "2", "--workers", "1", "--out", str(out), *extra]


def _exit_code(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


def test_the_robot_reaches_every_row_and_run_json(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    assert main(_args(out, "--robot-set", "realism=fr3", "--robot-set", "delay_ticks=0")) == 0
    rows = pd.read_csv(out / "episodes.csv")
    assert set(rows["robot_profile"]) == {"fr3"} and len(rows) == 4
    run = json.loads((out / "run.json").read_text())
    assert run["identity"]["spec"]["robot_overrides"] == ["realism=fr3", "delay_ticks=0"]
    assert sweep_argv(run)[-4:] == ["--robot-set", "realism=fr3", "--robot-set",
                                     "delay_ticks=0"]  # what reproduce reruns
    assert main(_args(out, "--robot-set", "realism=fr3", "--robot-set", "delay_ticks=0",
                      "--resume")) == 0
    capsys.readouterr()
    assert _exit_code(_args(out, "--robot-set", "realism=fr3", "--resume")) == 2
    assert "cannot resume: robot_overrides was ['realism=fr3', 'delay_ticks=0']" in \
        capsys.readouterr().err


def test_a_run_from_before_the_option_resumes_only_on_the_ideal_robot(tmp_path: Path,
                                                                    capsys) -> None:
    out = tmp_path / "old"
    assert main(_args(out)) == 0
    identity = out / "identity.json"
    recorded = json.loads(identity.read_text())
    spec = recorded["spec"]  # the flat layout written before --robot-set existed
    flat = {"env": spec["env_id"], "seed": spec["seed"], "param_name": recorded["param_name"],
            "controller_overrides": [], "methods": spec["methods"], "values": spec["values"],
            "episodes": spec["episodes"], "method_controllers": recorded["method_controllers"],
            "bin_highs": [], "policy_fingerprints": recorded["policy_fingerprints"]}
    identity.write_text(json.dumps(flat))
    assert main(_args(out, "--resume")) == 0
    capsys.readouterr()
    assert _exit_code(_args(out, "--robot-set", "realism=fr3", "--resume")) == 2
    assert "cannot resume: robot_overrides was []" in capsys.readouterr().err


@pytest.mark.parametrize(("setting", "message"), [
    ("realism=real", "invalid realism 'real'; valid choices: ideal, fr3"),
    ("delay=1", "invalid --robot-set 'delay=1'; valid: FIELD=VALUE with FIELD one of"),
    ("delay_ticks=3", "invalid delay_ticks 3; valid: an integer from 0 to 1"),
    ("sensor_noise=yes", "invalid --robot-set sensor_noise='yes'; valid: true or false"),
])
def test_a_bad_robot_setting_is_one_line_and_writes_nothing(tmp_path: Path, capsys, setting,
                                                            message) -> None:
    assert _exit_code(_args(tmp_path / "out", "--robot-set", setting)) == 2
    err = capsys.readouterr().err
    assert message in err and err.strip().count("\n") == 0
    assert not (tmp_path / "out").exists()


def test_evaluate_takes_the_same_settings(tmp_path: Path) -> None:
    rows = evaluate(lambda _id, _env: FakePolicy(0.9), ENV_ID, [0.5], tmp_path / "api",
                    episodes=2, controller="impedance", robot_set=["realism=fr3"])
    assert set(rows["robot_profile"]) == {"fr3"}
    with pytest.raises(InvalidArgumentError, match="valid: a list of 'FIELD=VALUE' strings"):
        evaluate(lambda _id, _env: FakePolicy(0.9), ENV_ID, [0.5], tmp_path / "x",
                 robot_set="realism=fr3")


# --- issue 53: an override may not undo a method's own flag -----------------------------


@pytest.mark.parametrize(("method", "setting"), [
    ("scripted_impact_authors", "torque_reading=link_side"),  # the case
    ("impact_authors", "torque_reading=link_side"),
    ("scripted+impact@paper+commanded", "torque_reading=link_side"),  # composed (variation)
])
def test_a_robot_set_that_undoes_a_flag_is_refused_naming_both(tmp_path: Path, capsys,
                                                              method: str,
                                                              setting: str) -> None:
    argv = _args(tmp_path / "out", "--robot-set", "realism=fr3", "--robot-set", setting)
    argv[argv.index("--method") + 1] = f"fake_fast,{method}"
    assert _exit_code(argv) == 2
    err = capsys.readouterr().err
    assert f"--robot-set {setting!r} contradicts method {method!r}'s +commanded" in err
    assert "torque_reading='commanded'" in err and err.strip().count("\n") == 0
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("settings", [
    ("torque_reading=commanded",),  # the flag's own value
    ("realism=fr3", "delay_ticks=0"),  # other fields (the realism tables)
    ("torque_reading=link_side", "torque_reading=commanded"),  # the last one wins: the flag's
])
def test_overrides_that_keep_the_flags_pass(settings: tuple[str, ...]) -> None:
    from impact_eval.methods import check_overrides_keep_flags, resolve_method

    for name in ("impact_authors", "scripted_impact_authors", "scripted_impact", "impact_warm"):
        check_overrides_keep_flags(resolve_method(name), settings)
    # a method without the flag may take any reading: it has none to undo
    check_overrides_keep_flags(resolve_method("scripted_impact"), ("torque_reading=link_side",))


def test_a_controller_set_on_the_authors_method_still_runs_and_is_recorded() -> None:
    """docs/results.md §5's nullspace override on ``impact_authors``: checked, accepted."""
    from impact_eval.spec import SweepSpec

    spec = SweepSpec("IMPACT/Hammer-v1", ("impact_authors",), (0.5,),
                     controller_overrides=("impedance.nullspace_stiffness_nm_per_rad=10",))
    assert spec.to_argv()[-2:] == ["--controller-set",
                                   "impedance.nullspace_stiffness_nm_per_rad=10"]
