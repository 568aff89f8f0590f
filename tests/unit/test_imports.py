"""The package's import graph: no circles, and no arrow back up the layers.

Every module of ``fibersweep`` is read with :mod:`ast` (nothing is imported), and
every import statement that names a module of the package is an arrow, wherever
it stands:

* at module level, inside a class body, a ``try`` or an ``if``;
* inside a function (a function-local import still makes the module depend on
  the other; it only runs later);
* under ``if TYPE_CHECKING:``. Such an import never runs, so it cannot fail at
  import time, but it still says that the module knows the other's types: a
  circle closed by moving one import under ``TYPE_CHECKING`` is the same
  responsibility in the wrong file, hidden from the interpreter. It counts.

Relative imports are resolved against the importing module's package.
``from P import name`` is an arrow to ``P.name`` when that is a module of the
package, else to ``P`` (whose ``__init__`` runs). Importing ``a.b.c`` also runs
the ``__init__`` of ``a`` and ``a.b``; those implicit arrows are not counted:
they carry no dependency on what the parent holds. Imports made by name at run
time (``importlib.import_module``: the effects package loading its effect
modules) are not seen.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

import fibersweep

#: The layers of docs/architecture.md ("Layers and who imports whom"), lowest
#: first. A module belongs to the layer of the longest name below that matches it;
#: it may import its own layer and the layers below, never one above.
#: * base: what every layer may use: the package's version (``fibersweep``, and
#:   ``_version``, which a build writes), exception types, the atomic writer, the
#:   stale-kernel-cache guard, the progress bars, the shipped example configs;
#: * geometry < units < analysis < flow < fiber < config: the diagram's chain
#:   (``analysis`` depends on nothing of the simulation; ``fiber`` reads the flow
#:   field; ``config`` validates fiber and flow settings);
#: * plots: figures from what the analysis, the config and the settings hand them
#:   ("plots never read files"); below the sweep, so a plot cannot reach the store,
#:   and below the discrepancy report, which draws its figures in the plots' style;
#: * sweep, then ``results`` (``fibersweep.load`` reads a sweep's folder through
#:   the store), then ``discrepancy`` (its batches run on the sweep's executors and
#:   worker), then ``cli``, the top.
LAYERS: tuple[tuple[str, ...], ...] = (
    (
        "fibersweep",
        "fibersweep._version",
        "fibersweep.errors",
        "fibersweep.atomic",
        "fibersweep.numba_cache",
        "fibersweep.progressbar",
        "fibersweep.examples",
    ),
    ("fibersweep.geometry",),
    ("fibersweep.units",),
    ("fibersweep.analysis",),
    ("fibersweep.flow",),
    ("fibersweep.fiber",),
    ("fibersweep.config",),
    ("fibersweep.plots",),
    ("fibersweep.sweep",),
    ("fibersweep.results",),
    ("fibersweep.discrepancy",),
    ("fibersweep.cli", "fibersweep.__main__"),
)

#: Arrows that run up the layers on purpose, each with the reason the
#: architecture gives. They are left out of both checks (circles and layers).
#: ``fibersweep.load`` is the documented convenience: the top package's
#: function-local import of the results reader, run only when a user calls it.
ALLOWED_UPWARD: Mapping[tuple[str, str], str] = {
    ("fibersweep", "fibersweep.results"): "fibersweep.load, the documented convenience",
}


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


def layer_of(module: str, layers: tuple[tuple[str, ...], ...] = LAYERS) -> int | None:
    """Index of the module's layer (longest matching name), None if no layer names it.

    A name matches itself and the modules below it; the top package's name (no
    dot) only itself, so that a new top-level module has no layer until one is
    given to it.
    """
    best: tuple[int, int] | None = None
    for i, names in enumerate(layers):
        for n in names:
            if module == n or ("." in n and module.startswith(n + ".")):
                if best is None or len(n) > best[0]:
                    best = (len(n), i)
    return None if best is None else best[1]


def circle_report(edges: list[Arrow], root: Path) -> str:
    """Each circle: its modules and the import lines that close it."""
    blocks = []
    for component in circles(edges):
        members = set(component)
        inside = sorted(
            (e for e in edges if e.source in members and e.target in members),
            key=lambda e: (e.source, e.line),
        )
        shown = "\n".join(f"    {e.show(root)}" for e in inside)
        head = f"circle of {len(component)} modules" if len(component) > 1 else "self-import"
        blocks.append(f"  {head}: {', '.join(component)}\n{shown}")
    return "\n".join(blocks)


def upward(edges: list[Arrow], layers: tuple[tuple[str, ...], ...] = LAYERS) -> list[Arrow]:
    """Arrows from a module to a module of a higher layer."""
    out = []
    for e in edges:
        a, b = layer_of(e.source, layers), layer_of(e.target, layers)
        if a is not None and b is not None and b > a:
            out.append(e)
    return out


def _package_edges(root: Path) -> tuple[dict[str, Path], list[Arrow]]:
    modules = discover(root)
    edges = [e for e in arrows(modules) if (e.source, e.target) not in ALLOWED_UPWARD]
    return modules, edges


ROOT = Path(fibersweep.__file__).resolve().parent


# --------------------------------------------------------------------------- self-checks


def _write(root: Path, files: Mapping[str, str]) -> Path:
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text, encoding="utf-8")
    return root / "pkg"


def test_a_circle_closed_inside_a_function_is_caught(tmp_path):
    """The check cannot pass vacuously: a synthetic package's circles are all found."""
    root = _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/low/__init__.py": "",
            # a <-> b, closed by a function-local relative import
            "pkg/low/a.py": "from pkg.low.b import B\n",
            "pkg/low/b.py": "B = 1\n\ndef f():\n    from .a import x\n    return x\n",
            # c -> d -> e -> c, the last one under TYPE_CHECKING
            "pkg/low/c.py": "from . import d\n",
            "pkg/low/d.py": "import pkg.low.e\n",
            "pkg/low/e.py": (
                "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                "    from pkg.low.c import C\n"
            ),
            "pkg/low/selfish.py": "def g():\n    from pkg.low import selfish\n",
            "pkg/low/fine.py": "import os\nfrom pkg.low import a\n",
        },
    )
    modules = discover(root)
    assert set(modules) == {
        "pkg", "pkg.low", "pkg.low.a", "pkg.low.b", "pkg.low.c", "pkg.low.d", "pkg.low.e",
        "pkg.low.selfish", "pkg.low.fine",
    }  # fmt: skip
    edges = arrows(modules)
    assert circles(edges) == [
        ["pkg.low.a", "pkg.low.b"],
        ["pkg.low.c", "pkg.low.d", "pkg.low.e"],
        ["pkg.low.selfish"],
    ]
    text = circle_report(edges, root)
    assert "pkg/low/b.py:4: from .a import x  [function]" in text
    assert "pkg/low/e.py:3: from pkg.low.c import C  [type-checking]" in text


def test_an_arrow_up_the_layers_is_caught(tmp_path):
    root = _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/base.py": "",
            "pkg/top/__init__.py": "",
            "pkg/top/cmd.py": "from pkg.base import x\n",
            "pkg/base_helpers.py": "def f():\n    from pkg.top import cmd\n",
        },
    )
    layers = (("pkg", "pkg.base", "pkg.base_helpers"), ("pkg.top",))
    up = upward(arrows(discover(root)), layers)
    assert [(e.source, e.target, e.line) for e in up] == [("pkg.base_helpers", "pkg.top.cmd", 2)]
    assert layer_of("pkg.top.cmd", layers) == 1 and layer_of("pkg.base", layers) == 0
    assert layer_of("pkg.unplaced", layers) is None  # the top package names only itself


def test_the_package_graph_is_seen():
    """The walk finds the package and its known arrows (a broken walk would find none)."""
    modules, edges = _package_edges(ROOT)
    assert len(modules) > 100
    seen = {(e.source, e.target) for e in edges}
    assert ("fibersweep.sweep.runner", "fibersweep.sweep.refine") in seen
    assert ("fibersweep.flow.cell", "fibersweep.flow.lattice") in seen
    # every module has a layer, so no module escapes the layer check
    assert [m for m in modules if layer_of(m) is None] == []
    # each allowed arrow is still there (an exception for nothing is removed)
    every = {(e.source, e.target) for e in arrows(modules)}
    assert [a for a in ALLOWED_UPWARD if a not in every] == []


# --------------------------------------------------------------------------- the package


def test_no_import_circles():
    _, edges = _package_edges(ROOT)
    found = circle_report(edges, ROOT)
    if found:
        pytest.fail(
            "import circles (a module that needs another that needs it: put the shared "
            "piece where both can import it):\n" + found,
            pytrace=False,
        )


def test_no_arrow_runs_up_the_layers():
    _, edges = _package_edges(ROOT)
    up = upward(edges)
    if up:
        names = [", ".join(n.removeprefix("fibersweep.") or "fibersweep" for n in layer)
                 for layer in LAYERS]  # fmt: skip
        lines = "\n".join(
            f"  {e.source} (layer {layer_of(e.source)}) -> {e.target} (layer "
            f"{layer_of(e.target)}): {e.show(ROOT)}"
            for e in sorted(up, key=lambda e: (e.source, e.line))
        )
        pytest.fail(
            "imports up the layers (layers, lowest first: "
            + " < ".join(f"{i}: {n}" for i, n in enumerate(names))
            + "):\n"
            + lines,
            pytrace=False,
        )
