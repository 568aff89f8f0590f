"""Example configs shipped with the package (``fibersweep init`` writes them).

* ``starter.yaml``: a commented starter (written as ``fibersweep.yaml``);
* ``quick.yaml``: a coarse grid and a small sweep across the separatrix;
* ``paper.yaml``: the source's 1323-run study at its resolution;
* ``friction_axis.yaml``: settings as sweep axes (friction x pillar surface);
* ``refine.yaml``: adaptive refinement of the class boundaries;
* ``shapes.yaml``: the pillar shape as a sweep axis (triangle vs circle);
* ``array.yaml``: rigid fibers through a tilted pillar array (``sort-report``);
* ``array-flexible.yaml``: flexible fibers of three stiffnesses through the same array.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from fibersweep.atomic import atomic_write
from fibersweep.errors import InputError

__all__ = ["EXAMPLES", "example_text", "write_examples"]

#: Shipped example -> name it is written under.
EXAMPLES = {
    "starter.yaml": "fibersweep.yaml",
    "quick.yaml": "quick.yaml",
    "paper.yaml": "paper.yaml",
    "friction_axis.yaml": "friction_axis.yaml",
    "refine.yaml": "refine.yaml",
    "shapes.yaml": "shapes.yaml",
    "array.yaml": "array.yaml",
    "array-flexible.yaml": "array-flexible.yaml",
}


def example_text(name: str) -> str:
    """Text of a shipped example config (a key of :data:`EXAMPLES`)."""
    if name not in EXAMPLES:
        raise InputError(f"unknown example {name!r}; valid: {', '.join(EXAMPLES)}")
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def write_examples(directory: str | Path, *, force: bool = False) -> list[Path]:
    """Write every example into ``directory``; returns the paths, starter first.

    Raises
    ------
    InputError
        A file exists and ``force`` is not set (nothing is written then).
    """
    out = Path(directory)
    targets = {name: out / dest for name, dest in EXAMPLES.items()}
    existing = [str(p) for p in targets.values() if p.exists()]
    if existing and not force:
        raise InputError(f"{', '.join(existing)} exist(s); use --force to overwrite")
    return [atomic_write(p, example_text(name)) for name, p in targets.items()]
