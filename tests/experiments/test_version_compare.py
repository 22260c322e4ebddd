"""``impact_experiments.version_compare``: a table against its ``-v2`` twin, per method."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from impact_experiments.version_compare import compare_table, main, markdown, wide


def _rows(method: str, successes: dict[float, int], n: int = 20,
          over_20n_s: float = 0.0) -> list[dict]:
    return [{"method": method, "param_value": v, "episode": e, "success": int(e < k),
             "contact_over_20n_s": over_20n_s}
            for v, k in successes.items() for e in range(n)]


def test_a_drop_of_half_is_significant_and_one_episode_is_not() -> None:
    old = pd.DataFrame(_rows("impact", {1.0: 20, 5.0: 18}) + _rows("vanilla_dp", {1.0: 10, 5.0: 0}))
    new = pd.DataFrame(_rows("impact", {1.0: 10, 5.0: 8}, over_20n_s=1.5)
                       + _rows("vanilla_dp", {1.0: 9, 5.0: 0}))
    rows = compare_table(old, new).set_index("method")
    assert rows.loc["impact", "old"] == "38/40" and rows.loc["impact", "new"] == "18/40"
    assert rows.loc["impact", "significantly_lower"]
    assert rows.loc["impact", "cells_moved"] == "1: 20→10; 5: 18→8"
    assert rows.loc["impact", "contact_over_20n_s"] == "0.00 → 1.50"
    assert not rows.loc["vanilla_dp", "significantly_lower"]
    assert rows.loc["vanilla_dp", "fisher_p"] == pytest.approx(1.0)
    assert "peak_contact_sustained_n" not in rows  # neither side has it


def test_cells_and_methods_of_one_side_are_named_not_pooled(tmp_path: Path) -> None:
    """An unfinished twin lacking its hard cell is compared on the shared cells only; a
    method of one side gets its own row; a NaN safety value is left out of the mean."""
    old = pd.DataFrame(_rows("impact", {1.0: 20, 9.0: 2}) + _rows("impact_warm", {1.0: 20}))
    new = pd.DataFrame(_rows("impact", {1.0: 19}, over_20n_s=float("nan"))
                       + _rows("lerobot_dp", {1.0: 5}))
    new.loc[0, "contact_over_20n_s"] = 3.0
    rows = compare_table(old, new).set_index("method")
    assert (rows.loc["impact", "old"], rows.loc["impact", "new"]) == ("20/20", "19/20")
    assert rows.loc["impact", "cells_moved"] == "1: 20→19; 9 only old"
    assert rows.loc["impact", "contact_over_20n_s"] == "0.00 → 3.00"
    assert rows.loc["impact_warm", "cells_moved"] == "only in the old table"
    assert rows.loc["lerobot_dp", "cells_moved"] == "only in the new table"
    assert not rows["significantly_lower"].any()
    text = markdown("t", 2, compare_table(old, new))
    assert "| impact_warm | 20/20 | 0/0 | 1 | no | only in the old table | – |" in text


def _results(tmp_path: Path) -> Path:
    for name, k in (("t", 18), ("t_v2", 17)):
        (tmp_path / name).mkdir()
        pd.DataFrame(_rows("impact", {1.0: k})).to_csv(tmp_path / name / "episodes.csv",
                                                       index=False)
    (tmp_path / "manifest.json").write_text(json.dumps(
        {"format": 1, "tables": {"t": {"dir": "t"}, "t_v2": {"dir": "t_v2"},
                                 "other": {"dir": "other"}}}))
    return tmp_path


def test_the_command_finds_the_twins_and_writes_the_report(tmp_path: Path, capsys) -> None:
    results = _results(tmp_path)
    out = tmp_path / "report.md"
    assert main(["--results", str(results), "--out", str(out)]) == 0
    text = out.read_text()
    assert "### `t` → `t_v2`" in text and "| impact | 18/20 | 17/20 | 1 | no | 1: 18→17 |" in text
    assert text == capsys.readouterr().out


@pytest.mark.parametrize("argv, needle", [
    (["other"], "no twin other_v2 in the manifest; valid: t"),
    (["--version", "3"], "no table of the manifest has a twin on -v3"),
    (["--results", "/nonexistent"], "no manifest.json in /nonexistent")])
def test_bad_input_is_one_line(tmp_path: Path, capsys, argv, needle) -> None:
    results = _results(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main(["--results", str(results), *argv])
    assert exc.value.code == 2 and needle in capsys.readouterr().err.strip().splitlines()[-1]


def test_wide_shows_both_versions_cell_by_cell() -> None:
    """``--wide``: the new version's row above the old one's, labelled from ``env_id``; a
    cell one side did not run is –."""
    old = pd.DataFrame(_rows("impact", {1.0: 20, 9.0: 2})).assign(env_id="IMPACT/Hammer-v1")
    new = pd.DataFrame(_rows("impact", {1.0: 19}) + _rows("vanilla_dp", {1.0: 4}))
    text = wide(old, new.assign(env_id="IMPACT/Hammer-v2"), 2)
    assert text.splitlines() == [
        "| method | env | 1 | 9 |", "|---|---|---|---|",
        "| `impact` | -v2 | 19/20 | – |", "| `impact` | -v1 | 20/20 | 2/20 |",
        "| `vanilla_dp` | -v2 | 4/20 | – |", "| `vanilla_dp` | -v1 | – | – |"]
    assert wide(old, new, 2, ["impact"]).splitlines()[2:] == [
        "| `impact` | -v2 | 19/20 | – |", "| `impact` | -v1 | 20/20 | 2/20 |"]


def test_wide_from_the_command_and_an_unknown_method_is_one_line(tmp_path: Path,
                                                                 capsys) -> None:
    results = _results(tmp_path)
    assert main(["--results", str(results), "--wide"]) == 0
    assert "| `impact` | -v2 | 17/20 |\n| `impact` | old | 18/20 |" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["--results", str(results), "--wide", "--methods", "impact,nope"])
    assert "--methods impact,nope: not in t; valid: impact" in capsys.readouterr().err


def test_methods_without_wide_is_refused(tmp_path: Path, capsys) -> None:
    """--methods picks the rows of --wide; without it (the pooled report of every method) it
    is one line, exit 2, nothing written."""
    results = _results(tmp_path)
    out = tmp_path / "report.md"
    with pytest.raises(SystemExit) as exc:
        main(["--results", str(results), "--methods", "impact", "--out", str(out)])
    assert exc.value.code == 2 and not out.exists()
    assert "--methods impact: only with --wide" in capsys.readouterr().err.strip().splitlines()[-1]
