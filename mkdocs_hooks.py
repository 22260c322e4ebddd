"""MkDocs hooks of the documentation site (mkdocs.yml ``hooks``): the figures under
``results/`` appear on the site as they appear on GitHub, and the API reference covers every
public name.

``on_pre_build`` fails the build when a name in the ``__all__`` of a package in
``PUBLIC_PACKAGES`` has no ``::: <package>....<name>`` entry on a page under ``docs/api/``
(``undocumented``; tests/test_docs_site.py lists them without building).

The Markdown pages link a table's figure where the command that made it wrote it, e.g.
``../results/hammer_basket/plots/authors_figure.png`` from ``docs/results.md``: right on
GitHub, outside the site's ``docs/``. ``on_files`` adds each figure under ``results/`` that a page
links to the site as ``_results/<path>`` (a missing one fails the strict build as a broken
link), and ``on_page_markdown`` points such links there. The figure is
never copied into ``docs/``: one file, made by its command.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

REPO = Path(__file__).resolve().parent
RESULTS = REPO / "results"
SITE_DIR = "_results"
LINK = re.compile(r"\]\(((?:\.\./)+)results/")


PUBLIC_PACKAGES = ("impact_control", "impact_envs", "impact_eval", "impact_franka",
                   "impact_lerobot")
"""The packages whose ``__all__`` is the API a user is told to call."""
DIRECTIVE = re.compile(r"^::: ([\w.]+)\s*$", re.MULTILINE)


def public_names(package: str) -> list[str]:
    """The ``__all__`` of ``package``, read from its ``__init__.py`` without importing it (the
    site builds with the ``docs`` extra alone, without MuJoCo or torch): a list or tuple of
    strings, or ``sorted(NAME)`` of a dict literal ``NAME``."""
    tree = ast.parse((REPO / package / "__init__.py").read_text())
    assigned = {t.id: node.value for node in tree.body
                if isinstance(node, ast.Assign | ast.AnnAssign) and node.value is not None
                for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
                if isinstance(t, ast.Name)}
    value = assigned["__all__"]
    if isinstance(value, ast.Call) and isinstance(value.func, ast.Name) \
            and value.func.id == "sorted" and isinstance(value.args[0], ast.Name):
        return sorted(ast.literal_eval(assigned[value.args[0].id]))
    return list(ast.literal_eval(value))


def undocumented(docs_dir: Path) -> list[str]:
    """``package.name`` of each public name without an API entry: an entry documents it when
    its path is inside the package and ends with the name (``impact_eval.api.evaluate``
    documents ``impact_eval.evaluate``, which calls it)."""
    entries = {d for page in (docs_dir / "api").glob("*.md")
               for d in DIRECTIVE.findall(page.read_text())}
    missing = []
    for package in PUBLIC_PACKAGES:
        for name in public_names(package):
            if not any(e.startswith(f"{package}.") and e.rsplit(".", 1)[-1] == name
                       for e in entries):
                missing.append(f"{package}.{name}")
    return missing


def on_pre_build(config) -> None:
    missing = undocumented(Path(config["docs_dir"]))
    if missing:
        raise PluginError(f"the API reference (docs/api/) lacks {len(missing)} public "
                          f"name(s): {', '.join(missing)}; add a '::: module.name' entry")


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
