"""episodes.csv: durable appends, torn-tail repair, resume keys, sorted atomic rewrite."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from impact_control.errors import InvalidArgumentError
from impact_eval.csvio import EpisodeLog, format_cell, read_rows, row_key
from impact_eval.metrics import EPISODE_COLUMNS


def _row(method: str, value: float, episode: int, reason: str = "") -> dict[str, object]:
    row: dict[str, object] = dict.fromkeys(EPISODE_COLUMNS, 0)
    row.update(
        method=method,
        env_id="Ns/E-v0",
        param_name="object_mass",
        param_value=value,
        episode=episode,
        seed=10 * episode,
        time_to_success_s=math.nan,
        energy_j=0.1 + 0.2,
        failure_reason=reason,
    )
    return row


def test_append_then_resume_appends(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    log = EpisodeLog(path)
    log.open()
    log.append(_row("b", 2.0, 1, 'exception: "Quoted", with comma'))
    log.append(_row("a", 0.6, 0))
    log.close()
    log.open()  # resume: no second header
    log.append(_row("a", 0.1, 3))
    log.close()
    rows = read_rows(path)
    assert [row_key(r) for r in rows] == [("b", "2.0", 1), ("a", "0.6", 0), ("a", "0.1", 3)]
    assert rows[0]["failure_reason"] == 'exception: "Quoted", with comma'
    assert rows[0]["energy_j"] == repr(0.1 + 0.2) and rows[0]["time_to_success_s"] == "nan"


def test_torn_last_line_is_ignored_and_repaired(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    log = EpisodeLog(path)
    log.open()
    log.append(_row("a", 1.0, 0))
    log.append(_row("a", 1.0, 1, "timeout"))
    log.close()
    full = path.read_text()
    path.write_text(full[:-4])  # crash mid-row: "...,time" without newline
    assert [row_key(r) for r in read_rows(path)] == [("a", "1.0", 0)]
    log.open()
    log.append(_row("a", 1.0, 1, "timeout"))
    log.close()
    assert path.read_text() == full


def test_finalize_sorts_and_deduplicates(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    log = EpisodeLog(path)
    log.open()
    for method, value, ep in [
        ("b", 10.0, 0),
        ("a", 2.0, 1),
        ("a", 2.0, 0),
        ("a", 0.5, 9),
        ("a", 2.0, 1),
    ]:
        log.append(_row(method, value, ep))
    assert log.finalize() == 4
    keys = [row_key(r) for r in read_rows(path)]
    assert keys == [("a", "0.5", 9), ("a", "2.0", 0), ("a", "2.0", 1), ("b", "10.0", 0)]
    assert not (tmp_path / "episodes.csv.tmp").exists()


def test_foreign_csv_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    path.write_text("a,b\n1,2\n")
    with pytest.raises(InvalidArgumentError):
        read_rows(path)


def test_format_cell_round_trips_floats() -> None:
    for value in (0.1, 1 / 3, 1e-300, 12345.678):
        assert float(format_cell(value)) == value
    assert format_cell(math.nan) == "nan" and format_cell(3) == "3"


def test_success_table_markdown_has_one_cell_per_method_and_value():
    import pandas as pd

    from impact_eval.report import success_table_markdown

    summary = pd.DataFrame({
        "method": ["a", "a", "b"], "param_name": "object_mass", "param_value": [0.2, 5.0, 0.2],
        "successes": [3, 0, 4], "n": [4, 4, 4], "success_rate": [0.75, 0.0, 1.0],
        "ci_low": [0.3, 0.0, 0.5], "ci_high": [0.95, 0.5, 1.0],
    })
    lines = success_table_markdown(summary).splitlines()
    assert lines[0] == "| object_mass | a | b |"
    assert lines[2] == "| 0.2 | 3/4 (75%, 30%–95%) | 4/4 (100%, 50%–100%) |"
    assert lines[3] == "| 5 | 0/4 (0%, 0%–50%) | — |"


def test_plot_axis_label_takes_the_unit_the_task_declares():
    import pandas as pd

    from impact_eval.plots import param_label

    def label(env_id: str, name: str) -> str:
        return param_label(pd.DataFrame({"env_id": [env_id], "param_name": [name]}))

    assert label("IMPACT/Hammer-v1", "object_mass") == "object mass [kg]"
    assert label("IMPACT/Disturbance-v1", "disturbance_n") == "disturbance n [N]"
    assert label("IMPACT/Calligraphy-v1", "surface_friction") == "surface friction"
    assert label("test_eval_fake:ImpactTest/Fake-v0", "object_mass") == "object mass"
