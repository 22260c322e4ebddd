"""The documentation site builds in strict mode (issue 58): warnings are errors, so a broken
link, a figure under ``results/`` that a page links but that is missing, or an API object
that no longer exists fails here (``mkdocs.yml``; the ``docs`` extra, in ``dev``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def test_the_site_builds_strictly(tmp_path: Path) -> None:
    pytest.importorskip("mkdocs", reason="the docs extra is not installed")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d",
                           str(tmp_path / "site")], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    site = tmp_path / "site"
    for page in ("index.html", "results/index.html", "api/eval/index.html",
                 "api/envs/index.html", "_results/hammer_basket/plots/authors_figure.png",
                 "environments/hammer_basket/index.html"):
        assert (site / page).is_file(), page
    api = (site / "api" / "eval" / "index.html").read_text()
    assert "evaluate" in api and "SweepSpec" in api  # rendered from the docstrings
    env_page = (site / "environments" / "hammer" / "index.html").read_text()
    assert "Observation space" in env_page and "Version history" in env_page  # the docstring
    start = (site / "index.html").read_text()
    assert "pip install torch==2.13.0" in start  # the README's commands, one source


def test_every_public_name_has_an_api_entry_and_a_missing_one_fails_the_build(
        tmp_path: Path) -> None:
    """The public API is the ``__all__`` of ``mkdocs_hooks.PUBLIC_PACKAGES``; each name has a
    ``:::`` entry under docs/api/, and without one ``on_pre_build`` stops the build."""
    pytest.importorskip("mkdocs", reason="the docs extra is not installed")
    sys.path.insert(0, str(REPO))
    try:
        from mkdocs.exceptions import PluginError

        import mkdocs_hooks
    finally:
        sys.path.remove(str(REPO))
    assert mkdocs_hooks.undocumented(REPO / "docs") == []
    (tmp_path / "api").mkdir()
    page = (REPO / "docs" / "api" / "eval.md").read_text()
    for other in (REPO / "docs" / "api").glob("*.md"):
        text = page.replace("::: impact_eval.api.evaluate\n", "") if other.name == "eval.md" \
            else other.read_text()
        (tmp_path / "api" / other.name).write_text(text)
    assert mkdocs_hooks.undocumented(tmp_path) == ["impact_eval.evaluate"]
    with pytest.raises(PluginError, match="lacks 1 public name.*impact_eval.evaluate"):
        mkdocs_hooks.on_pre_build({"docs_dir": str(tmp_path)})


def test_the_public_names_are_read_without_importing_the_packages() -> None:
    """The hook reads each ``__all__`` from the source (a docs-only install has no MuJoCo):
    the same names the imported packages declare."""
    import importlib

    pytest.importorskip("mkdocs", reason="the docs extra is not installed")
    sys.path.insert(0, str(REPO))
    try:
        import mkdocs_hooks
    finally:
        sys.path.remove(str(REPO))
    for package in mkdocs_hooks.PUBLIC_PACKAGES:
        declared = importlib.import_module(package).__all__
        assert mkdocs_hooks.public_names(package) == list(declared), package
