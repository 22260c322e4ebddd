"""impact-eval end to end on the fake env: outputs, determinism, report, bad input."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pandas as pd
import pytest
from fixtures.eval_fake import run_cli, sweep_args

from impact_control.errors import InvalidArgumentError
from impact_eval.cli import main

PLOTS = [
    "success_heatmap",
    "success_surface",
    "success_vs_object_mass",
    "energy_vs_object_mass",
    "safety_vs_object_mass",
]


def test_sweep_writes_csvs_run_json_and_plots(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    # mass 77: every episode raises; the sweep completes, writes everything and exits 1
    assert main(sweep_args(out, "--workers", "1", masses="0.5,2,66,77,88")) == 1
    err = capsys.readouterr().err.splitlines()[-1]  # after the progress bar
    assert err.startswith("impact-eval: error: every episode raised in 3 cell(s)")
    assert "fake_fast @ 77: exception: RuntimeError" in err
    episodes = pd.read_csv(out / "episodes.csv", keep_default_na=False)
    assert len(episodes) == 3 * 5 * 5
    assert set(episodes["env_id"]) == {"ImpactTest/Fake-v0"}
    reasons = set(episodes["failure_reason"])
    assert {
        "unstable: qacc diverged at t=0.1 s",
        "exception: RuntimeError",
        "timeout",
        "unstable: non-finite observation",
        "",
    } <= reasons
    assert (episodes.loc[episodes["method"] == "fake_slow", "success"] == 0).all()
    summary = pd.read_csv(out / "summary.csv")
    assert len(summary) == 3 * 5 and (summary["n"] == 5).all()
    assert (summary["ci_low"] <= summary["success_rate"]).all()
    assert (summary["success_rate"] <= summary["ci_high"]).all()
    run = json.loads((out / "run.json").read_text())
    assert run["env"]["policy_dt_s"] == pytest.approx(1 / 30)
    assert run["env"]["control_dt_s"] == 0.001
    assert run["env"]["spec"]["id"] == "ImpactTest/Fake-v0"
    assert {"numpy", "gymnasium", "mujoco", "torch"} <= set(run["versions"])
    assert "sha" in run["git"] and run["invocations"][-1]["status"] == "complete"
    for stem in PLOTS:
        for ext in ("png", "pdf"):
            assert (out / "plots" / f"{stem}.{ext}").stat().st_size > 1000


def test_same_arguments_give_identical_episodes_csv(tmp_path: Path) -> None:
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    assert main(sweep_args(a, "--workers", "2")) == 0
    assert main(sweep_args(b, "--workers", "2")) == 0
    assert main(sweep_args(c, "--workers", "1")) == 0
    text = (a / "episodes.csv").read_text()
    assert text == (b / "episodes.csv").read_text() == (c / "episodes.csv").read_text()
    assert "wall" not in text.splitlines()[0]


def test_resume_completes_a_partial_csv(tmp_path: Path) -> None:
    full, part = tmp_path / "full", tmp_path / "part"
    assert main(sweep_args(full, "--workers", "1")) == 0
    lines = (full / "episodes.csv").read_text().splitlines(keepends=True)
    part.mkdir()
    (part / "episodes.csv").write_text("".join(lines[:20]) + lines[20][:15])  # torn row
    assert main(sweep_args(part, "--workers", "2")) == 2  # no --resume: refused
    assert main(sweep_args(part, "--workers", "2", "--resume")) == 2  # rows, no identity
    (part / "identity.json").write_text((full / "identity.json").read_text())
    assert main(sweep_args(part, "--workers", "2", "--resume")) == 0
    assert (part / "episodes.csv").read_text() == (full / "episodes.csv").read_text()
    assert main(sweep_args(part, "--workers", "2", "--resume", "--seed", "12")) == 2


def test_report_redraws_from_csv(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert main(sweep_args(out, "--workers", "1")) == 0
    summary = (out / "summary.csv").read_text()
    (out / "summary.csv").unlink()
    for png in (out / "plots").iterdir():
        png.unlink()
    proc = run_cli("report", str(out))
    assert proc.returncode == 0, proc.stderr
    assert (out / "summary.csv").read_text() == summary
    assert sorted(p.name for p in (out / "plots").iterdir()) == sorted(
        f"{s}.{e}" for s in PLOTS for e in ("png", "pdf")
    )


def test_bad_input_in_a_real_process(tmp_path: Path) -> None:
    proc = run_cli(*sweep_args(tmp_path / "out", "--method", "nope"))
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "valid choices" in proc.stderr
    assert proc.stdout == "" and not (tmp_path / "out").exists()


def test_missing_sweep_options_name_quick(capsys):
    from impact_eval.cli import main

    assert main(["--env", "IMPACT/Hammer-v1", "--out", "/tmp/impact-never-written"]) == 2
    err = capsys.readouterr().err.strip()
    assert "missing --method, --masses/--param-values" in err and "--quick" in err
    assert "\n" not in err


def test_quick_fills_defaults_and_explicit_options_win():
    from impact_eval.sweep_command import _with_defaults, sweep_parser

    args = _with_defaults(sweep_parser().parse_args(["--quick", "--episodes", "2"]))
    assert args.env == "IMPACT/Hammer-v2" and args.grid == "0.2,2.5,5,7.5,10"
    assert args.episodes == 2 and str(args.out) == "results/quickstart"
    assert args.method in ("scripted,scripted_impact,scripted_impact_paper",
                           "vanilla_dp,augmented_dp,impact,impact_paper")


def test_param_selects_a_declared_secondary_parameter(tmp_path):
    from impact_eval.envs import check_param, describe_env, make_env

    env = make_env("IMPACT/Calligraphy-v1", "impedance")
    info = describe_env(env, "surface_friction")
    assert info.param_name == "surface_friction"
    assert info.param_names == ("tool_mass", "surface_friction")
    check_param(info, "surface_friction")
    _, reset_info = env.reset(seed=0, options={"surface_friction": 0.8})
    assert reset_info["surface_friction"] == 0.8
    with pytest.raises(InvalidArgumentError, match="valid choices: tool_mass, surface_friction"):
        check_param(info, "gravity")
    env.close()


def _threads_in_worker(queue) -> None:  # module level: picklable for the worker
    from impact_envs.parallel import THREAD_ENV, single_threaded_torch

    single_threaded_torch()
    import torch

    queue.put((torch.get_num_threads(), [os.environ.get(k) for k in THREAD_ENV]))


def test_sweep_workers_are_single_threaded() -> None:
    from impact_envs.parallel import THREAD_ENV, single_threaded_children
    from impact_eval.sweep import _context

    before = {k: os.environ.get(k) for k in THREAD_ENV}
    ctx = _context()
    queue = ctx.Queue()
    proc = ctx.Process(target=_threads_in_worker, args=(queue,))
    with single_threaded_children():
        proc.start()
    torch_threads, env = queue.get(timeout=60)
    proc.join(timeout=10)
    assert torch_threads == 1
    assert env == ["1"] * len(THREAD_ENV)  # OpenMP, OpenBLAS, MKL: read when they load
    assert {k: os.environ.get(k) for k in THREAD_ENV} == before  # parent's env restored


def test_beyond_hardware_limits_flag_allows_and_records_it(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["--env", "IMPACT/Hammer-v1", "--method", "scripted", "--masses", "0.2",
            "--episodes", "1", "--workers", "1", "--out", str(out),
            "--controller-set", "limits.torque_rate_max_nm_per_s=2000"]
    assert main(args) == 2  # refused without the flag, nothing written
    assert not out.exists()
    assert main([*args, "--beyond-hardware-limits"]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["identity"]["spec"]["beyond_hardware_limits"] is True
    assert run["identity"]["spec"]["controller_overrides"] == [
        "limits.torque_rate_max_nm_per_s=2000"]
