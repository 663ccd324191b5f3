"""The import layers: who may import whom, and no import cycle between modules.

Every import statement of the packages is read with ``ast``, at module level and inside
functions alike (a lazy import is a dependency too), including ``TYPE_CHECKING`` blocks.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sdar_tamp", "solvers", "streams", "domains")

#: Layer of a module: the longest prefix in this table names it (low to high).
LAYERS: dict[str, str] = {
    # leaves: nothing of ours but other leaves
    "sdar_tamp": "leaves",  # the package itself: the version and SdarError only
    "sdar_tamp.errors": "leaves",
    "sdar_tamp.arguments": "leaves",
    "sdar_tamp.textfile": "leaves",
    "sdar_tamp.graph": "leaves",
    "sdar_tamp.resources": "leaves",
    "sdar_tamp.logs": "leaves",
    # the language and the world
    "sdar_tamp.language": "language",
    "sdar_tamp.world": "world",
    # plan files and their independent validator: the world only
    "sdar_tamp.plan_file": "plan",
    "sdar_tamp.plan_metrics": "plan",
    "sdar_tamp.plan_reading": "plan",
    "sdar_tamp.plan_writing": "plan",
    "sdar_tamp.plan_building": "plan",
    "sdar_tamp.plan_rules": "plan",
    "sdar_tamp.plan_state": "plan",
    "sdar_tamp.replay": "plan",
    "sdar_tamp.replay_walk": "plan",
    "sdar_tamp.replay_sampling": "plan",
    "sdar_tamp.replay_steps": "plan",
    # planners, geometric streams, the declarative domains' samplers
    "solvers": "solvers",
    "streams": "streams",
    "domains": "domains",
    # the application layer
    "sdar_tamp.app": "app",
    "sdar_tamp.evaluation": "evaluation",
    "sdar_tamp.compat": "compat",
    "sdar_tamp.viewer": "viewer",
    "sdar_tamp.export": "export",
    "sdar_tamp.schedule": "schedule",
    "sdar_tamp.schemas": "leaves",  # JSON Schema files and their loader
    # the command line on top
    "sdar_tamp.cli": "cli",
}

_BASE = {"leaves"}
#: Layer -> the layers its modules may import (their own included).
ALLOWED: dict[str, set[str]] = {
    "leaves": _BASE,
    "language": _BASE | {"language"},
    "world": _BASE | {"world"},
    "plan": _BASE | {"world", "plan"},
    "solvers": _BASE | {"language", "solvers"},
    "streams": _BASE | {"world", "streams"},
    "domains": _BASE | {"language", "domains"},
    "app": _BASE | {"language", "world", "plan", "schedule", "solvers", "streams", "app"},
    "evaluation": _BASE | {"world", "plan", "app", "evaluation"},
    "compat": _BASE | {"language", "solvers", "compat"},
    "viewer": _BASE | {"world", "plan", "viewer"},
    "export": _BASE | {"world", "plan", "export"},
    "schedule": _BASE | {"world", "plan", "schedule"},
    "cli": set(LAYERS.values()),
}


def layer_of(module: str) -> str | None:
    """The layer of ``module`` (None: not one of ours)."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        layer = LAYERS.get(".".join(parts[:n]))
        if layer is not None:
            return layer
    return None


@cache
def module_files() -> dict[str, Path]:
    """Module name -> file, for every module of :data:`PACKAGES`."""
    out: dict[str, Path] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            out[".".join(parts)] = path
    return out


def imports(module: str, path: Path, known: set[str]) -> Iterator[tuple[str, int]]:
    """``(imported module, line)`` for every import in the file, at any depth; ``from a
    import b`` names ``a.b`` when that is a module, else ``a``."""
    is_package = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = module.split(".")
                anchor = anchor[: len(anchor) - node.level + (1 if is_package else 0)]
                base = ".".join([*anchor, base] if base else anchor)
            for alias in node.names:
                full = f"{base}.{alias.name}"
                yield (full if full in known else base), node.lineno


@cache
def dependency_graph() -> dict[str, dict[str, int]]:
    """Module -> {imported module of ours: line}."""
    files = module_files()
    known = set(files)
    graph: dict[str, dict[str, int]] = {}
    for module, path in files.items():
        edges = graph.setdefault(module, {})
        for target, line in imports(module, path, known):
            if layer_of(target) is not None and target != module:
                edges.setdefault(target, line)
    return graph


def test_every_module_has_a_layer() -> None:
    unplaced = sorted(m for m in module_files() if layer_of(m) is None)
    assert not unplaced, f"modules without a layer in LAYERS: {unplaced}"


def test_no_module_imports_above_its_layer() -> None:
    files = module_files()
    breaks = []
    for module, edges in dependency_graph().items():
        own = layer_of(module)
        assert own is not None
        for target, line in edges.items():
            layer = layer_of(target)
            if layer not in ALLOWED[own]:
                where = files[module].relative_to(ROOT)
                breaks.append(f"{where}:{line}: {module} ({own}) imports {target} ({layer})")
    assert not breaks, "layering breaks:\n" + "\n".join(breaks)


def find_cycle(graph: dict[str, dict[str, int]]) -> list[str] | None:
    """One import cycle (its modules, first repeated at the end), or None."""
    state: dict[str, int] = {}  # 1: on the stack, 2: done
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for target in sorted(graph.get(node, {})):
            if state.get(target) == 1:
                return [*stack[stack.index(target) :], target]
            if target not in state:
                found = visit(target)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_no_import_cycle_between_modules() -> None:
    cycle = find_cycle(dependency_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_the_checks_catch_a_break_and_a_cycle() -> None:
    assert layer_of("solvers.sdar.solver") == "solvers"
    assert layer_of("sdar_tamp.app.config") == "app"
    assert layer_of("numpy") is None
    assert "app" not in ALLOWED["solvers"] and "streams" not in ALLOWED["solvers"]
    assert find_cycle({"a": {"b": 1}, "b": {"c": 1}, "c": {"a": 1}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b": 1}, "b": {}}) is None


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("def f():\n    from streams.motion import X\n", ["streams.motion"]),
        ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import sdar_tamp.app\n",
         ["typing", "sdar_tamp.app"]),
        ("from . import errors\n", ["sdar_tamp.errors"]),
    ],
)  # fmt: skip
def test_imports_are_found_at_any_depth(tmp_path: Path, source: str, expected: list[str]) -> None:
    path = tmp_path / "mod.py"
    path.write_text(source)
    found = [m for m, _ in imports("sdar_tamp.mod", path, {"sdar_tamp.errors"})]
    assert found == expected
