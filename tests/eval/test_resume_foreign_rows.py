"""``--resume`` keeps only the run's own rows (issue 53, silent 3 and 4): a row of another
method, value, bin, episode index or seed, or a bin row whose ``drawn_mass_kg`` its bin and
seed do not draw, is refused in one line naming the first, and nothing is written."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from fixtures.eval_fake import ENV_ID

from impact_eval.cli import main

CHANGES = [  # (column, value) of a copied row that makes it foreign, and what the line says
    ("param_value", "3.5", "value 3.5 is not among [0.5, 2.0]"),  # another mass
    ("method", "fake_slow", "method 'fake_slow' is not among fake_fast, fake_impact"),
    ("episode", "2", "episode 2 is beyond --episodes 2"),  # another episode index
    ("seed", "12345", "its seed is not this grid's"),  # another seed (invented variation)
]


def _args(out: Path, *extra: str, values: tuple[str, str] = ("--masses", "0.5,2")) -> list[str]:
    return ["--env", ENV_ID, "--method", "fake_fast,fake_impact", *values, "--episodes", "2",
            "--envs-per-worker", "2", "--seed", "11", "--workers", "1", "--out", str(out),
            *extra]


def _rows(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        return list(reader.fieldnames or []), list(reader)


def _write(path: Path, header: list[str], rows: list[dict[str, str]]) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, header, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


def _refused(out: Path, argv: list[str], capsys) -> str:
    """Resume ``argv``: exit 2, one line, episodes.csv and run.json untouched."""
    before = [(out / n).read_bytes() for n in ("episodes.csv", "run.json")]
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot resume" in err
    assert [(out / n).read_bytes() for n in ("episodes.csv", "run.json")] == before
    return err


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("finished") / "run"
    assert main(_args(out)) == 0
    return out


@pytest.mark.parametrize("column, value, named", CHANGES)
def test_a_foreign_row_appended_is_refused_naming_it(finished: Path, tmp_path: Path, capsys,
                                                     column: str, value: str,
                                                     named: str) -> None:
    out = tmp_path / "run"
    out.mkdir()
    for name in ("episodes.csv", "run.json", "identity.json"):
        (out / name).write_bytes((finished / name).read_bytes())
    header, rows = _rows(out / "episodes.csv")
    _write(out / "episodes.csv", header, [*rows, {**rows[-1], column: value}])
    err = _refused(out, _args(out, "--resume"), capsys)
    assert named in err and f"line {len(rows) + 2} " in err


def test_the_first_of_two_foreign_rows_in_the_middle_is_named(finished: Path, tmp_path: Path,
                                                              capsys) -> None:
    out = tmp_path / "run"
    out.mkdir()
    for name in ("episodes.csv", "run.json", "identity.json"):
        (out / name).write_bytes((finished / name).read_bytes())
    header, rows = _rows(out / "episodes.csv")
    foreign = [{**rows[0], "param_value": "7.0"}, {**rows[0], "method": "other"}]
    _write(out / "episodes.csv", header, [rows[0], *foreign, *rows[1:]])
    err = _refused(out, _args(out, "--resume"), capsys)
    assert "line 3 " in err and "value 7.0" in err and "'other'" not in err
    capsys.readouterr()
    _write(out / "episodes.csv", header, rows)  # without them it resumes: nothing to run
    assert main(_args(out, "--resume")) == 0
    assert "0 episodes run (8 already done, 8 in total)" in capsys.readouterr().out


@pytest.mark.parametrize("bins, edited", [
    ("0.5-1.5,1.5-6", [1.5, 6.0]),  # the case: the last bin widened
    ("0.5-1.5,1.5-3", [1.5, 3.0]),  # narrowed (invented variation)
])
def test_rows_drawn_in_the_old_bin_are_not_relabelled(tmp_path: Path, capsys, bins: str,
                                                      edited: list[float]) -> None:
    out = tmp_path / "run"
    assert main(_args(out, values=("--mass-bins", "0.5-1.5,1.5-4"))) == 0
    (out / "identity.json").unlink()
    run = json.loads((out / "run.json").read_text())
    run["identity"]["spec"]["bin_highs"] = edited
    (out / "run.json").write_text(json.dumps(run))
    err = _refused(out, _args(out, "--resume", values=("--mass-bins", bins)), capsys)
    assert f"is not the mass bin [1.5, {edited[1]!r}) draws from its seed" in err


def test_an_edited_drawn_mass_is_refused(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    args = _args(out, values=("--mass-bins", "0.5-1.5"))
    assert main(args) == 0
    header, rows = _rows(out / "episodes.csv")
    rows[1]["drawn_mass_kg"] = "1.0"
    _write(out / "episodes.csv", header, rows)
    err = _refused(out, [*args, "--resume"], capsys)
    assert "line 3 " in err and "drawn_mass_kg 1.0 is not the mass bin [0.5, 1.5)" in err
