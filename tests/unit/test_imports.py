"""The package's import graph: no circles, and no arrow back up the layers.

The graph is read by ``scripts/tools/import_graph.py`` (every import statement that
names a module of the package is an arrow: at module level, inside a function, or
under ``if TYPE_CHECKING:``; a circle closed by a function-local or type-checking
import is still a circle). Nothing is whitelisted.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path

import pytest

import fibersweep

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts" / "tools"))
from import_graph import Arrow, arrows, circles, discover, levels  # noqa: E402

#: The layers of docs/architecture.md ("Layers and who imports whom"), lowest
#: first. A module belongs to the layer of the longest name below that matches it;
#: it may import its own layer and the layers below, never one above.
#: * base: what every layer may use: the package's version (``version``, and
#:   ``_version``, which a build writes), exception types, the atomic writer, the
#:   stale-kernel-cache guard, the progress bars, the shipped example configs;
#: * geometry < units < analysis < config: shapes, scales, pure analysis of
#:   trajectories, and the config schema (which imports no simulation: the physics
#:   checks are handed in by the sweep);
#: * flow < fiber: the solver reads its settings; the fiber reads the flow field;
#: * sorting: pure analysis of array results (tables in, tables out);
#: * plots: figures from what the analysis and the settings hand them ("plots
#:   never read files"); below the sweep, so a plot cannot reach the store;
#: * sweep (orchestration), then ``results`` (a results folder read back), then
#:   ``discrepancy`` (its batches run on the sweep's executors and worker), then
#:   ``api`` (the public functions), ``cli`` (a thin layer over them), ``docgen``
#:   and the top package, whose attributes are the API's functions.
LAYERS: tuple[tuple[str, ...], ...] = (
    (
        "fibersweep.version",
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
    ("fibersweep.config",),
    ("fibersweep.flow",),
    ("fibersweep.fiber",),
    ("fibersweep.resolved",),
    ("fibersweep.sorting",),
    ("fibersweep.plots",),
    ("fibersweep.sweep",),
    ("fibersweep.results",),
    ("fibersweep.discrepancy",),
    ("fibersweep.api",),
    ("fibersweep.cli", "fibersweep.__main__"),
    # the reference pages read the command line, the config schema and the columns
    ("fibersweep.docgen",),
    ("fibersweep",),
)


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
    return modules, arrows(modules)


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
    assert levels(edges, modules) > 5


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
