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
