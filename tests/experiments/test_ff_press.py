"""The controller-attributed press's diagnostic runner (``experiments/ff_press.py``, issue 54):
its paired summary and exact McNemar test on hand-made rows, and the episodes it reads from a
table."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest

from impact_control.errors import InvalidArgumentError
from impact_experiments.ff_press import COLUMNS, mcnemar_p, pairs_from, summary


def test_exact_mcnemar_p() -> None:
    assert mcnemar_p(0, 6) == pytest.approx(2 / 64)  # 6 discordant pairs, all one way
    assert mcnemar_p(3, 3) == 1.0 and mcnemar_p(0, 0) == 1.0
    assert mcnemar_p(1, 7) == pytest.approx(2 * (1 + 8) / 256)


def _row(method: str, value: float, episode: int, success: int, over: float,
         ff: float) -> dict[str, object]:
    return {"method": method, "env_id": "IMPACT/Hammer-v1", "param_value": value,
            "reset_value": value, "seed": 100 + episode, "episode": episode,
            "success": success, "length": 750, "contact_over_20n_s": over,
            "peak_contact_sustained_n": 1.0, "ff_press_over_20n_s": ff,
            "ff_press_mean_n": math.nan, "contact_net_p95_n": 0.0,
            "contact_net_over_20n_s": 0.0}


def test_summary_pairs_the_episodes_and_pools_them(tmp_path: Path) -> None:
    rows = [_row("a", 9.0, 0, 1, 0.1, 0.0), _row("b", 9.0, 0, 0, 0.2, 0.0),
            _row("a", 9.0, 1, 0, 7.5, 0.3), _row("b", 9.0, 1, 0, 0.02, 0.0),
            _row("a", 10.0, 0, 0, 9.0, 0.0), _row("b", 10.0, 0, 1, 0.0, 0.0)]
    path = tmp_path / "rows.csv"
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    lines = summary(path, "a", "b")
    assert lines[1] == "9 | 1/2 | 0/2 | 1 | 0 | 7.50 / 0.20 | 0.30 / 0.00"
    assert lines[2] == "10 | 0/1 | 1/1 | 0 | 1 | 9.00 / - | 0.00 / 0.00"
    assert lines[3].startswith("pooled: 1 vs 1; only a 1, only b 1; exact McNemar p = 1")


def test_pairs_from_a_table_keep_its_seeds_and_drawn_masses(tmp_path: Path) -> None:
    path = tmp_path / "episodes.csv"
    path.write_text("method,param_name,param_value,seed,episode,drawn_mass_kg\n"
                    "impact,object_mass,9.0,11,0,9.0\n"
                    "impact,object_mass_bin,8.0,12,1,9.5\n"
                    "other,object_mass,9.0,13,0,9.0\n"
                    "impact,object_mass,4.0,14,0,4.0\n")
    assert pairs_from(path, "impact", 5, 10) == [(9.0, 9.0, 11, 0), (8.0, 9.5, 12, 1)]
    with pytest.raises(InvalidArgumentError, match="no rows of method 'nope'"):
        pairs_from(path, "nope", 5, 10)


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str], needle: str) -> None:
    from impact_experiments.ff_press import main

    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert needle in err, err


def test_bad_input_is_one_line_and_writes_nothing(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "rows.csv"
    grid = ["--values", "9", "--episodes", "1", "--out", str(out)]
    _refused(["--methods", "impakt", *grid], capsys, "impakt")
    _refused(["--methods", "", *grid], capsys, "names no method")
    _refused(["--methods", "impact", "--env", "IMPACT/Nail-v1", *grid], capsys, "Nail")
    _refused(["--methods", "impact", "--controller-set", "guard.nope=1", *grid], capsys,
             "nope")
    _refused(["--methods", "impact", "--workers", "0", *grid], capsys, "--workers")
    assert not out.exists() and not out.with_suffix(".json").exists()
    out.write_text("a,b\n1,2\n")  # somebody else's file: never appended to
    _refused(["--methods", "impact", *grid], capsys, "holds other rows")
    assert out.read_text() == "a,b\n1,2\n"
    _refused(["--out", str(tmp_path / "none.csv"), "--summary", "a,b"], capsys, "cannot read")
    _refused(["--out", str(out), "--summary", "a,b"], capsys, "holds rows of")


def test_a_resume_needs_the_same_env_and_controller_changes(tmp_path: Path) -> None:
    from impact_experiments.ff_press import check_out

    out = tmp_path / "rows.csv"
    check_out(out, "IMPACT/Hammer-v1", ["guard.enabled=False"])
    out.write_text(",".join(COLUMNS) + "\n")
    check_out(out, "IMPACT/Hammer-v1", ["guard.enabled=False"])  # the same run: resumes
    with pytest.raises(InvalidArgumentError, match="holds other rows"):
        check_out(out, "IMPACT/Hammer-v1", [])
    with pytest.raises(InvalidArgumentError, match="holds other rows"):
        check_out(out, "IMPACT/Dumbbell-v1", ["guard.enabled=False"])


def test_contact_wedge_refuses_bad_steps_and_bodies(capsys: pytest.CaptureFixture[str]) -> None:
    from impact_experiments.contact_wedge import main

    for argv, needle in ((["--steps", "-1"], "invalid --steps -1"),
                         (["--steps", "0", "--body", "anvil"], "invalid --body 'anvil'")):
        with pytest.raises(SystemExit) as exit_info:
            main(["--env", "IMPACT/Hammer-v1", "--method", "scripted", "--value", "1",
                  *argv])
        err = capsys.readouterr().err
        assert exit_info.value.code == 2 and err.count("\n") == 1 and needle in err, err
