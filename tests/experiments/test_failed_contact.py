"""``impact_experiments.failed_contact``: the failed episodes' contact and the long presses,
per method, with a Fisher comparison against a second table."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from impact_experiments.failed_contact import contact_summary, main


def _table(folder: Path, presses: list[tuple[str, int, float]]) -> Path:
    """``folder/episodes.csv`` with one row per (method, success, seconds above 20 N); the
    sustained peak is 10 N per second above 20 N."""
    folder.mkdir()
    pd.DataFrame([{"method": m, "success": s, "contact_over_20n_s": t,
                   "peak_contact_sustained_n": 10.0 * t} for m, s, t in presses]
                 ).to_csv(folder / "episodes.csv", index=False)
    return folder


def test_percentiles_are_over_failures_and_long_presses_over_all_episodes() -> None:
    rows = ([("impact", 1, 0.0)] * 8 + [("impact", 1, 1.5)]          # a success that pressed
            + [("impact", 0, t) for t in (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 5.0)])
    summary = contact_summary(pd.DataFrame(rows, columns=["method", "success",
                                                          "contact_over_20n_s"]).assign(
        peak_contact_sustained_n=lambda f: 10 * f["contact_over_20n_s"]))
    r = summary.loc["impact"]
    assert (r["failed"], r["long"], r["episodes"]) == (10, 2, 19)
    assert r["over_20n_p90_s"] == pytest.approx(0.8 + 0.1 * (5.0 - 0.8))  # linear, as pandas
    assert r["sustained_p90_n"] == pytest.approx(10 * r["over_20n_p90_s"])


def test_the_command_compares_two_tables(tmp_path: Path, capsys) -> None:
    new = _table(tmp_path / "new", [("a", 0, 3.0)] * 10 + [("a", 1, 0.0)] * 10
                 + [("b", 0, 0.0)])
    old = _table(tmp_path / "old", [("a", 0, 0.0)] * 10 + [("a", 1, 0.0)] * 10)
    assert main([str(new), str(old)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[2] == "| `a` | 10 | 3.00 | 30.0 | 10/20 | 0/20 | 0.000436 |"  # 2 C(20,10) / C(40,10)
    assert out[3] == "| `b` | 1 | 0.00 | 0.0 | 0/1 | – | – |"


def test_a_method_without_failures_has_no_percentile(tmp_path: Path, capsys) -> None:
    table = _table(tmp_path / "t", [("a", 1, 2.0), ("a", 1, 0.0)])
    assert main([str(table)]) == 0
    assert capsys.readouterr().out.splitlines()[2] == "| `a` | 0 | – | – | 1/2 |"


@pytest.mark.parametrize("argv, needle", [
    (["{empty}"], "no {empty}/episodes.csv; valid: a sweep's output folder"),
    (["{bare}"], "lacks contact_over_20n_s, peak_contact_sustained_n; valid"),
    (["{bare}", "--long-s", "0"], "invalid --long-s 0.0; valid: > 0")])
def test_bad_input_is_one_line(tmp_path: Path, capsys, argv, needle) -> None:
    (tmp_path / "empty").mkdir()
    (tmp_path / "bare").mkdir()
    pd.DataFrame({"method": ["a"], "success": [1]}).to_csv(tmp_path / "bare" / "episodes.csv",
                                                           index=False)
    fill = {"empty": tmp_path / "empty", "bare": tmp_path / "bare"}
    with pytest.raises(SystemExit) as exc:
        main([a.format(**fill) for a in argv])
    assert exc.value.code == 2
    assert needle.format(**fill) in capsys.readouterr().err.strip().splitlines()[-1]
