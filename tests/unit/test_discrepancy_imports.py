"""The discrepancy package's modules import each other without a circle.

Every import of one module of ``fibersweep.discrepancy`` by another is read from
the source (top-level and inside functions alike), and the graph must be acyclic:
a circle closed by a function-local import would pass an import test but still
tie two modules' responsibilities together. Internal imports are also required
to sit at the top of a module, where a reader sees them.
"""

from __future__ import annotations

import ast
from pathlib import Path

import fibersweep.discrepancy as pkg

ROOT = Path(pkg.__file__).parent
PREFIX = "fibersweep.discrepancy."


def _imports(path: Path) -> tuple[set[str], set[str]]:
    """Internal modules imported by ``path``: (at the top level, inside a function)."""
    tree = ast.parse(path.read_text())
    top = {n for n in tree.body if isinstance(n, ast.ImportFrom | ast.Import)}
    found: tuple[set[str], set[str]] = (set(), set())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module, *(f"{node.module}.{a.name}" for a in node.names)]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        for name in names:
            if name.startswith(PREFIX) and (ROOT / f"{name[len(PREFIX):]}.py").exists():
                found[0 if node in top else 1].add(name[len(PREFIX) :])
    return found


def _graph() -> dict[str, tuple[set[str], set[str]]]:
    return {p.stem: _imports(p) for p in sorted(ROOT.glob("*.py")) if p.stem != "__init__"}


def test_no_import_circle_inside_the_package():
    graph = {m: top | local for m, (top, local) in _graph().items()}
    state: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        for d in sorted(graph[m]):
            assert state.get(d) != 1, f"import circle: {' -> '.join([*path, d])}"
            if d not in state:
                visit(d, [*path, d])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [m])


def test_internal_imports_are_at_the_top_of_each_module():
    local = {m: sorted(loc) for m, (_, loc) in _graph().items() if loc}
    assert not local, f"function-local imports of discrepancy modules: {local}"


#: The report's modules: they format and write what the workflow computed.
REPORT = ("report", "report_text", "report_followup", "report_format", "report_figures", "advice")
#: Modules that run the workflow, simulate, or compute tests and counts.
COMPUTING = (
    "workflow", "stages", "followup", "next_measure", "power", "settle", "discriminant",
    "dispersion", "scores", "decide", "fit", "pairs", "signatures", "simulate", "copies",
)  # fmt: skip


def test_the_report_imports_nothing_that_computes():
    """The report receives every test and count in the workflow's result (:mod:`.result`):
    none of its modules imports the workflow or a module that computes a test."""
    graph = _graph()
    found = {m: sorted(d for d in graph[m][0] | graph[m][1] if d in COMPUTING) for m in REPORT}
    assert {m: d for m, d in found.items() if d} == {}
