"""MkDocs hooks of the documentation site (mkdocs.yml ``hooks``): the figures under
``results/`` appear on the site as they appear on GitHub.

The Markdown pages link a table's figure where the command that made it wrote it, e.g.
``../results/hammer_basket/plots/authors_figure.png`` from ``docs/results.md``: right on
GitHub, outside the site's ``docs/``. ``on_files`` adds each figure under ``results/`` that a page
links to the site as ``_results/<path>`` (a missing one fails the strict build as a broken
link), and ``on_page_markdown`` points such links there. The figure is
never copied into ``docs/``: one file, made by its command.
"""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.structure.files import File, Files

REPO = Path(__file__).resolve().parent
RESULTS = REPO / "results"
SITE_DIR = "_results"
LINK = re.compile(r"\]\(((?:\.\./)+)results/")


LINKED = re.compile(r"\]\((?:\.\./)+results/([^)\s#]+)\)")


def on_files(files: Files, config) -> Files:
    docs = Path(config["docs_dir"])
    linked = {m for page in docs.rglob("*.md") for m in LINKED.findall(page.read_text())}
    for name in sorted(linked):
        if (RESULTS / name).is_file():
            files.append(File.generated(config, f"{SITE_DIR}/{name}",
                                        abs_src_path=str(RESULTS / name)))
    return files


def on_page_markdown(markdown: str, page, config, files) -> str:
    depth = page.file.src_uri.count("/")  # ../ steps from the page up to docs/
    return LINK.sub(lambda m: "](" + "../" * depth + f"{SITE_DIR}/", markdown)
