"""The import structure of symloc (docs/architecture.md): no cycles, and what runs on a robot
never imports what evaluates it.

Every import statement of every module is read from the source (top level, inside functions and
under ``if TYPE_CHECKING`` alike), so a function-local import that dodges a rule fails here too.
"""

from __future__ import annotations

import ast
import itertools
from collections.abc import Iterable, Mapping
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "symloc"

ROBOT_SIDE = (
    "geometry.py",
    "scan.py",
    "odometry.py",
    "lidar_spec.py",
    "camera_model.py",
    "image_header.py",
    "errors.py",
    "hypothesis.py",
    "_checks.py",
    "grid",
    "features",
    "symmetry",
    "mcl",
    "slam",
    "vision",
    "localizer",
    "msgs",
    "files",
    "io",
    "ros",
)
EVALUATION = ("symloc.sim", "symloc.bench", "symloc.figures", "symloc.experiments", "symloc.cli")


def _modules() -> list[Path]:
    out: list[Path] = []
    for name in ROBOT_SIDE:
        path = PACKAGE / name
        out.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path])
    return out


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@cache
def _all_modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _imports(path: Path) -> list[tuple[int, str]]:
    """``(line, module)`` of every absolute import, and relative ones resolved."""
    tree = ast.parse(path.read_text(), filename=str(path))
    here = _module_name(path).split(".")
    base = here if path.name == "__init__.py" else here[:-1]
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                pkg = base[: len(base) - (node.level - 1)]
                mod = ".".join(pkg + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            # ``from symloc.x import y`` imports module symloc.x.y when y is one, else symloc.x
            modules = _all_modules()
            for alias in node.names:
                sub = f"{mod}.{alias.name}"
                found.append((node.lineno, sub if sub in modules else mod))
    return found


def _resolve(name: str) -> str | None:
    """The symloc module (file) that ``name`` names, or None outside symloc."""
    modules = _all_modules()
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


@cache
def _module_graph() -> dict[str, dict[str, int]]:
    """module -> {imported symloc module: first line}, for every module of symloc."""
    graph: dict[str, dict[str, int]] = {}
    for name, path in _all_modules().items():
        edges: dict[str, int] = {}
        for line, mod in _imports(path):
            if mod != "symloc" and not mod.startswith("symloc."):
                continue
            target = _resolve(mod)
            if target is not None and target != name and target != "symloc":
                edges.setdefault(target, line)
        graph[name] = edges
    return graph


def _unit(module: str) -> str:
    """The package-level node of a module: ``symloc.io.rosbag`` -> ``symloc.io``."""
    return ".".join(module.split(".")[:2])


def _cycles(graph: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """One cycle (as a path that returns to its start) through each strongly connected
    component of more than one node (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[set[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work: list[tuple[str, list[str]]] = [(root, sorted(graph.get(root, ())))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, todo = work[-1]
            if todo:
                nxt = todo.pop(0)
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, sorted(graph.get(nxt, ()))))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp: set[str] = set()
                while True:
                    top = stack.pop()
                    on_stack.discard(top)
                    comp.add(top)
                    if top == node:
                        break
                if len(comp) > 1:
                    components.append(comp)
    return [_path_in(graph, comp) for comp in components]


def _path_in(graph: Mapping[str, Iterable[str]], comp: set[str]) -> list[str]:
    """A shortest cycle through the smallest node of a strongly connected component."""
    start = min(comp)
    prev: dict[str, str] = {}
    frontier = [start]
    while frontier:
        nxt_frontier = []
        for node in frontier:
            for nxt in sorted(graph.get(node, ())):
                if nxt == start:
                    path = [node]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    return [start, *reversed(path[:-1]), start]
                if nxt in comp and nxt not in prev:
                    prev[nxt] = node
                    nxt_frontier.append(nxt)
        frontier = nxt_frontier
    raise AssertionError(f"no cycle through {start}")  # pragma: no cover


def _explain(cycle: list[str], edge_of: Mapping[tuple[str, str], str]) -> str:
    lines = (edge_of[a, b] for a, b in itertools.pairwise(cycle))
    return " -> ".join(cycle) + "\n  " + "\n  ".join(lines)


def test_no_import_cycle_between_packages() -> None:
    graph: dict[str, set[str]] = {}
    edge_of: dict[tuple[str, str], str] = {}
    for module, edges in _module_graph().items():
        for target, line in edges.items():
            a, b = _unit(module), _unit(target)
            if a != b:
                graph.setdefault(a, set()).add(b)
                edge_of.setdefault((a, b), f"{module} imports {target} (line {line})")
    cycles = _cycles(graph)
    assert not cycles, "import cycles between symloc's packages:\n" + "\n".join(
        _explain(c, edge_of) for c in cycles
    )


def test_no_import_cycle_between_modules() -> None:
    graph = {m: set(edges) for m, edges in _module_graph().items()}
    edge_of = {
        (m, t): f"{m} imports {t} (line {line})"
        for m, edges in _module_graph().items()
        for t, line in edges.items()
    }
    cycles = _cycles(graph)
    assert not cycles, "import cycles between symloc's modules:\n" + "\n".join(
        _explain(c, edge_of) for c in cycles
    )


def test_cycle_finder_reports_the_path() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"e"}}
    assert _cycles(graph) == [["a", "b", "c", "a"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_graph_sees_function_local_and_relative_imports() -> None:
    graph = _module_graph()
    # relative: localizer/localizer.py has ``from .claim import ...``
    assert "symloc.localizer.claim" in graph["symloc.localizer.localizer"]
    # function-local: the CLI imports its commands' dependencies inside functions
    assert "symloc.ros.replay" in graph["symloc.cli.commands.replay"]


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_robot_side_does_not_import_evaluation(path: Path) -> None:
    bad = [
        f"line {line}: {mod}"
        for line, mod in _imports(path)
        if any(mod == e or mod.startswith(e + ".") for e in EVALUATION)
    ]
    assert not bad, f"{path.relative_to(PACKAGE)} imports evaluation code: {bad}"
