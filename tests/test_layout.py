"""The package layout: data flows one way, so the import graph between packages has no
cycle, and mapping, scoring and planning stay free of motion and the simulator."""

from __future__ import annotations

import ast
from pathlib import Path

import footfall

ROOT = Path(footfall.__file__).parent
# Budgets (STYLE.md: one concept per module, typically 100-300 lines).
MODULE_LINES = 400
CLASS_LINES = 300
# The modules and classes allowed over their budget, and why each is one piece. An entry
# that no longer needs its exception is an error too, so the list stays short and true.
LONG_MODULES = {
    "messages/types.py": "every message type of the bus in one place, as docs/runtime.md "
    "lists them: the codec and the recorders read them together",
    "recording/ros_types.py": "one converter pair per message type to its ROS 2 type; the "
    "table of schemas is read and checked as one",
    "motion/walker.py": "the walking controller (see its class's exception)",
}
LONG_CLASSES = {
    "motion/walker.py::WalkController": "the thesis' state machine (Table 5.1): every tick "
    "reads and writes the step under way, the body's reference pose and the state together; "
    "its policies already live in nine part modules (command shaping, stroke governor, gait "
    "scheduler, foothold policies, feedback, leg solver, safety, swing feet, registration)",
}


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


def long_pieces(root: Path) -> tuple[dict[str, int], dict[str, int]]:
    """Modules over ``MODULE_LINES`` and classes over ``CLASS_LINES`` under ``root``, with
    their lengths, keyed ``path`` and ``path::Class`` (paths relative to ``root``)."""
    modules, classes = {}, {}
    for path in sorted(root.rglob("*.py")):
        name = path.relative_to(root).as_posix()
        text = path.read_text()
        if (lines := len(text.splitlines())) > MODULE_LINES:
            modules[name] = lines
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                length = node.end_lineno - node.lineno + 1
                if length > CLASS_LINES:
                    classes[f"{name}::{node.name}"] = length
    return modules, classes


def test_the_budget_finds_long_modules_and_classes(tmp_path):
    """The checker itself: a planted long module and a planted long class are reported,
    a short module is not."""
    body = "\n".join(f"    x{k} = {k}" for k in range(CLASS_LINES + 1))
    (tmp_path / "long.py").write_text(f"class Big:\n{body}\n" + "\n" * MODULE_LINES)
    (tmp_path / "short.py").write_text("class Small:\n    pass\n")
    modules, classes = long_pieces(tmp_path)
    assert set(modules) == {"long.py"} and set(classes) == {"long.py::Big"}


def test_modules_and_classes_keep_their_budgets():
    """No module over MODULE_LINES and no class over CLASS_LINES lines, but the named
    exceptions; and every exception is still over its budget (else it goes from the list)."""
    modules, classes = long_pieces(ROOT)
    assert set(modules) == set(LONG_MODULES), modules
    assert set(classes) == set(LONG_CLASSES), classes
    assert all(len(why) > 40 for why in (*LONG_MODULES.values(), *LONG_CLASSES.values()))
