"""``impact-eval report`` and ``--resume`` on damaged output directories: torn rows, malformed
values, a file where the plots go, a run.json that is not an object. One line, exit 2, and
nothing rewritten before the input is known good."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest
from fixtures.eval_fake import sweep_args

from impact_eval.cli import main


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("damaged") / "run"
    assert main(sweep_args(out, "--workers", "1")) == 0
    return out


def _copy(src: Path, dst: Path) -> Path:
    dst.mkdir()
    for name in ("episodes.csv", "run.json", "identity.json", "summary.csv", "summary.md"):
        (dst / name).write_bytes((src / name).read_bytes())
    return dst


def _edit_row(column: str, value: str) -> Callable[[Path], None]:
    def edit(out: Path) -> None:
        lines = (out / "episodes.csv").read_text().splitlines(keepends=True)
        header = lines[0].rstrip("\n").split(",")
        fields = lines[3].rstrip("\n").split(",")
        fields[header.index(column)] = value
        lines[3] = ",".join(fields) + "\n"
        (out / "episodes.csv").write_text("".join(lines))
    return edit


def _torn(out: Path) -> None:
    text = (out / "episodes.csv").read_text()
    (out / "episodes.csv").write_text(text + text.splitlines()[1][:20])


def _plots_file(out: Path) -> None:
    (out / "plots").write_text("not a directory")


def _header_only(out: Path) -> None:
    (out / "episodes.csv").write_text((out / "episodes.csv").read_text().splitlines()[0] + "\n")


def _other_csv(out: Path) -> None:
    (out / "episodes.csv").write_text("a,b\n1,2\n")


REPORT_CASES: dict[str, tuple[Callable[[Path], None], str]] = {
    "torn last row": (_torn, "ends in a row cut mid-line"),
    "success not a number": (_edit_row("success", "yes"), "row 4: invalid success 'yes'"),
    "success 2": (_edit_row("success", "2"), "valid: 0 or 1"),
    "energy not a number": (_edit_row("energy_j", "lots"), "invalid energy_j 'lots'"),
    "length fractional": (_edit_row("length", "2.5"), "invalid length"),
    "seed empty": (_edit_row("seed", ""), "invalid seed"),
    "param_value text": (_edit_row("param_value", "heavy"), "invalid param_value 'heavy'"),
    "plots is a file": (_plots_file, "plots is not a directory"),
    "header only": (_header_only, "has no episodes"),
    "not an episodes csv": (_other_csv, "lacks columns"),
}


def _refused_with_one_line(finished: Path, tmp_path: Path, capsys: pytest.CaptureFixture,
                           case: tuple[Callable[[Path], None], str],
                           argv: Callable[[Path], list[str]]) -> None:
    """Damage a copy of the finished sweep, run ``argv(out)``: exit 2, the expected message on
    one line, and every file of the directory byte for byte as it was."""
    damage, message = case
    out = _copy(finished, tmp_path / "out")
    damage(out)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert main(argv(out)) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


@pytest.mark.parametrize("case", sorted(REPORT_CASES))
def test_report_refuses_damaged_input_before_rewriting_anything(
        case: str, finished: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    _refused_with_one_line(finished, tmp_path, capsys, REPORT_CASES[case],
                           lambda out: ["report", str(out)])


RESUME_CASES: dict[str, tuple[Callable[[Path], None], str]] = {
    "seed not an integer": (_edit_row("seed", "abc"), "seed 'abc'"),
    "run.json a list": (lambda out: (out / "run.json").write_text("[1, 2]"),
                        "run.json is not a JSON object"),
    "identity.json a string": (lambda out: (out / "identity.json").write_text('"x"'),
                               "identity.json is not a JSON object"),
    "identity.json corrupt": (lambda out: (out / "identity.json").write_text("{"),
                              "cannot read"),
    "no identity at all": (lambda out: [(out / n).unlink() for n in ("run.json",
                                                                     "identity.json")],
                           "neither identity.json nor a run.json"),
    "run.json empty object": (lambda out: [(out / "identity.json").unlink(),
                                           (out / "run.json").write_text("{}")],
                              "neither identity.json nor a run.json"),
}


@pytest.mark.parametrize("case", sorted(RESUME_CASES))
def test_resume_refuses_damaged_input_with_one_line(
        case: str, finished: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    _refused_with_one_line(finished, tmp_path, capsys, RESUME_CASES[case],
                           lambda out: [*sweep_args(out, "--workers", "1"), "--resume"])


@pytest.mark.parametrize("change", [("--episodes", "2"), ("--seed", "3"),
                                    ("--method", "fake_fast,fake_slow")])
def test_resume_refuses_changes_with_run_json_gone(
        change: tuple[str, str], finished: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture) -> None:
    out = _copy(finished, tmp_path / "out")
    (out / "run.json").unlink()
    assert main([*sweep_args(out, "--workers", "1"), "--resume", *change]) == 2
    assert "cannot resume" in capsys.readouterr().err
    assert json.loads((out / "identity.json").read_text())["spec"]["controller_overrides"] == []


def test_a_zero_byte_csv_is_a_fresh_start(finished: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "episodes.csv").write_bytes(b"")
    assert main(sweep_args(out, "--workers", "1")) == 0
    assert (out / "episodes.csv").read_bytes() == (finished / "episodes.csv").read_bytes()


@pytest.mark.parametrize("identity", [
    {"spec_format": 2, "spec": [1, 2], "param_name": "object_mass"},  # current layout
    {"env": "x", "seed": 0, "methods": ["fake_fast"], "values": 3, "episodes": 2},  # legacy
])
def test_a_damaged_identity_is_one_line_and_changes_nothing(
        identity: dict, finished: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = _copy(finished, tmp_path / "out")
    (out / "run.json").unlink()
    (out / "identity.json").write_text(json.dumps(identity))
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert main([*sweep_args(out, "--workers", "1"), "--resume"]) == 2
    err = capsys.readouterr().err.strip()
    assert "damaged run record" in err and "\n" not in err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
