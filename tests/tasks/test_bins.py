"""Mass bins (``impact-eval --mass-bins``, ``evaluate(values=[(lo, hi), ...])``): parsing, the
per-episode draw, the rows, resume and ``--extend``, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from fixtures.eval_fake import ENV_ID, FakePolicy

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.bins import MassBin, draw_in_bin, format_bins, parse_bins
from impact_eval.api import evaluate
from impact_eval.cli import main
from impact_eval.grid import episode_seed

AUTHORS_BINS = "0.1-0.3,0.3-0.5,0.5-1,1-2,2-4,4-6,6-8,8-10"


def _args(out: Path, bins: str, *extra: str) -> list[str]:
    return ["--env", ENV_ID, "--method", "fake_fast,fake_slow", "--mass-bins", bins,
            "--episodes", "5", "--envs-per-worker", "2", "--seed", "11", "--workers", "1",
            "--out", str(out), *extra]


def _exit_code(argv: list[str]) -> int:
    """``main``'s exit status, whether argparse exits (2) or the sweep refuses (returns 2)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


def test_parse_the_authors_bins_and_read_back_their_text() -> None:
    bins = parse_bins(AUTHORS_BINS)
    assert bins[0] == MassBin(0.1, 0.3) and bins[-1] == MassBin(8.0, 10.0) and len(bins) == 8
    assert parse_bins(format_bins(bins)) == bins
    assert bins[2].label == "0.5–1"


@pytest.mark.parametrize("spec, message", [
    ("", "empty item"),
    ("0.1-0.3,", "empty item"),
    ("0.3-0.1", "reversed or empty"),
    ("0.3-0.3", "reversed or empty"),
    ("0.1-0.5,0.3-0.6", "overlaps or precedes"),
    ("1-2,0.1-0.3", "overlaps or precedes"),
    ("0.1:0.3", "is not LO-HI"),
    ("0.1-0.3-0.5", "is not LO-HI"),
    ("a-1", "is not a number"),
    ("0.1-inf", "is not finite"),
])
def test_bad_bins_are_one_line(spec: str, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message) as err:
        parse_bins(spec)
    assert "\n" not in str(err.value) and "e.g. 0.1-0.3,0.3-0.5" in str(err.value)


def test_each_bins_50_reference_draws_lie_in_it_and_span_80_percent() -> None:
    """The acceptance of issue 38: a seeded episode's mass lies in its bin, and the 50
    episodes of a bin (reference seed 0, the table's seeds) span >= 80 % of its width."""
    for vi, b in enumerate(parse_bins(AUTHORS_BINS)):
        masses = np.array([draw_in_bin(b.lo, b.hi, episode_seed(0, vi, e)) for e in range(50)])
        assert np.all((masses >= b.lo) & (masses < b.hi))
        assert np.ptp(masses) >= 0.8 * (b.hi - b.lo), b.label


def test_the_draw_is_a_fixed_function_of_the_seed_and_never_the_upper_edge() -> None:
    assert draw_in_bin(2.0, 4.0, 123) == draw_in_bin(2.0, 4.0, 123)
    assert draw_in_bin(2.0, 4.0, 123) != draw_in_bin(2.0, 4.0, 124)
    assert draw_in_bin(1.0, 1.0 + 1e-15, 5) < 1.0 + 1e-15


def test_rows_name_the_bin_draw_in_it_and_pair_the_methods(tmp_path: Path) -> None:
    assert main(_args(tmp_path / "run", "0.5-1.5,1.5-4")) == 0
    rows = pd.read_csv(tmp_path / "run" / "episodes.csv")
    assert set(rows["param_name"]) == {"object_mass_bin"}
    assert sorted(set(rows["param_value"])) == [0.5, 1.5]
    for lo, hi in ((0.5, 1.5), (1.5, 4.0)):
        cell = rows[rows["param_value"] == lo]
        assert cell["drawn_mass_kg"].between(lo, hi, inclusive="left").all()
    by_method = {m: g.sort_values(["param_value", "episode"]) for m, g in rows.groupby("method")}
    np.testing.assert_array_equal(by_method["fake_fast"]["drawn_mass_kg"],
                                  by_method["fake_slow"]["drawn_mass_kg"])  # paired
    summary = pd.read_csv(tmp_path / "run" / "summary.csv")
    assert len(summary) == 4 and set(summary["n"]) == {5}


def test_resume_and_extend_keep_the_rows(tmp_path: Path, capsys) -> None:
    whole, grown = tmp_path / "whole", tmp_path / "grown"
    assert main(_args(whole, "0.5-1.5,1.5-4")) == 0
    assert main(_args(grown, "0.5-1.5")) == 0
    assert main(_args(grown, "0.5-1.5,1.5-4", "--extend")) == 0
    key = ["method", "param_value", "episode"]
    a = pd.read_csv(whole / "episodes.csv").sort_values(key).reset_index(drop=True)
    b = pd.read_csv(grown / "episodes.csv").sort_values(key).reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b)
    assert main(_args(grown, "0.5-1.5,1.5-4", "--resume")) == 0
    assert "(20 already done, 20 in total)" in capsys.readouterr().out
    assert main(_args(grown, "0.5-1.5,1.5-3", "--resume")) == 2
    assert "cannot resume: bin_highs was [1.5, 4.0]" in capsys.readouterr().err


@pytest.mark.parametrize("extra, message", [
    (("--masses", "1,2"), "not allowed with argument --mass-bins"),
    (("--mass-bins", "0.5-1.5,1-2"), "overlaps"),
])
def test_bad_bin_requests_are_one_line_and_write_nothing(tmp_path: Path, capsys, extra,
                                                         message) -> None:
    args = _args(tmp_path / "out", "0.5-1.5")
    if extra[0] == "--mass-bins":
        args[args.index("--mass-bins") + 1] = extra[1]
    else:
        args += list(extra)
    code = _exit_code(args)
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.strip().count("\n") <= 1
    assert not (tmp_path / "out").exists()


def test_a_bin_beyond_the_tasks_range_is_one_line(tmp_path: Path, capsys) -> None:
    """Both edges are probed: the Hammer task takes masses up to 12 kg."""
    code = _exit_code(["--env", "IMPACT/Hammer-v1", "--method", "scripted", "--mass-bins",
                       "8-14", "--episodes", "1", "--workers", "1",
                       "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "object_mass=14.0 rejected" in err
    assert err.strip().count("\n") == 0 and not (tmp_path / "out").exists()


def test_evaluate_takes_bins_as_pairs(tmp_path: Path) -> None:
    rows = evaluate(lambda _id, _env: FakePolicy(0.9), ENV_ID, [(0.5, 1.5), (1.5, 4.0)],
                    tmp_path / "api", episodes=3, controller="impedance", seed=11)
    assert set(rows["param_name"]) == {"object_mass_bin"} and len(rows) == 6
    with pytest.raises(InvalidArgumentError, match="valid: \\(lo, hi\\) pairs"):
        evaluate(lambda _id, _env: FakePolicy(0.9), ENV_ID, [(0.5, 1.5, 2.0)], tmp_path / "x")


def test_reproduce_reruns_a_bin_table_from_its_recorded_bins(tmp_path: Path) -> None:
    """``reproduce`` rebuilds the sweep's arguments from run.json: the bins, not a grid."""
    import json

    from impact_eval.reproduce_manifest import sweep_argv

    assert main(_args(tmp_path / "run", "0.5-1.5,1.5-4")) == 0
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    argv = sweep_argv(run)
    assert argv[argv.index("--mass-bins") + 1] == "0.5-1.5,1.5-4.0"  # the spec's own text
    spec = run["identity"]["spec"]
    assert "--param-values" not in argv and spec["bin_highs"] == [1.5, 4.0]
    flat = {"env": spec["env_id"], "methods": spec["methods"], "values": spec["values"],
            "bin_highs": spec["bin_highs"], "episodes": spec["episodes"], "seed": spec["seed"]}
    assert sweep_argv({"args": flat}) == argv  # a run.json from before the spec (run_migration)
    assert main([*argv, "--workers", "1", "--envs-per-worker", "2",
                 "--out", str(tmp_path / "again")]) == 0
    assert ((tmp_path / "again" / "episodes.csv").read_bytes()
            == (tmp_path / "run" / "episodes.csv").read_bytes())


# --- issue 53: a bin draws the env's mass only; bin text is quoted as typed ---------------


def test_every_task_bins_the_one_mass_both_tools_draw() -> None:
    """For every built-in task and each of its parameters, a bin is accepted exactly on the
    mass the LeRobot plugin's ``mass_bin`` draws (``mass_param``) and ``drawn_mass_kg``
    records; any other parameter is refused naming its own unit, never kg for newtons."""
    from impact_envs import ENV_IDS
    from impact_envs.tasks.bins import check_bin_param, mass_param_name
    from impact_envs.tasks.registry import task_class
    from impact_lerobot.settings import mass_param

    for env_id in ENV_IDS:
        task = task_class(env_id)
        mass = mass_param(task).name
        assert mass_param_name(task.params) == mass
        for p in task.params:
            if p.name == mass:
                check_bin_param(env_id, p.name, task.params)
                continue
            with pytest.raises(InvalidArgumentError) as err:
                check_bin_param(env_id, p.name, task.params)
            text = str(err.value)
            assert "\n" not in text and f"--param {mass} with --mass-bins" in text
            assert f"not {p.name} ({'in ' + p.unit if p.unit else 'without a unit'}" in text


@pytest.mark.parametrize("extra, named", [
    ((), "not disturbance_n (in N)"),  # the push in newtons
    (("--param", "added_mass"), "not added_mass (in kg, not the mass drawn_mass_kg records)"),
    (("--param", "disturbance_n", "--mass-bins", "0-1"), "not disturbance_n (in N)"),
])
def test_a_bin_of_the_push_or_another_mass_is_one_line_and_writes_nothing(
        tmp_path: Path, capsys, extra: tuple[str, ...], named: str) -> None:
    argv = ["--env", "IMPACT/Disturbance-v1", "--method", "scripted_impact", "--mass-bins",
            "10-30", "--episodes", "1", "--workers", "1", "--out", str(tmp_path / "out")]
    if "--mass-bins" in extra:
        argv[argv.index("--mass-bins") + 1] = extra[-1]
        extra = extra[:2]
    assert _exit_code([*argv, *extra]) == 2
    err = capsys.readouterr().err
    assert named in err and "--param object_mass with --mass-bins" in err
    assert err.strip().count("\n") == 0 and not (tmp_path / "out").exists()


def test_calligraphy_friction_bins_are_refused_in_the_api_too(tmp_path: Path) -> None:
    with pytest.raises(InvalidArgumentError, match="not surface_friction \\(without a unit\\)"):
        evaluate(lambda _id, _env: FakePolicy(0.9), "IMPACT/Calligraphy-v1", [(0.1, 0.3)],
                 tmp_path / "api",
                 episodes=1, param="surface_friction")
    assert not (tmp_path / "api").exists()


@pytest.mark.parametrize("text, edges", [
    ("0.00001-5", ((1e-05, 5.0),)),  # the case
    ("0.1-0.3,0.3-0.0000005", None),  # reversed: its own text, not 5e-07
    ("0.00002-0.5,0.3-4", None),  # overlapping: both items as typed
    ("1e-5-5", None),  # an exponent's minus: not LO-HI, with the fixed-point hint
])
def test_bin_text_round_trips_and_errors_quote_it_as_typed(text: str, edges) -> None:
    from impact_eval.spec import SweepSpec, values_from_text

    if edges is None:
        with pytest.raises(InvalidArgumentError) as err:
            values_from_text(None, text)
        message = str(err.value)
        assert f"--mass-bins {text!r}" in message and "e-0" not in message
        assert "\n" not in message
        if text.startswith("1e"):
            assert "fixed point, e.g. 0.00001" in message
        return
    values, highs = values_from_text(None, text)
    assert tuple(zip(values, highs, strict=True)) == edges
    spec = SweepSpec("IMPACT/Hammer-v1", ("scripted",), values, highs)
    again = spec.to_argv()[spec.to_argv().index("--mass-bins") + 1]
    assert again == "0.00001-5.0" and parse_bins(again) == spec.bins  # reproduce reruns it
    from impact_eval.api import grid_or_bins

    assert grid_or_bins([(0.00001, 5)]) == (None, "0.00001-5.0")


@pytest.mark.parametrize("args", [["--mass-bins", "0.00001-5"], ["--masses", "0.00002,5"]])
def test_a_value_the_env_refuses_is_named_as_typed_not_as_a_float_repr(
        args: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from impact_eval.cli import main

    code = main(["--env", "IMPACT/Hammer-v1", "--method", "scripted", *args, "--episodes", "1",
                 "--out", str(tmp_path / "out")])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert "out of range" in err and "e-05" not in err and "\n" not in err
    assert "=0.0000" in err and not (tmp_path / "out").exists()
