"""The package's import graph, read from the sources (nothing imported): no two modules import
each other, at module level, inside a function or under ``TYPE_CHECKING``; no package imports a
package on its own floor or above it (``FLOORS``), so no two packages import each other; the
controller package imports no other package of the project; the experiments live outside the
library."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FLOORS: dict[str, int] = {
    "impact_control": 0,  # the controller core: NumPy only
    "impact_envs": 1, "impact_franka": 1,  # the simulated robot and tasks; the real one
    "impact_learn": 2, "impact_robosuite": 2,  # demos and training; robosuite's controller
    "impact_lerobot": 3,  # the LeRobot plugin (its policies run impact_learn's networks)
    "impact_eval": 4,  # sweeps, methods, reproduce
    "impact_experiments": 5,  # one-off measurements: import the library, imported by none
}
"""Each package's floor: a package imports only packages on lower floors (docs/architecture.md)."""
PACKAGES = tuple(FLOORS)


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


def package_edges() -> dict[tuple[str, str], list[str]]:
    """(importing package, imported package) -> the module imports behind it."""
    edges: dict[tuple[str, str], list[str]] = {}
    for a, deps in import_graph().items():
        for b in deps:
            pa, pb = a.split(".")[0], b.split(".")[0]
            if pa != pb:
                edges.setdefault((pa, pb), []).append(f"{a} -> {b}")
    return edges


def test_no_package_imports_one_on_its_floor_or_above() -> None:
    upward = sorted(line for (pa, pb), lines in package_edges().items()
                    if FLOORS[pb] >= FLOORS[pa] for line in lines)
    assert upward == []


def test_no_package_level_cycle() -> None:
    graph: dict[str, set[str]] = {p: set() for p in PACKAGES}
    for pa, pb in package_edges():
        graph[pa].add(pb)
    done: set[str] = set()

    def cycle_from(node: str, path: tuple[str, ...]) -> tuple[str, ...] | None:
        if node in path:
            return (*path[path.index(node):], node)
        if node in done:
            return None
        for nxt in sorted(graph[node]):
            found = cycle_from(nxt, (*path, node))
            if found:
                return found
        done.add(node)
        return None

    assert [c for p in PACKAGES if (c := cycle_from(p, ()))] == []


def test_every_project_package_has_a_floor() -> None:
    found = {p.name for p in ROOT.iterdir()
             if p.name.startswith("impact_") and (p / "__init__.py").exists()}
    assert found == set(FLOORS)


def test_the_library_holds_no_experiments() -> None:
    """One-off measurements live in ``impact_experiments``, never inside ``impact_eval``."""
    assert not (ROOT / "impact_eval" / "experiments").exists()
    importers = sorted(f"{a} -> {b}" for a, deps in import_graph().items()
                       if not a.startswith("impact_experiments") for b in deps
                       if b.startswith("impact_experiments"))
    assert importers == []
