"""The full rerun's driver (impact_eval/experiments/rerun_tables.py): which tables it reruns
and with which env id."""

from __future__ import annotations

from impact_eval.experiments.rerun_tables import current_args, is_current


def test_a_retired_env_id_is_rerun_on_its_current_version() -> None:
    args = ["--env", "IMPACT/Hammer-v0", "--method", "impact", "--seed", "0"]
    assert current_args(args) == ["--env", "IMPACT/Hammer-v1", "--method", "impact",
                                  "--seed", "0"]
    assert current_args(["--env", "mod:IMPACT/Dumbbell-v0"])[1] == "mod:IMPACT/Dumbbell-v1"
    assert current_args(["--env", "ImpactTest/Fake-v0"])[1] == "ImpactTest/Fake-v0"


def test_a_table_recorded_on_the_current_version_is_skipped() -> None:
    old = {"sweep_args": ["--env", "IMPACT/Hammer-v0"]}
    assert not is_current(old)
    assert not is_current({**old, "env_version": 0})
    assert is_current({"sweep_args": ["--env", "IMPACT/Hammer-v1"], "env_version": 1})
    assert is_current({"sweep_args": ["--env", "ImpactTest/Fake-v0"]})


def test_version_flips_pairs_episodes_and_counts_outcome_changes() -> None:
    from impact_eval.experiments.version_flips import table_flips

    head = "method,env_id,param_value,episode,success,success_once\n"
    before = head + ("a,IMPACT/Hammer-v0,1,0,True,True\na,IMPACT/Hammer-v0,1,1,False,True\n"
                     "b,IMPACT/Hammer-v0,1,0,True,True\n")
    after = head + ("a,IMPACT/Hammer-v1,1,0,True,True\na,IMPACT/Hammer-v1,1,1,True,True\n"
                    "b,IMPACT/Hammer-v1,2,0,True,True\n")
    r = table_flips(before, after)
    assert (r["rows"], r["missing"], r["flips"]) == (3, 2, 1)
    assert r["methods"] == {"a": (1, 2)}  # b has no episode on both sides
    assert r["cells"] == {("a", "1"): (1, 2, 2)}  # the one cell whose successes moved


def test_an_unknown_table_is_one_line(capsys) -> None:
    import pytest

    from impact_eval.experiments.rerun_tables import main

    with pytest.raises(SystemExit) as info:
        main(["no_such_table"])
    err = capsys.readouterr().err.strip().splitlines()
    assert info.value.code == 2 and len(err) == 1 and "valid: " in err[0] and "main_job" in err[0]


def _git(repo, *args: str) -> None:
    import subprocess

    subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=repo,
                   check=True, capture_output=True)


def _commit_table(repo, version: int, rows: str, cpu: dict) -> None:
    import json

    table = repo / "results" / "t"
    table.mkdir(parents=True, exist_ok=True)
    (table / "episodes.csv").write_text("method,env_id,param_value,episode,success,"
                                        "success_once\n" + rows.replace("VER", str(version)))
    entry = {"sweep_args": ["--env", f"IMPACT/Hammer-v{version}"], "cpu": cpu}
    if version:
        entry["env_version"] = version
    (repo / "results" / "manifest.json").write_text(json.dumps({"tables": {"t": entry}}))
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", f"v{version}")


def test_version_flips_report_names_each_sides_cpu_and_a_bad_rev_is_one_line(
        tmp_path, capsys) -> None:
    import pytest

    from impact_eval.experiments.version_flips import main, report

    _git(tmp_path, "init", "-q")
    rows = "a,IMPACT/Hammer-vVER,1,0,True,True\na,IMPACT/Hammer-vVER,1,1,{},True\n"
    _commit_table(tmp_path, 0, rows.format("False"), {"cpu_model": "Intel", "simd": "avx512"})
    _git(tmp_path, "tag", "before")
    _commit_table(tmp_path, 1, rows.format("True"), {"cpu_model": "AMD EPYC", "simd": "avx2"})
    lines = report(tmp_path / "results", "before").splitlines()
    assert lines[-2] == "| t | 2 | 0 | 1 | a 1->2 | Intel avx512 -> AMD EPYC avx2 |"
    assert lines[-1] == "| all | 2 | 0 | 1 | | |"

    with pytest.raises(SystemExit) as info:
        main(["--before", "no_such_rev", "--results", str(tmp_path / "results")])
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if "error:" in line]  # argparse's usage, then one line
    assert info.value.code == 2 and errors == [err[-1]]
    assert "cannot read results/manifest.json at --before no_such_rev" in err[-1]
