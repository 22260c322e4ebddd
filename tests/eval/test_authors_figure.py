"""``impact_eval.experiments.authors_figure``: per-bin rates, the Fisher test, issue 38's
acceptance checks, the table and the plot, on synthetic bin sweeps."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from impact_eval.experiments.authors_figure import (
    BINS,
    PUBLISHED,
    acceptance,
    bin_rates,
    fisher_two_sided,
    main,
)


def _episodes(successes: dict[str, list[int]], n: int = 50) -> pd.DataFrame:
    """A bin sweep's rows: ``successes[method][b]`` of ``n`` episodes in bin b succeed."""
    rows = [{"method": m, "param_name": "object_mass_bin", "param_value": lo, "episode": e,
             "success": int(e < ks[b])}
            for m, ks in successes.items() for b, (lo, _) in enumerate(BINS) for e in range(n)]
    return pd.DataFrame(rows)


def test_fisher_matches_textbook_values() -> None:
    assert fisher_two_sided(3, 4, 1, 4) == pytest.approx(0.4857, abs=1e-4)  # the lady tasting tea
    assert fisher_two_sided(10, 10, 0, 10) == pytest.approx(2 / 184756, rel=1e-9)
    assert fisher_two_sided(5, 10, 5, 10) == pytest.approx(1.0)


def test_their_own_rates_pass_and_a_weaker_ours_fails() -> None:
    theirs = {m: [round(50 * v) for v in vals] for m, vals in PUBLISHED.items()}
    good = {**theirs, "impact": [48, 48, 47, 46, 45, 44, 42, 30]}
    checks = {what: ok for what, ok, _ in acceptance(bin_rates(_episodes(good)))}
    assert all(checks.values()), checks
    weak = {**theirs, "impact": [48, 48, 47, 46, 45, 44, 5, 2]}
    checks = {what: ok for what, ok, _ in acceptance(bin_rates(_episodes(weak)))}
    assert not checks["impact >= 0.80 in every bin up to 8 kg"]
    assert not checks["no bin where impact is below impact_authors (Fisher two-sided, 5 %)"]
    off = {**good, "impact_authors": [25] * 8}
    checks = {what: ok for what, ok, _ in acceptance(bin_rates(_episodes(off)))}
    assert not checks["impact_authors: published rate inside our 95 % interval in >= 6 bins"]


def test_the_command_writes_the_table_and_the_plot(tmp_path: Path, capsys) -> None:
    theirs = {m: [round(50 * v) for v in vals] for m, vals in PUBLISHED.items()}
    _episodes({**theirs, "impact": [45] * 8}).to_csv(tmp_path / "episodes.csv", index=False)
    assert main(["--table", str(tmp_path)]) == 0
    text = (tmp_path / "authors_figure.md").read_text()
    assert "| IMPACT, their controller | 43/50" in text and "| ↳ published | 0.86" in text
    assert (tmp_path / "plots" / "authors_figure.png").stat().st_size > 0
    assert "NOT met" not in capsys.readouterr().out


def test_a_grid_table_is_refused_in_one_line(tmp_path: Path, capsys) -> None:
    pd.DataFrame([{"method": "impact", "param_name": "object_mass", "param_value": 1.0,
                   "success": 1}]).to_csv(tmp_path / "episodes.csv", index=False)
    with pytest.raises(SystemExit) as exc:
        main(["--table", str(tmp_path)])
    assert exc.value.code == 2 and "not a bin sweep" in capsys.readouterr().err
