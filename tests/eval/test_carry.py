"""Carried methods (``MethodSpec.carry``, ``impact_eval/chain.py``): a cell's episodes as one
chain, the controller state carried from each into the next, written as the same bytes for any
``--workers``, ``--envs-per-worker``, executor and interruption.

The sweeps run a Hammer env cut to ``SHORT_STEPS`` policy steps per episode, registered here
under its own namespace; workers (processes, Ray) import this module by its dotted name
``eval.test_carry`` (``tests/`` is on their path) and so register it too.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import gymnasium as gym
import pytest
from fixtures.eval_fake import ENV_ID as FAKE_ENV_ID

from impact_control.errors import InvalidArgumentError
from impact_eval.cli import main
from impact_eval.csvio import read_rows
from impact_eval.method_parts import AUTHORS_ROBOT, policy_part
from impact_eval.methods import MethodSpec, register_method, resolve_method
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep import SweepConfig, plan_tasks

BARE_ID = "ImpactCarryTest/Hammer-v1"
ENV_ID = f"eval.test_carry:{BARE_ID}"
SHORT_STEPS = 12
CARRIED, FRESH = "scripted_authors_carry_test", "scripted_authors_fresh_test"


def _hammer_expert(_env_id: str, _env: gym.Env) -> object:
    from impact_envs.policies.experts import make_expert

    return make_expert("IMPACT/Hammer-v1")


if BARE_ID not in gym.registry:
    gym.register(BARE_ID, entry_point="impact_envs.envs.hammer:HammerEnv",
                 max_episode_steps=SHORT_STEPS)
for _name, _carry in ((CARRIED, True), (FRESH, False)):
    register_method(MethodSpec(_name, "impact", _hammer_expert, "scripted, authors_sim (test)",
                               preset="authors_sim", robot=AUTHORS_ROBOT, carry=_carry))


def _args(out: Path, *extra: str) -> list[str]:
    return ["--env", ENV_ID, "--method", f"{CARRIED},{FRESH}", "--masses", "0.5,2.5",
            "--episodes", "3", "--seed", "4", "--out", str(out), *extra]


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sweep run in this process, one env per task: its episodes.csv."""
    out = tmp_path_factory.mktemp("carry") / "reference"
    assert main(_args(out, "--workers", "1", "--envs-per-worker", "1")) == 0
    return out / "episodes.csv"


def _rows(path: Path) -> dict[tuple[str, str, int], dict[str, str]]:
    return {(r["method"], r["param_value"], int(r["episode"])): r for r in read_rows(path)}


def test_episode_0_is_fresh_and_later_episodes_carry(reference: Path) -> None:
    rows = _rows(reference)
    assert len(rows) == 12
    measured = ("energy_j", "peak_torque_nm", "mean_pose_error_m")
    for value in ("0.5", "2.5"):
        first = (rows[(CARRIED, value, 0)], rows[(FRESH, value, 0)])
        assert all(first[0][k] == first[1][k] for k in measured)  # both start fresh
        for episode in (1, 2):  # the carried rate limiter starts from the last command...
            carried, fresh = rows[(CARRIED, value, episode)], rows[(FRESH, value, episode)]
            assert any(carried[k] != fresh[k] for k in measured), (value, episode)


@pytest.mark.parametrize("extra", [
    pytest.param(("--workers", "1", "--envs-per-worker", "2"), id="w1-b2"),
    pytest.param(("--workers", "2", "--envs-per-worker", "2"), id="w2-b2"),
    pytest.param(("--workers", "2", "--envs-per-worker", "1"), id="w2-b1",
                 marks=pytest.mark.slow)])  # 50 s on the loaded 2-core VM
def test_same_bytes_for_any_workers_and_batch(reference: Path, tmp_path: Path,
                                              extra: tuple[str, ...]) -> None:
    assert main(_args(tmp_path / "run", *extra)) == 0
    assert (tmp_path / "run" / "episodes.csv").read_bytes() == reference.read_bytes()


def _interrupted(reference: Path, out: Path, keep: set[int]) -> None:
    """``out`` as a run of the reference interrupted after the rows of episodes ``keep``."""
    out.mkdir()
    for name in ("run.json", "identity.json"):
        shutil.copy(reference.parent / name, out / name)
    lines = reference.read_text().splitlines(keepends=True)
    header = lines[0].rstrip("\n").split(",")
    col = header.index("episode")
    kept = [line for line in lines[1:] if int(line.split(",")[col]) in keep]
    (out / "episodes.csv").write_text(lines[0] + "".join(kept))


@pytest.mark.parametrize("keep", [{0}, {0, 2}], ids=["after-episode-0", "episode-1-missing"])
def test_an_interrupted_run_resumes_to_the_same_bytes(reference: Path, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture,
                                                      keep: set[int]) -> None:
    out = tmp_path / "cut"
    _interrupted(reference, out, keep)
    assert main(_args(out, "--workers", "1", "--envs-per-worker", "2", "--resume")) == 0
    done = 4 * len(keep)
    assert f"{12 - done} episodes run ({done} already done, 12 in total)" in \
        capsys.readouterr().out
    assert (out / "episodes.csv").read_bytes() == reference.read_bytes()


@pytest.mark.slow  # ~35 s; Ray's bytes are checked in test_sweep_ray
def test_the_ray_executor_writes_the_same_bytes(ray_local, reference: Path,
                                                tmp_path: Path) -> None:
    assert main(_args(tmp_path / "ray", "--executor", "ray")) == 0
    assert (tmp_path / "ray" / "episodes.csv").read_bytes() == reference.read_bytes()


def test_run_json_records_the_carry_and_the_robot(reference: Path) -> None:
    run = json.loads((reference.parent / "run.json").read_text())
    settings = run["identity"]["method_controllers"]
    assert settings[CARRIED]["carry"] is True
    assert settings[CARRIED]["robot"]["torque_reading"] == "commanded"
    assert "carry" not in settings[FRESH]  # absent: not carried (older runs' records match)


def test_a_resume_that_changes_the_carry_is_refused(reference: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "cut"
    _interrupted(reference, out, {0})
    identity = json.loads((out / "identity.json").read_text())
    del identity["method_controllers"][CARRIED]["carry"]  # as if it had run uncarried
    (out / "identity.json").write_text(json.dumps(identity))
    before = (out / "episodes.csv").read_bytes()
    assert main(_args(out, "--workers", "1", "--resume")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"cannot resume: method {CARRIED!r}" in err
    assert (out / "episodes.csv").read_bytes() == before


LATER_ROBOT_FIELDS = ("realism", "tau_offset_std_nm", "tau_offset_drift_nm_per_sqrt_s",
                      "model_link_mass_std", "model_com_std_m", "model_inertia_std",
                      "model_seed", "delay_ticks", "command_loss_rate", "encoder_step_rad")
"""The robot fields issue 39 added: a run recorded before them has none of them."""


def test_a_run_recorded_before_the_realism_fields_resumes(reference: Path, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "cut"
    _interrupted(reference, out, {0})
    for name in ("identity.json", "run.json"):
        record = json.loads((out / name).read_text())
        settings = record.get("method_controllers") or record["identity"]["method_controllers"]
        for field in LATER_ROBOT_FIELDS:
            del settings[CARRIED]["robot"][field]
        (out / name).write_text(json.dumps(record))
    assert main(_args(out, "--workers", "1", "--resume")) == 0, capsys.readouterr().err
    assert (out / "episodes.csv").read_bytes() == reference.read_bytes()


def test_a_resume_under_another_realism_is_refused(reference: Path, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "cut"
    _interrupted(reference, out, {0})
    identity = json.loads((out / "identity.json").read_text())
    identity["method_controllers"][CARRIED]["robot"]["realism"] = "fr3"
    (out / "identity.json").write_text(json.dumps(identity))
    assert main(_args(out, "--workers", "1", "--resume")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"cannot resume: method {CARRIED!r}" in err


def _config(methods: tuple[str, ...], episodes: int = 4) -> SweepConfig:
    spec = SweepSpec(env_id=ENV_ID, methods=methods, values=(0.5, 2.5), episodes=episodes,
                     seed=4)
    return SweepConfig(spec, RunOptions(out=Path("unused"), envs_per_worker=2),
                       canonical_env_id=BARE_ID, param_name="object_mass", policy_dt=1 / 30)


def test_a_carried_cell_is_one_task_rerun_from_its_start() -> None:
    tasks = plan_tasks(_config((CARRIED, FRESH)), set())
    carried = [t for t in tasks if t.method == CARRIED]
    assert [t.value for t in carried] == [0.5, 2.5]
    assert [j.episode for j in carried[0].chain] == [j.episode for j in carried[0].jobs] == \
        [0, 1, 2, 3]
    assert all(len(t.jobs) <= 2 and not t.chain for t in tasks if t.method == FRESH)
    done = {(CARRIED, "0.5", 0), (CARRIED, "0.5", 2), (CARRIED, "2.5", 3)}
    by_value = {t.value: t for t in plan_tasks(_config((CARRIED,)), done)}
    assert [j.episode for j in by_value[0.5].chain] == [0, 1, 2, 3]
    assert [j.episode for j in by_value[0.5].jobs] == [1, 3]
    assert [j.episode for j in by_value[2.5].chain] == [0, 1, 2]  # nothing after the last
    assert [j.episode for j in by_value[2.5].jobs] == [0, 1, 2]
    whole = {(CARRIED, v, e) for v in ("0.5", "2.5") for e in range(4)}
    assert plan_tasks(_config((CARRIED,)), whole) == []


def test_the_authors_methods() -> None:
    for name, policy in (("impact_authors", "dp.vanilla"), ("scripted_impact_authors", "scripted")):
        spec = resolve_method(name)
        assert (spec.controller, spec.preset, spec.carry, spec.warm) == \
            ("impact", "authors_sim", True, False)
        assert spec.robot is not None and spec.robot.torque_reading == "commanded"
        assert spec.policy == policy
    hammer = "IMPACT/Hammer-v1"
    assert resolve_method("impact_authors").env_key(hammer) != \
        resolve_method("impact_paper").env_key(hammer)


def test_a_method_env_gets_the_robot_options() -> None:
    from impact_eval.envs import method_env

    env = method_env("IMPACT/Hammer-v1", resolve_method("scripted_impact_authors"))
    try:
        base = env.unwrapped
        assert base.sim.torque_reading == "commanded"
        assert base.controller_preset == "authors_sim"
    finally:
        env.close()


def test_carry_with_warm_is_refused_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="carry and warm exclude each other") as err:
        MethodSpec("both", "impact", policy_part("scripted").build, "both", carry=True,
                   warm=True)
    assert "\n" not in str(err.value)


def test_a_carried_method_on_an_env_that_cannot_carry_is_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from fixtures.eval_fake import FakePolicy

    register_method(MethodSpec("fake_carried_test", "impact", lambda _i, _e: FakePolicy(0.9),
                               "fake, carried", carry=True))
    out = tmp_path / "out"
    assert main(["--env", FAKE_ENV_ID, "--method", "fake_carried_test", "--masses", "1",
                 "--episodes", "2", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot (no carry_controller" in err
    assert not out.exists()
