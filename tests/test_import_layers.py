"""The package's layers (docs/design.md), read from the source: imports point down, never round.

Every import counts, at module level, inside a function or under ``TYPE_CHECKING``: a
function-level import that closes a loop is a circle all the same.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "tuflexperf"
# the layered packages: their modules import each other in no circle
LAYERED = ("analysis", "models", "reduction", "report")
# (importer prefix, forbidden prefix): a lower layer never imports a higher one
NEVER = [
    ("tuflexperf.models", "tuflexperf.analysis"),
    ("tuflexperf.models", "tuflexperf.reduction"),
    ("tuflexperf.models", "tuflexperf.report"),
    ("tuflexperf.analysis", "tuflexperf.report"),
    ("tuflexperf.analysis", "tuflexperf.cli"),
    ("tuflexperf.reduction", "tuflexperf.analysis"),
    ("tuflexperf.reduction", "tuflexperf.report"),
    ("tuflexperf.reduction", "tuflexperf.cli"),
    ("tuflexperf.analysis.study", "tuflexperf.analysis.requirements"),
    ("tuflexperf.analysis.mission", "tuflexperf.analysis.requirements"),
    ("tuflexperf.analysis.batch", "tuflexperf.analysis.requirements"),
]


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path, modules: set[str]) -> set[str]:
    """The package's modules that ``path`` imports anywhere in its text."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            # `from pkg import module` names that module; `from module import name` the module
            names = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules
                     else node.module for a in node.names]
        else:
            continue
        found.update(n for n in names if n in modules)
    return found


def graph() -> dict[str, set[str]]:
    files = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    modules = set(files)
    return {name: imports_of(path, modules) - {name} for name, path in files.items()}


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def test_the_layered_packages_import_in_no_circle() -> None:
    prefixes = tuple(f"tuflexperf.{p}" for p in LAYERED)
    edges = {m: {d for d in ds if d.startswith(prefixes)}
             for m, ds in graph().items() if m.startswith(prefixes)}
    assert circles(edges) == []


@pytest.mark.parametrize(("lower", "higher"), NEVER)
def test_a_lower_layer_never_imports_a_higher_one(lower: str, higher: str) -> None:
    taken = {(m, d) for m, ds in graph().items() if m == lower or m.startswith(lower + ".")
             for d in ds if d == higher or d.startswith(higher + ".")}
    assert taken == set()


def test_the_circle_finder_finds_a_circle() -> None:
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []
