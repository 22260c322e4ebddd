"""``impact_experiments.executor_cost``: the task schedule behind docs/scale.md's estimate."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from impact_experiments.executor_cost import main, schedule_wall

REPO = Path(__file__).resolve().parents[2]


def test_schedule_hands_each_task_to_the_first_free_cpu():
    assert schedule_wall([4.0, 1.0, 1.0, 1.0], 2) == 4.0
    assert schedule_wall([1.0, 1.0, 1.0, 4.0], 2) == 5.0  # 1 | 1, then 1 | 1 + 4
    assert schedule_wall([2.0] * 10, 100) == 2.0


def test_estimate_matches_what_docs_scale_states(capsys):
    csv = REPO / "results" / "hammer_presets" / "episodes.csv"
    main(["--estimate", str(csv), "--methods", "vanilla_dp,augmented_dp,impact,impact_paper",
          "--cpus", "160"])
    out = capsys.readouterr().out
    estimate = json.loads(out)
    doc = (REPO / "docs" / "scale.md").read_text()
    documented = re.search(r"It is (\d+) tasks and ([\d,]+) CPU-seconds", doc)
    assert documented, "docs/scale.md no longer states the estimate"
    assert estimate["tasks"] == int(documented[1])
    assert round(estimate["cpu_s"]) == int(documented[2].replace(",", ""))
    assert f"| 160 (10 nodes × 16 cores) | {round(estimate['wall_s'])} s |" in doc


@pytest.mark.parametrize("argv, message", [
    (["--estimate", "nowhere.csv"], "is not a file"),
    (["--estimate", "README.md", "--step-ms", "impact=fast"], "--step-ms must be"),
    (["--estimate", "README.md", "--cpus", "0"], "must be >= 1"),
    (["--repeats", "0", "--out", "x"], "--repeats must be >= 1"),
    ([], "give --out"),
])
def test_bad_input_is_one_line(argv, message, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and message in err
