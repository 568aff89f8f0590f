"""Provenance of a sweep: manifest.json and the compact copy kept in Parquet metadata."""

from __future__ import annotations

import json
import logging
import platform
import subprocess
import sys
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from fibersweep.atomic import atomic_write
from fibersweep.errors import UnreadableResults

__all__ = [
    "MANIFEST",
    "build_revision",
    "git_revision",
    "library_versions",
    "provenance",
    "read_manifest",
    "write_manifest",
]

log = logging.getLogger(__name__)

MANIFEST = "manifest.json"
_LIBS = ("numpy", "scipy", "numba", "pandas", "pyarrow", "pydantic", "matplotlib", "distributed")


def library_versions() -> dict[str, str]:
    """Versions of Python and the libraries that can change results or files."""
    out = {"python": platform.python_version()}
    for name in _LIBS:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            continue
    return out


def _git(src: Path, *args: str) -> str:
    """Output of ``git -C SRC ARGS`` (stripped); raises on failure."""
    return subprocess.run(
        ["git", "-C", str(src), *args], capture_output=True, text=True, timeout=5, check=True
    ).stdout.strip()


def git_revision(src: Path | None = None) -> str | None:
    """Commit of fibersweep's own source checkout (``+dirty`` if modified), or None.

    Only when fibersweep runs from its own git checkout (an editable install):
    ``src`` (default: the folder above the package) must be the top of a git
    work tree whose ``pyproject.toml`` names the ``fibersweep`` project. An
    installed copy inside a user's repository (a virtual environment in a
    project folder) must not record the user's commit; the package version
    identifies it instead.
    """
    src = (src or Path(__file__).resolve().parents[2]).resolve()
    try:
        if 'name = "fibersweep"' not in (src / "pyproject.toml").read_text():
            return None
        top = _git(src, "rev-parse", "--show-toplevel")
        if Path(top).resolve() != src:
            return None
        rev = _git(src, "rev-parse", "HEAD")
        dirty = _git(src, "status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError, UnicodeDecodeError):
        return None
    return rev + ("+dirty" if dirty else "") if rev else None


def build_revision() -> str | None:
    """Commit an installed copy was built from (``+dirty`` if its tree was modified), or None.

    setuptools-scm writes ``fibersweep/_version.py`` when the package is built
    (``pip install``, editable or not): the version derived from git and the
    commit (``__commit_id__``, ``g`` + short hash). A modified tree shows in the
    version's local part as a date (``+gHASH.dYYYYMMDD``). A source tree that was
    never built has no such file.
    """
    try:
        from fibersweep import _version  # type: ignore[attr-defined]
    except ImportError:
        return None
    node = getattr(_version, "__commit_id__", None)
    if not node:
        return None
    rev = node[1:] if node.startswith("g") else node
    local = str(getattr(_version, "__version__", "")).partition("+")[2]
    dirty = any(p[:1] == "d" and p[1:].isdigit() for p in local.split("."))
    return rev + ("+dirty" if dirty else "")


def revision() -> tuple[str | None, str | None]:
    """fibersweep's own revision and where it comes from: ``checkout`` or ``build``.

    A git checkout of fibersweep (an editable install) knows its current commit;
    an installed copy knows the commit it was built from; else ``(None, None)``.
    """
    rev = git_revision()
    if rev is not None:
        return rev, "checkout"
    rev = build_revision()
    return (rev, "build") if rev is not None else (None, None)


def provenance(flow_key: str) -> dict[str, Any]:
    """Package version, git revision, flow-field hash, library versions, host and time."""
    from fibersweep.version import __version__

    rev, source = revision()
    return {
        "fibersweep": __version__,
        "git": rev,
        "git_from": source,
        "flow_key": flow_key,
        "libraries": library_versions(),
        "host": platform.node(),
        "argv": sys.argv,
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


def read_manifest(out: Path) -> dict[str, Any] | None:
    """The manifest of an output directory, or None if there is none.

    Raises
    ------
    UnreadableResults
        The file exists but is not a readable JSON object (cut short, not JSON):
        named once, exit code 2 at the command line.
    """
    p = Path(out) / MANIFEST
    if not p.exists():
        return None
    try:
        man = json.loads(p.read_text())
    except (OSError, ValueError) as exc:  # cut short, not JSON, unreadable
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise UnreadableResults(
            f"{p}: unreadable manifest ({why}); the runs and trajectories are kept in their "
            "parts, but the settings that made them are lost with it: move it aside and run "
            "the sweep's config with --no-resume, or restore it"
        ) from None
    if not isinstance(man, dict):
        raise UnreadableResults(f"{p}: unreadable manifest (not a JSON object)")
    return man


def write_manifest(out: Path, manifest: dict[str, Any]) -> Path:
    """Write manifest.json atomically."""
    text = json.dumps(manifest, indent=2, sort_keys=True, default=str) + "\n"
    return atomic_write(Path(out) / MANIFEST, text)
