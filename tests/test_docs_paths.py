"""Every repository path cited in the docs, the code, the tests and ``results/`` exists: a
file moved or deleted takes its citations with it (issue 57). A path that a documented command
writes (after ``--out``) is not cited as existing, and ``GENERATED`` lists the few that a guide
or a run makes, each with the reason."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CITED = re.compile(
    r"(?<![\w/.\-])(?<!--out )((?:docs|results|tests|impact_[a-z_]+|configs|\.ci)/"
    r"[\w./\-]*[\w\-]\.(?:md|py|csv|json|xml|sh|png|svg|toml|gif|mp4|txt|safetensors))")
"""A cited path: under one of the repository's folders, ending in a file suffix."""
SOURCES = (".md", ".py", ".json", ".toml", ".sh")
SKIP_DIRS = ("docs/plans",)
"""Plans record what was intended when they were written, not today's tree."""
GENERATED = {
    "results/quickstart/summary.md": "written by the README's quickstart (impact-eval --quick)",
    "impact_control/friction_observer.py": "written by docs/adding_a_stage.md's walk-through",
}


def _sources() -> list[Path]:
    found = []
    for path in ROOT.rglob("*"):
        rel = path.relative_to(ROOT)
        if (path.suffix not in SOURCES or not path.is_file()
                or any(p.startswith(".") and p != ".ci" for p in rel.parts)
                or any(p.endswith("venv") for p in rel.parts)
                or str(rel).startswith(SKIP_DIRS) or path.stat().st_size > 2_000_000):
            continue
        found.append(path)
    return found


def test_every_cited_path_exists() -> None:
    missing = sorted({f"{cited} (cited in {path.relative_to(ROOT)})"
                      for path in _sources()
                      for cited in CITED.findall(path.read_text(errors="replace"))
                      if "*" not in cited and cited not in GENERATED
                      and not (ROOT / cited).exists()})
    assert missing == []


def test_the_citation_pattern_finds_paths_and_skips_outputs() -> None:
    text = ("see docs/eval.md and `impact_envs/tasks/bins.py`; --out results/new/x.csv; "
            "/abs/docs/eval.md; tests/conftest.py.")
    assert CITED.findall(text) == ["docs/eval.md", "impact_envs/tasks/bins.py",
                                   "tests/conftest.py"]
