"""The package layout: data flows one way, so the import graph between packages has no
cycle, and mapping, scoring and planning stay free of motion and the simulator."""

from __future__ import annotations

import ast
from pathlib import Path

import footfall

ROOT = Path(footfall.__file__).parent
# A module longer than this says at its top why (STYLE.md: one concept per module).
MAX_LINES = 400


def _unit(module: str) -> str:
    """The package (or top-level module) a footfall module belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
        elif isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
    return names


def package_graph() -> dict[str, set[str]]:
    """Which footfall package imports which (every import, lazy or not)."""
    graph: dict[str, set[str]] = {}
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        module = ".".join(rel.parts).removesuffix(".__init__")
        if module == "footfall":
            continue  # the public API re-exports everything
        source = _unit(module)
        for name in _imports(path):
            if name.startswith("footfall.") and _unit(name) != source:
                graph.setdefault(source, set()).add(_unit(name))
            elif not name.startswith("footfall"):
                graph.setdefault(source, set()).add("<" + name.split(".")[0] + ">")
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """A cycle in a directed graph, or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt) :], nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_the_cycle_finder_finds_cycles():
    """The checker itself: it reports a planted cycle and passes a chain."""
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": {"c"}}) is None


def test_packages_import_each_other_without_cycles():
    """No footfall package imports one that imports it back, directly or through others."""
    assert find_cycle(package_graph()) is None


def test_mapping_scoring_and_planning_never_import_motion_or_the_simulator():
    """The map and the planner do not depend on the controller, MuJoCo or the simulator."""
    graph = package_graph()
    for package in ("mapping", "scoring", "planning"):
        assert not graph.get(package, set()) & {"motion", "sim", "<mujoco>", "nodes"}, package


def test_long_modules_say_why():
    """A module over MAX_LINES lines explains at its top why it is one module."""
    for path in ROOT.rglob("*.py"):
        lines = path.read_text().splitlines()
        if len(lines) > MAX_LINES:
            head = "\n".join(lines[:40])
            assert "one module" in head, f"{path.relative_to(ROOT)}: {len(lines)} lines"
