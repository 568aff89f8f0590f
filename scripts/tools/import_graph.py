#!/usr/bin/env python3
"""The package's import graph, read with :mod:`ast` (nothing is imported).

Every import statement that names a module of the package is an arrow, wherever it
stands: at module level, inside a function (it still makes the module depend on the
other), or under ``if TYPE_CHECKING:`` (it still says the module knows the other's
types). Relative imports are resolved against the importing module's package;
``from P import name`` is an arrow to ``P.name`` when that is a module, else to
``P``. The implicit runs of parent ``__init__`` files are not arrows. Imports made
by name at run time (``importlib.import_module``) are not seen.

Prints the counts a refactor is judged by: modules, lines, import levels (the
longest chain of imports, in modules), circles and their modules.

Usage:  python3 scripts/tools/import_graph.py [PACKAGE_DIR]   (default: fibersweep/)
"""

from __future__ import annotations

import ast
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Arrow:
    """One import of a package module by another.

    Attributes
    ----------
    source, target : str
        Dotted module names (a package is its ``__init__``).
    path : Path
        File of ``source``.
    line : int
        Line of the import statement.
    text : str
        The statement as written (first line).
    where : {'module', 'function', 'type-checking'}
        Where it stands: run on import, run when its function is called, or never run.
    """

    source: str
    target: str
    path: Path
    line: int
    text: str
    where: str

    def show(self, root: Path) -> str:
        try:
            shown = self.path.relative_to(root.parent)
        except ValueError:
            shown = self.path
        where = "" if self.where == "module" else f"  [{self.where}]"
        return f"{shown}:{self.line}: {self.text}{where}"


def discover(root: Path) -> dict[str, Path]:
    """Every module of the package at ``root`` (a folder with ``__init__.py``): name -> file."""
    modules: dict[str, Path] = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).with_suffix("")
        parts = list(rel.parts)
        if not all((root.parent / Path(*parts[:i]) / "__init__.py").is_file()
                   for i in range(1, len(parts))):  # fmt: skip
            continue  # a script in a data folder, not a module of the package
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _is_type_checking(test: ast.expr) -> bool:
    if isinstance(test, ast.Name):
        return test.id == "TYPE_CHECKING"
    return isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"


def _statements(tree: ast.Module) -> Iterable[tuple[ast.Import | ast.ImportFrom, str]]:
    """Every import statement of a module with where it stands."""

    def visit(node: ast.AST, where: str) -> Iterable[tuple[ast.Import | ast.ImportFrom, str]]:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node, where
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            inner = "type-checking" if where == "type-checking" else "function"
            for child in ast.iter_child_nodes(node):
                yield from visit(child, inner)
        elif isinstance(node, ast.If) and _is_type_checking(node.test):
            for stmt in node.body:
                yield from visit(stmt, "type-checking")
            for stmt in node.orelse:
                yield from visit(stmt, where)
        else:
            for child in ast.iter_child_nodes(node):
                yield from visit(child, where)

    yield from visit(tree, "module")


def _known(name: str, modules: Mapping[str, Path]) -> str | None:
    """The longest prefix of ``name`` that is a module of the package (None if none)."""
    parts = name.split(".")
    for n in range(len(parts), 0, -1):
        candidate = ".".join(parts[:n])
        if candidate in modules:
            return candidate
    return None


def arrows(modules: Mapping[str, Path]) -> list[Arrow]:
    """Every import of a package module by a package module."""
    out: list[Arrow] = []
    for name, path in modules.items():
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for stmt, where in _statements(ast.parse(source, filename=str(path))):
            targets: list[str | None] = []
            if isinstance(stmt, ast.Import):
                targets = [_known(a.name, modules) for a in stmt.names]
            else:
                if stmt.level:
                    base = package.split(".")
                    base = base[: len(base) - (stmt.level - 1)]
                    origin = ".".join(base + ([stmt.module] if stmt.module else []))
                else:
                    origin = stmt.module or ""
                for a in stmt.names:
                    sub = f"{origin}.{a.name}"
                    targets.append(sub if sub in modules else _known(origin, modules))
            text = lines[stmt.lineno - 1].strip()
            for target in dict.fromkeys(t for t in targets if t is not None):
                out.append(Arrow(name, target, path, stmt.lineno, text, where))
    return out


def circles(edges: Iterable[Arrow]) -> list[list[str]]:
    """Strongly connected components of more than one module, and self-imports.

    Tarjan's algorithm, iterative; each component sorted, the list sorted.
    """
    graph: dict[str, set[str]] = {}
    selfs: set[str] = set()
    for e in edges:
        graph.setdefault(e.source, set()).add(e.target)
        graph.setdefault(e.target, set())
        if e.source == e.target:
            selfs.add(e.source)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1 or node in selfs:
                    found.append(sorted(component))
    return sorted(found)


def levels(edges: Iterable[Arrow], modules: Iterable[str]) -> int:
    """The longest chain of imports, counted in modules (circles collapsed to one)."""
    comp: dict[str, str] = {}
    for c in circles(list(edges)):
        for m in c:
            comp[m] = c[0]
    graph: dict[str, set[str]] = {comp.get(m, m): set() for m in modules}
    for e in edges:
        a, b = comp.get(e.source, e.source), comp.get(e.target, e.target)
        if a != b:
            graph.setdefault(a, set()).add(b)
            graph.setdefault(b, set())
    depth: dict[str, int] = {}

    def d(n: str) -> int:
        stack = [(n, False)]
        while stack:
            node, done = stack.pop()
            if node in depth:
                continue
            if done:
                depth[node] = 1 + max((depth[c] for c in graph[node]), default=0)
                continue
            stack.append((node, True))
            stack.extend((c, False) for c in graph[node] if c not in depth)
        return depth[n]

    return max((d(n) for n in graph), default=0)


def main(argv: list[str]) -> int:
    root = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parents[2] / "fibersweep"
    modules = discover(root)
    edges = arrows(modules)
    lines = sum(len(p.read_text(encoding="utf-8").splitlines()) for p in modules.values())
    found = circles(edges)
    print(f"modules {len(modules)}  lines {lines}  import levels {levels(edges, modules)}  "
          f"circles {len(found)}")
    for c in found:
        print("  circle:", ", ".join(c))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
