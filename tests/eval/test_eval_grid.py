"""impact-eval grid parsing, paired seeds and task planning."""

from __future__ import annotations

from pathlib import Path

import pytest

from impact_control.errors import InvalidArgumentError
from impact_eval.grid import episode_seed, format_value, parse_grid
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep import SweepConfig, plan_tasks


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ("0.1:0.3:0.1", [0.1, 0.2, 0.3]),
        ("0:1:0.1", [round(0.1 * i, 10) for i in range(11)]),
        ("1:1:0.5", [1.0]),
        ("0.1:1.2:0.5", [0.1, 0.6, 1.1]),
        ("0.2, 1,5", [0.2, 1.0, 5.0]),
        ("3", [3.0]),
        (" 8,0.1 ", [8.0, 0.1]),
    ],
)
def test_parse_grid(spec: str, expected: list[float]) -> None:
    assert parse_grid(spec) == expected


def test_paper_mass_grid_has_exact_values() -> None:
    values = parse_grid("0.1:10:0.5")
    assert len(values) == 20
    assert values[0] == 0.1 and values[-1] == 9.6
    assert [format_value(v) for v in values[:4]] == ["0.1", "0.6", "1.1", "1.6"]
    assert parse_grid("0:10:0.5")[-1] == 10.0


@pytest.mark.parametrize(
    "spec",
    [
        "",
        "  ",
        "1:2",
        "1:2:3:4",
        "1:2:0",
        "1:2:-0.5",
        "2:1:0.5",
        "a,b",
        "1,,2",
        "1:2:x",
        "nan",
        "inf,1",
        "1,1",
        "0:1:1e-9",
        "1:2,3",
        "0.1:10:0.5:",
    ],
)
def test_malformed_grid_is_one_line_error(spec: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        parse_grid(spec)
    assert "\n" not in str(err.value)
    assert "grid" in str(err.value)


def test_episode_seed_is_deterministic_and_distinct() -> None:
    seeds = {episode_seed(7, v, e) for v in range(20) for e in range(50)}
    assert len(seeds) == 1000
    assert episode_seed(7, 3, 4) == episode_seed(7, 3, 4)
    assert episode_seed(7, 3, 4) != episode_seed(8, 3, 4)
    assert all(0 <= s < 2**31 for s in seeds)
    with pytest.raises(InvalidArgumentError):
        episode_seed(-1, 0, 0)


def _config() -> SweepConfig:
    spec = SweepSpec(env_id="x:Ns/E-v0", methods=("a", "b", "c"), values=(0.5, 1.0, 2.0),
                     episodes=5, seed=3)
    return SweepConfig(spec, RunOptions(out=Path("unused"), envs_per_worker=2),
                       canonical_env_id="Ns/E-v0", param_name="object_mass", policy_dt=1 / 30)


def test_seeds_are_paired_across_methods() -> None:
    cfg = _config()
    seeds: dict[tuple[float, int], set[int]] = {}
    methods: dict[tuple[float, int], set[str]] = {}
    for task in plan_tasks(cfg, set()):
        assert 1 <= len(task.jobs) <= cfg.options.envs_per_worker
        for job in task.jobs:
            seeds.setdefault((job.value, job.episode), set()).add(job.seed)
            methods.setdefault((job.value, job.episode), set()).add(task.method)
    assert len(seeds) == 3 * 5
    assert all(len(s) == 1 for s in seeds.values()), "a cell got different seeds per method"
    assert all(m == {"a", "b", "c"} for m in methods.values())


def test_plan_skips_done_cells_and_is_value_major() -> None:
    cfg = _config()
    done = {("a", "0.5", 0), ("b", "1.0", 4), ("c", "2.0", 1)}
    tasks = plan_tasks(cfg, done)
    cells = [(t.method, format_value(j.value), j.episode) for t in tasks for j in t.jobs]
    assert len(cells) == 3 * 3 * 5 - 3
    assert not done & set(cells)
    assert [t.value for t in tasks] == sorted(t.value for t in tasks)
    assert [t.method for t in tasks[:3]] == ["a", "b", "c"]
