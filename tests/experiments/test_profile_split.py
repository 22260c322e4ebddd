"""``impact_experiments.profile_split``: py-spy samples of a sweep, counted per part."""

from __future__ import annotations

from pathlib import Path

import pytest

from impact_experiments.profile_split import count_samples, main, part_of

WORKER = "BaseProcess.run (multiprocessing/process.py:108);_worker_main (impact_eval/sweep.py:76)"
ROLL = WORKER + ";LockstepBatch.run (impact_eval/rollout.py:140)"
STEP = ROLL + ";ImpactEnv.step (impact_envs/envs/base.py:287)"
PIXELS = "impact_envs/envs/pixels.py:130"
RAW = "\n".join([
    f"{STEP};ImpactEnv._observation (x.py:1);PixelObservations.render ({PIXELS}) 30",
    f"{ROLL};DiffusionPolicy.act (impact_envs/policies/diffusion/policy.py:173) 50",
    f"{STEP};ClosedLoop.run (c.py:145);FrankaSim.step (impact_envs/robot/sim.py:389) 15",
    f"{STEP};ClosedLoop.run (impact_envs/loop/closed_loop.py:142) 5",
    "Thread.run (threading.py:982);Queue._feed (multiprocessing/queues.py:231) 400",
    "main (impact_eval/__main__.py:5);wait (impact_eval/sweep.py:120) 99",
]) + "\n"


def test_each_worker_sample_counts_for_one_part_and_other_threads_for_none(tmp_path: Path) -> None:
    (tmp_path / "a.txt").write_text(RAW)
    (tmp_path / "b.txt").write_text(RAW)
    counts = count_samples([tmp_path / "a.txt", tmp_path / "b.txt"])
    assert counts == {"rendering": 60, "policy": 100, "physics (mj_step)": 30,
                      "controller, env and the rest": 10}


@pytest.mark.parametrize("stack, part", [
    (f"{ROLL};act (impact_envs/policies/diffusion/policy.py:173)", "policy"),  # older py-spy
    (f"{ROLL};PickPlaceExpert.act (impact_envs/policies/experts.py:9)", "policy"),
    (f"{STEP};render ({PIXELS})", "rendering"),
    # an act that is not the rollout's
    (f"{STEP};Other.act (impact_envs/policies/experts.py:1)", "controller, env and the rest"),
    (f"{STEP};FrankaSim.step_gripper (impact_envs/robot/sim.py:4)", "controller, env and the rest"),
])
def test_parts_are_matched_by_function_and_file(stack: str, part: str) -> None:
    assert part_of(stack) == part


def test_the_command_prints_seconds_per_episode(tmp_path: Path, capsys) -> None:
    (tmp_path / "a.txt").write_text(RAW)
    assert main([str(tmp_path / "a.txt"), "--episodes", "20", "--wall-s", "100"]) == 0
    out = capsys.readouterr().out  # 100 s x 2 workers / 20 episodes = 10 s per episode
    assert "| policy | 50 | 50.0% | 5.00 |" in out and "| all | 100 | 100% | 10.00 |" in out


@pytest.mark.parametrize("text, extra, needle", [
    ("", [], "no sample of a sweep worker"),
    (None, [], "no such file"),
    (f"{STEP};ClosedLoop.run (c.py:1) 7\n", [], "no sample matched a named part"),
    (RAW, ["--workers", "0"], "--workers 0: valid: a number above 0"),
])
def test_bad_input_is_one_line(tmp_path: Path, capsys, text, extra, needle) -> None:
    path = tmp_path / "a.txt"
    if text is not None:
        path.write_text(text)
    with pytest.raises(SystemExit) as exc:
        main([str(path), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and needle in err[-1]
