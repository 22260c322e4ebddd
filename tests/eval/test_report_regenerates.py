"""A figure on the site is what its command draws: ``impact-eval report DIR`` on a committed
table rewrites its plots and ``summary.csv`` byte for byte (issue 58 item 4). The fast test
redraws the smallest linked table; ``--runslow`` redraws every table docs/results.md shows."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from impact_eval.cli import main

REPO = Path(__file__).resolve().parents[2]
FIGURE = re.compile(r"\]\(\.\./results/([a-z0-9_]+)/plots/[^)]+\.png\)")


def _shown_tables() -> list[str]:
    text = (REPO / "docs" / "results.md").read_text()
    return sorted(set(FIGURE.findall(text)))


def _redraws_identically(name: str, tmp_path: Path) -> None:
    copy = tmp_path / name
    shutil.copytree(REPO / "results" / name, copy)
    for png in (copy / "plots").glob("*.png"):
        png.unlink()
    assert main(["report", str(copy)]) == 0
    drawn = sorted(p.name for p in (copy / "plots").glob("*.png"))
    committed = {p.name for p in (REPO / "results" / name / "plots").glob("*.png")}
    assert drawn and set(drawn) <= committed  # authors_figure.png has a command of its own
    for png in drawn:
        assert (copy / "plots" / png).read_bytes() == \
            (REPO / "results" / name / "plots" / png).read_bytes(), f"{name}/plots/{png}"
    assert (copy / "summary.csv").read_bytes() == \
        (REPO / "results" / name / "summary.csv").read_bytes()


def test_the_smallest_shown_table_redraws_byte_for_byte(tmp_path: Path) -> None:
    assert "hammer_rgb" in _shown_tables()
    _redraws_identically("hammer_rgb", tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", _shown_tables())
def test_every_shown_table_redraws_byte_for_byte(name: str, tmp_path: Path) -> None:
    if not (REPO / "results" / name / "episodes.csv").is_file():
        pytest.skip(f"{name} is drawn by its own command, not impact-eval report")
    _redraws_identically(name, tmp_path)
