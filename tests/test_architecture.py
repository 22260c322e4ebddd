"""The package's import graph, read from the sources (nothing imported): no two modules import
each other, at module level, inside a function or under ``TYPE_CHECKING``; and the controller
package imports no other package of the project."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("impact_control", "impact_envs", "impact_eval", "impact_learn", "impact_franka",
            "impact_lerobot", "impact_robosuite")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, modules: set[str]) -> set[str]:
    """The project modules ``path`` imports (``from a import b`` counts ``a.b`` when that is a
    module, else ``a``)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules
                     else node.module for a in node.names]
        else:
            continue
        found |= {n for n in names if n in modules}
    return found


def import_graph() -> dict[str, set[str]]:
    """Project module -> the project modules it imports."""
    paths = {_module_name(p): p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")}
    modules = set(paths)
    return {name: _imports(path, modules) - {name} for name, path in paths.items()}


def test_no_two_modules_import_each_other() -> None:
    graph = import_graph()
    pairs = sorted({tuple(sorted((a, b))) for a, deps in graph.items() for b in deps
                    if a in graph.get(b, set())})
    assert pairs == []


def test_the_controller_package_imports_no_other_project_package() -> None:
    outside = {f"{a} -> {b}" for a, deps in import_graph().items()
               if a.startswith("impact_control") for b in deps
               if not b.startswith("impact_control")}
    assert outside == set()


def test_the_robot_runner_imports_only_the_controller_package() -> None:
    outside = {f"{a} -> {b}" for a, deps in import_graph().items()
               if a.startswith("impact_franka") for b in deps
               if not b.startswith(("impact_control", "impact_franka"))}
    assert outside == set()
